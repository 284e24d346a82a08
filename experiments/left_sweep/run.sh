#!/usr/bin/env bash
# The sweep's runs: the variants named as arguments ($DIR/NAME.py, DIR defaults to experiments/left_sweep) side by
# side on one GPU, each training the left hand for $MINUTES (compilation included). With $SONG: on that song, then
# evaluated on the whole song; NAME@STEM trains on $(dirname $SONG)/STEM.json instead. Without $SONG: on the general
# procedural material (--style general), evaluated later on songs it never saw (experiments/general_left.py).
# $INIT: every variant starts from that policy (--init-from). Runs go to $RUNS/NAME (default runs/sweep).
#   SONG=../shared/data/official/notes/turkish_march.json MINUTES=6.8 experiments/left_sweep/run.sh clip3 clip4 clip5 kl01
#   DIR=experiments/left_general_sweep INIT=runs/left-general/policy MINUTES=20 experiments/left_sweep/run.sh base clip3
set -u
DIR=${DIR:-experiments/left_sweep}; RUNS=${RUNS:-runs/sweep}; INIT=${INIT:-}; SONG=${SONG:-}
mkdir -p "$RUNS"
export XLA_PYTHON_CLIENT_MEM_FRACTION=${FRAC:-$(python3 -c "print(round(0.9 / $#, 2))")}
for v in "$@"; do
  c=${v%@*}; s=$SONG; [ -n "$SONG" ] && [ "$c" != "$v" ] && s=$(dirname "$SONG")/${v#*@}.json
  material=(--style general); [ -n "$s" ] && material=(--song "$s")
  init=(); [ -n "$INIT" ] && init=(--init-from "$INIT")
  ( dexguitar train --hand left "${material[@]}" "${init[@]}" --config "$DIR/$c.py" --out "$RUNS/$v" \
      --max-minutes "$MINUTES" > "$RUNS/$v.log" 2>&1
    [ -n "$s" ] && dexguitar eval --ckpt "$RUNS/$v" --song "$s" --json > "$RUNS/$v/eval.json" 2>> "$RUNS/$v.log" ) &
done
wait
