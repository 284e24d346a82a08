#!/bin/bash
# On the device (carry .data; models/policies holding left_general, and runs/ the policies to judge):
# experiments/perturbed_eval.py on 48 held-out procedural songs and the 15 official songs, DRAWS offsets each (default 4;
# the plans in .cache/plans when carried, see experiments/pack_plans.py). Usage: [DRAWS=3] bash perturbed_eval.sh POLICY...
set -e
[ -d /tmp/site ] || { tar xJf .data/site.txz -C /tmp && mv /tmp/slim /tmp/site; }
mkdir -p /tmp/plans; cp .cache/plans/*.npz /tmp/plans/ 2>/dev/null || true
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 DEXGUITAR_CACHE=/tmp/xla DEXGUITAR_PLANS=/tmp/plans
t=$SECONDS
python3 experiments/perturbed_eval.py "$@" --out $OUT/perturbed.json --procedural 48 --seed 2 \
  --song .data/official/*.json --rms 4e-5 --draws ${DRAWS:-4} 2>&1 | tee $OUT/perturbed.log | grep -v "it/s"
echo "command seconds: $((SECONDS - t))" | tee -a $OUT/perturbed.log
