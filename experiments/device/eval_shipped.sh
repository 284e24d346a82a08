#!/bin/bash
# On the device (carry .data: site.txz, the tabs in .data/official; models/policies holding left_general,
# right_general, right_mixed and the synchronizers to judge): the planner pair on the 15 official songs, then each
# synchronizer models/policies/gsync*_SONG on its song (before and after); F1 JSON and seconds into $OUT (the
# synchronizers' JSON in one archive, gsync_evals.tgz: a call brings back 8 files at most).
# Usage: bash eval_shipped.sh
set -e
tar xJf .data/site.txz -C /tmp && rm -rf /tmp/site && mv /tmp/slim /tmp/site
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 DEXGUITAR_CACHE=/tmp/xla DEXGUITAR_PLANS=/tmp/plans
nvidia-smi --query-gpu=name --format=csv,noheader | tee $OUT/gpu.txt
mkdir -p /tmp/evals
D() { python3 -c "import sys; from dexguitar.cli import main; sys.exit(main())" "$@"; }
t=$SECONDS; D eval --left models/policies/left_general --right models/policies/right_general \
  --song .data/official/*.json --json > $OUT/pair_official.h100.json 2>> $OUT/log.txt
echo "pair: $((SECONDS - t)) s" | tee -a $OUT/times.txt
for d in models/policies/gsync*_*; do
  name=$(basename $d); song=${name#*_}
  t=$SECONDS; D eval --ckpt $d --song .data/official/$song.json --json > /tmp/evals/$name.h100.json 2>> $OUT/log.txt
  echo "$name: $((SECONDS - t)) s" | tee -a $OUT/times.txt
done
tar czf $OUT/gsync_evals.tgz -C /tmp/evals .
