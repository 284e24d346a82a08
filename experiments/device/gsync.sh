#!/usr/bin/env bash
# GSync on a rented GPU: one synchronizer per song on the general pair (left_general + right_mixed), songs in turn.
# Started by start.sh with the tabs carried in .data/official (copied to /tmp first: a later call without the carry
# would remove them under a running loop):
#   RUN=gsync SONGS="wipe_out super_mario" MIN=2.5 CMD='bash $REPO/experiments/device/gsync.sh' WAIT=540 bash .data/start.sh
# Songs of the same plan capacity (a power of two of frames, feedforward.MIN_FRAMES) share one compiled program:
# order them by length. Each song's run is /tmp/runs/gsync/<song>, its log /tmp/runs/gsync/<song>.log.
mkdir -p /tmp/official /tmp/runs/gsync /tmp/plans && cp "$REPO"/.data/official/*.json /tmp/official/
export DEXGUITAR_PLANS=/tmp/plans
for s in $SONGS; do
  t0=$(date +%s)
  dexguitar sync --song /tmp/official/$s.json --out /tmp/runs/gsync/$s --config experiments/sync_songs.py \
    --max-minutes "${MIN:-2.5}" > /tmp/runs/gsync/$s.log 2>&1
  echo "$s rc=$? seconds=$(( $(date +%s) - t0 ))"
done
