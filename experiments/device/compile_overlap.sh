#!/bin/bash
# On the device (carry .data; models/policies holding left_general and right_mixed): experiments/compile_overlap.py in
# fresh processes: seq and overlap with empty caches (SKIP=1 leaves them out), then save (with XLA's stage timers in
# log.txt), load and seq over one cache. Results: results/general_left/session26/compile_overlap/.
set -e
[ -d /tmp/site/mujoco ] || { tar xJf .data/site.txz -C /tmp && rm -rf /tmp/site && mv /tmp/slim /tmp/site; }
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 DEXGUITAR_PLANS=/tmp/plans
nvidia-smi --query-gpu=name --format=csv,noheader | tee $OUT/gpu.txt
python3 -c "import jax, jaxlib; print(jax.__version__, jaxlib.__version__)" | tee -a $OUT/gpu.txt
F0="--xla_gpu_enable_triton_gemm=false"
F1="$F0"     # first --xla_gpu_enable_llvm_module_compilation_parallelism=true: unknown to JAX 0.11.2
run() { echo "== $1 $2 $3" >> $OUT/log.txt; XLA_FLAGS="$2" DEXGUITAR_CACHE=$3 timeout 220 python3 experiments/compile_overlap.py .data/official/spring_overture.json $1 2>>$OUT/log.txt | tail -1 | tee -a $OUT/overlap.jsonl; }
[ -z "$SKIP" ] && run seq "$F0" $(mktemp -d)
[ -z "$SKIP" ] && run overlap "$F0" $(mktemp -d)
C=$(mktemp -d)
TF_CPP_MIN_LOG_LEVEL=0 TF_CPP_VMODULE=gpu_compiler=1,nvptx_compiler=1 run save "$F1" $C
run load "$F1" $C
run seq "$F1" $C
