#!/bin/bash
# On the device (carry .data: site.txz, the tabs in .data/official; models/policies holding only left_general and
# right_mixed): GSync of left_general + right_mixed on one song for --max-minutes 5 (compilation included), with the
# hold reward; eval, metrics, log and the synchronizer into $OUT. Usage: bash gsync5.sh SONG [SEED]
set -e
tar xJf .data/site.txz -C /tmp && rm -rf /tmp/site && mv /tmp/slim /tmp/site
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 DEXGUITAR_CACHE=/tmp/xla DEXGUITAR_PLANS=/tmp/plans
S=$1; SEED=${2:-1}
t=$SECONDS
python3 -c "import sys; from dexguitar.cli import main; sys.exit(main())" sync --song .data/official/$S.json \
  --config sync_hold --max-minutes 5 --seed $SEED --out /tmp/runs/$S 2>&1 | tee $OUT/$S.log | grep -v "it/s" | tail -5
echo "command seconds: $((SECONDS - t))" | tee -a $OUT/$S.log
cp /tmp/runs/$S/eval.json $OUT/$S.eval.json; cp /tmp/runs/$S/metrics.jsonl $OUT/$S.metrics.jsonl
tar czf $OUT/$S.policy.tgz -C /tmp/runs/$S policy config.json
