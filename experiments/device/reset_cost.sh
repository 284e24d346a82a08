#!/bin/bash
# On the device (carry .data; models/policies holding only left_general and right_mixed): what the auto-reset's MJX
# kinematics inside every step costs (issue 10): experiments/compile_split.py with the real reset and with
# RESET_STUB=1, each in a fresh process with an empty compilation cache, RUNS (default 3) timed chunk calls each.
set -e
[ -d /tmp/site/mujoco ] || { tar xJf .data/site.txz -C /tmp && rm -rf /tmp/site && mv /tmp/slim /tmp/site; }
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 DEXGUITAR_PLANS=/tmp/plans XLA_FLAGS=--xla_gpu_enable_triton_gemm=false
nvidia-smi --query-gpu=name --format=csv,noheader | tee $OUT/gpu.txt
for stub in "" 1 ${REPEAT:+"" 1}; do
  RESET_STUB=$stub DEXGUITAR_CACHE=$(mktemp -d) timeout ${LIMIT:-260} python3 experiments/compile_split.py \
    .data/official/spring_overture.json 0 "${RUNS:-3}" 2>> $OUT/log.txt | tail -1 | tee -a $OUT/reset.jsonl
done
