#!/bin/bash
# On the device (carry .data with site.txz and the official tabs in .data/official; models/policies holding only
# left_general and right_mixed): experiments/compile_split.py once per XLA flag set (each argument one set, "" for
# none), each in a fresh process with an empty compilation cache, timing RUNS (default 2) calls of the compiled chunk too
# (issue 10: a first run within 30 s). E.g.
#   bash experiments/device/compile_flags.sh "" --xla_gpu_autotune_level=0 --xla_gpu_enable_triton_gemm=false
set -e
[ -d /tmp/site/mujoco ] || { tar xJf .data/site.txz -C /tmp && rm -rf /tmp/site && mv /tmp/slim /tmp/site; }
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 DEXGUITAR_PLANS=/tmp/plans
nvidia-smi --query-gpu=name --format=csv,noheader | tee $OUT/gpu.txt
for flags in "$@"; do
  cache=${CACHE:-$(mktemp -d)}            # CACHE=dir: one cache for every set (a later run loads)
  XLA_FLAGS="$flags" DEXGUITAR_CACHE=$cache timeout ${LIMIT:-400} python3 experiments/compile_split.py .data/official/spring_overture.json 0 "${RUNS:-2}" \
    2>> $OUT/log.txt | tail -1 | tee -a $OUT/flags.jsonl
done
