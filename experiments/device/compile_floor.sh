#!/bin/bash
# On the device (carry .data; models/policies holding only left_general and right_mixed): experiments/compile_floor.py
# on spring_overture, one process, no compilation cache (issue 10: the physics' share of a first run's compile).
set -e
[ -d /tmp/site/mujoco ] || { tar xJf .data/site.txz -C /tmp && rm -rf /tmp/site && mv /tmp/slim /tmp/site; }
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 DEXGUITAR_PLANS=/tmp/plans
nvidia-smi --query-gpu=name --format=csv,noheader | tee $OUT/gpu.txt
XLA_FLAGS="--xla_gpu_enable_triton_gemm=false" python3 experiments/compile_floor.py .data/official/spring_overture.json \
  2> $OUT/floor.log | tee -a $OUT/floor.jsonl
