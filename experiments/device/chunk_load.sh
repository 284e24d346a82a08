#!/bin/bash
# On the device (carry .data; models/policies holding left_general and right_mixed): where a later run's 10 s to a
# ready chunk go (issue 10). A first `dexguitar sync` call keeps its chunk; a later one loads it with XLA's compiler
# stages logged; then experiments/chunk_load.py times the file's load alone in a fresh process, twice.
[ -d /tmp/site/mujoco ] || { tar xJf .data/site.txz -C /tmp && rm -rf /tmp/site && mv /tmp/slim /tmp/site; }
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 DEXGUITAR_CACHE=/tmp/xla DEXGUITAR_PLANS=/tmp/plans
nvidia-smi --query-gpu=name --format=csv,noheader | tee $OUT/gpu.txt
D() { python3 -c "import sys; from dexguitar.cli import main; sys.exit(main())" "$@"; }
S=${SONG:-.data/official/spring_overture.json}
sync1() {
  t=$SECONDS
  D sync --song $S --left models/policies/left_general --right models/policies/right_mixed \
    --config experiments/sync_hold.py --out /tmp/runs/$1 --stop-after-calls 1 --no-eval > $OUT/$1.log 2>&1
  echo "$1: rc $? $((SECONDS - t)) s; $(grep -E 'training chunk' $OUT/$1.log | cut -c1-160)" | tee -a $OUT/times.txt
}
ls /tmp/xla/chunks/*.exe > /dev/null 2>&1 || sync1 first
TF_CPP_MIN_LOG_LEVEL=0 TF_CPP_VMODULE=gpu_compiler=1,nvptx_compiler=1 sync1 later
grep -E "RunHloPasses|RunBackend|ptx|Deserializ" $OUT/later.log | head -20 | tee -a $OUT/times.txt
for i in 1 2; do python3 experiments/chunk_load.py /tmp/xla | tee -a $OUT/load.jsonl; done
