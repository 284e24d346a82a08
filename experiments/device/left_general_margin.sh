#!/bin/bash
# On the device (carry .data and .cache/plans, the plans of the 128 training songs, the 48 held-out songs and the
# official ones, made on a CPU and packed by experiments/pack_plans.py): the margin-paid general left hand
# (experiments/left_general_margin.py) for MIN minutes on 128 procedural songs, resuming the run a warm machine still
# holds in /tmp/runs; then its exported policy played as it is and with DRAWS offsets (experiments/perturbed_eval.py)
# on the 48 held-out procedural songs (seed 2) and the 15 official ones.
# Usage: bash left_general_margin.sh MIN [DRAWS]   (MIN 0: no training; no DRAWS: no evaluation; MIN 7.5 took 474 s
# of a fresh machine, DRAWS 2 130 s). CONFIG=experiments/left_general_margin_free.py: the same without the prior.
set -e
[ -d /tmp/site ] || { tar xJf .data/site.txz -C /tmp && mv /tmp/slim /tmp/site; }
mkdir -p /tmp/plans; cp .cache/plans/*.npz /tmp/plans/ 2>/dev/null || true
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 DEXGUITAR_CACHE=/tmp/xla DEXGUITAR_PLANS=/tmp/plans
CONFIG=${CONFIG:-experiments/left_general_margin.py}
RUN=/tmp/runs/$(basename $CONFIG .py)
t=$SECONDS
if [ "$1" != 0 ]; then
python3 -c "import sys; from dexguitar.cli import main; sys.exit(main())" train --hand left --style general \
  --procedural 128 --config $CONFIG --out $RUN --max-minutes $1 \
  $([ -d $RUN ] && echo --resume) 2>&1 | tee -a $OUT/train.log | grep -v "it/s" | tail -8
echo "train seconds: $((SECONDS - t))" | tee -a $OUT/train.log
cp $RUN/metrics.jsonl $RUN/config.json $OUT/
tar czf $OUT/policy.tgz -C $RUN policy
fi
[ -n "$2" ] || exit 0
python3 experiments/perturbed_eval.py $RUN/policy --out $OUT/perturbed.json --procedural 48 --seed 2 \
  --song .data/official/*.json --rms 4e-5 --draws $2 2>&1 | tee $OUT/perturbed.log | grep -v "it/s"
echo "command seconds: $((SECONDS - t))" | tee -a $OUT/perturbed.log
