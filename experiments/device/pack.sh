#!/usr/bin/env bash
# Wait until N songs of gsync.sh's log have ended (or T seconds), then pack its runs, without checkpoints, into
# $OUT/gs.tgz: a machine goes back with its files 30 s after the last call, so each call brings back what has ended.
#   N=2 T=560 bash .data/pack.sh
t=0
while [ $t -lt ${T:-500} ] && [ $(cat /tmp/runs/gsync.log 2>/dev/null | grep -c " rc=") -lt ${N:-1} ]; do
  sleep 5; t=$((t+5))
done
cat /tmp/runs/gsync.log; grep -h "synchronization\]" /tmp/runs/gsync/*.log | cut -c1-250
cd /tmp/runs && tar czf $OUT/gs.tgz --exclude=ckpt --exclude=resume --exclude='*.lock' gsync gsync.log
ls -la $OUT
