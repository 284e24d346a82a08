#!/bin/bash
# On the device (carry .data; models/policies holding only left_general and right_mixed): XLA's compile of the GSync
# chunk, pass by pass (issue 10): experiments/compile_split.py in a fresh process with an empty compilation cache and
# XLA's pass timers logged, then experiments/xla_passes.py on the log. Each argument is one XLA_FLAGS set (added to
# the commands' default --xla_gpu_enable_triton_gemm=false), "" for none; RUNS (default 2) timed chunk calls each.
set -e
[ -d /tmp/site/mujoco ] || { tar xJf .data/site.txz -C /tmp && rm -rf /tmp/site && mv /tmp/slim /tmp/site; }
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 DEXGUITAR_PLANS=/tmp/plans
nvidia-smi --query-gpu=name --format=csv,noheader | tee $OUT/gpu.txt
i=0
for flags in "$@"; do
  i=$((i+1))
  log=/tmp/passes$i.log
  XLA_FLAGS="--xla_gpu_enable_triton_gemm=false $flags" DEXGUITAR_CACHE=$(mktemp -d) TF_CPP_MIN_LOG_LEVEL=0 \
    TF_CPP_VMODULE=hlo_pass_pipeline=1,gpu_compiler=1 timeout ${LIMIT:-300} python3 experiments/compile_split.py \
    .data/official/spring_overture.json 0 "${RUNS:-2}" 2> $log | tail -1 | tee -a $OUT/flags.jsonl
  { echo "== $flags"; grep -E "RunHloPasses|RunBackend" $log | grep -v "#called: 0"; \
    python3 experiments/xla_passes.py $log jit_chunk 60; python3 experiments/xla_passes.py $log jit_initial_state 15; } \
    >> $OUT/passes.txt
  [ $i -eq 1 ] && gzip -c $log > $OUT/passes1.log.gz
done
