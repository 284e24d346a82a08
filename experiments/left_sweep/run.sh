#!/usr/bin/env bash
# The sweep's runs: the variants named as arguments (experiments/left_sweep/NAME.py) side by side on one GPU, each
# training the left hand on $SONG for $MINUTES (compilation included), then evaluated on the whole song.
#   SONG=../shared/data/official/notes/turkish_march.json MINUTES=6.8 experiments/left_sweep/run.sh clip3 clip4 clip5 kl01
# NAME@STEM trains on $(dirname $SONG)/STEM.json instead. Runs go to runs/sweep/NAME (metrics.jsonl, eval.json).
set -u
mkdir -p runs/sweep
export XLA_PYTHON_CLIENT_MEM_FRACTION=${FRAC:-$(python3 -c "print(round(0.9 / $#, 2))")}
for v in "$@"; do
  c=${v%@*}; s=$SONG; [ "$c" != "$v" ] && s=$(dirname "$SONG")/${v#*@}.json
  ( dexguitar train --hand left --song "$s" --config experiments/left_sweep/$c.py --out runs/sweep/$v \
      --max-minutes "$MINUTES" > runs/sweep/$v.log 2>&1
    dexguitar eval --ckpt runs/sweep/$v --song "$s" --json > runs/sweep/$v/eval.json 2>> runs/sweep/$v.log ) &
done
wait
