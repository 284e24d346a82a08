#!/usr/bin/env bash
# GSync on a rented GPU machine: one synchronizer per song on the general pair (left_general + right_mixed).
# Started by start.sh with the tabs carried in .data/official (copied to /tmp first: a later call without the carry
# would remove them under a running loop):
#   RUN=gsync SONGS="wipe_out super_mario" MIN=2.5 CMD='bash $REPO/experiments/device/gsync.sh' WAIT=540 bash .data/start.sh
# Several GPUs: groups of songs separated by '|' run side by side, group i on GPU i, each group's songs in turn:
#   SONGS="canon_in_d_major1 snow | super_mario dont_cry"
# A song may name its seed, song:seed (two seeds of one song side by side: "snow:1 | snow:2"); its run is then
# <song>_s<seed>. Songs of the same plan capacity (a power of two of frames, feedforward.MIN_FRAMES) share one
# compiled program: order each group by length. Each song's run is /tmp/runs/gsync/<song>, its log
# /tmp/runs/gsync/<song>.log; the last line of this script's output is "gsync done".
mkdir -p /tmp/official /tmp/runs/gsync /tmp/plans && cp "$REPO"/.data/official/*.json /tmp/official/
export DEXGUITAR_PLANS=/tmp/plans
# Plans made beforehand on a CPU (DEXGUITAR_PLANS=$PWD/.data/plans there) skip the planning here.
ls "$REPO"/.data/plans/*.npz > /dev/null 2>&1 && cp "$REPO"/.data/plans/*.npz /tmp/plans/
group() {
  for job in $1; do
    s=${job%%:*}; n=$s; seed=()
    [ "$job" != "$s" ] && { n=${s}_s${job#*:}; seed=(--seed "${job#*:}"); }
    # A song already started (here or by another group) is left alone: its run and log stay as they are.
    [ -e /tmp/runs/gsync/$n ] && { echo "$n skipped: /tmp/runs/gsync/$n exists"; continue; }
    t0=$(date +%s)
    dexguitar sync --song /tmp/official/$s.json --out /tmp/runs/gsync/$n --config sync_hold \
      --max-minutes "${MIN:-2.5}" "${seed[@]}" > /tmp/runs/gsync/$n.log 2>&1
    echo "$n rc=$? seconds=$(( $(date +%s) - t0 )) gpu=${CUDA_VISIBLE_DEVICES:-all}"
  done
}
IFS='|' read -ra groups <<< "$SONGS"
if [ ${#groups[@]} -eq 1 ]; then group "${groups[0]}"
else
  for i in "${!groups[@]}"; do CUDA_VISIBLE_DEVICES=$i group "${groups[$i]}" & done
  wait
fi
echo "gsync done"
