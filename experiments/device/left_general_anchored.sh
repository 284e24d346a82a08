#!/bin/bash
# On the device (carry .data: site.txz; models/policies may stay behind): the anchored general left hand
# (dexguitar/configs/left_general_anchored.py) for MIN minutes on 256 procedural songs, resuming /tmp/runs/anchored when
# a warm machine still has it; log, metrics and the exported policy into $OUT. Usage: bash left_general_anchored.sh MIN
# MIN counts from the compile, not from planning: a fresh machine plans the 256 songs for about 6 minutes first (then
# cached in /tmp/plans), so keep MIN at 3 there; a call with MIN 8 ran past the 10-minute limit and lost its export.
set -e
[ -d /tmp/site ] || { tar xJf .data/site.txz -C /tmp && mv /tmp/slim /tmp/site; }
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 DEXGUITAR_CACHE=/tmp/xla DEXGUITAR_PLANS=/tmp/plans
RUN=/tmp/runs/anchored
t=$SECONDS
python3 -c "import sys; from dexguitar.cli import main; sys.exit(main())" train --hand left --style general \
  --procedural 256 --config left_general_anchored --out $RUN --max-minutes $1 \
  $([ -d $RUN ] && echo --resume) 2>&1 | tee -a $OUT/train.log | grep -v "it/s" | tail -8
echo "command seconds: $((SECONDS - t))" | tee -a $OUT/train.log
cp $RUN/metrics.jsonl $RUN/config.json $OUT/
tar czf $OUT/policy.tgz -C $RUN policy
