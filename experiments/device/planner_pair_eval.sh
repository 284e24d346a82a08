#!/bin/bash
# On the device, from the repository root with only left_general and right_general in models/policies and the official
# tabs in .data/official (carry .data): right_general alone, then the planner pair twice (PAIR_RUNS; a first process compiles, a
# second loads) on the 15 official songs (SKIP_RIGHT=1: the pair only); F1 JSON and seconds into $OUT
# (results/general_left/session24/).
set -e
tar xJf .data/site.txz -C /tmp && rm -rf /tmp/site && mv /tmp/slim /tmp/site
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 DEXGUITAR_CACHE=/tmp/xla DEXGUITAR_PLANS=/tmp/plans
nvidia-smi --query-gpu=name --format=csv,noheader | tee $OUT/gpu.txt
D() { python3 -c "import sys; from dexguitar.cli import main; sys.exit(main())" "$@"; }
S=$(ls ../shared/data/official/notes/*.json 2>/dev/null || ls .data/official/*.json)
[ -n "$SKIP_RIGHT" ] || { t=$SECONDS; D eval --ckpt models/policies/right_general --song $S --json > $OUT/right_gpu_1.json 2>> $OUT/log.txt
echo "right_general run 1: $((SECONDS - t)) s" >> $OUT/times.txt; }
for run in $(seq ${PAIR_RUNS:-2}); do
  t=$SECONDS; D eval --left models/policies/left_general --right models/policies/right_general --song $S --json > $OUT/pair_gpu_$run.json 2>> $OUT/log.txt
  echo "pair run $run: $((SECONDS - t)) s" >> $OUT/times.txt
done
cat $OUT/times.txt
