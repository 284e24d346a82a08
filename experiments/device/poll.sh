#!/usr/bin/env bash
# Wait (WAIT seconds, default 540) while `dexguitar songs` runs, then show its log's tail and copy logs to $OUT.
# With COLLECT=1: pack each song's stage dirs (no checkpoints) and the compilation cache into $OUT.
WAIT=${WAIT:-540}; t=0
while pgrep -f "dexguitar[.]cli" >/dev/null && [ $t -lt $WAIT ]; do sleep 10; t=$((t+10)); done
pgrep -f "dexguitar[.]cli" >/dev/null && echo "RUNNING after ${t}s" || echo "DONE after ${t}s"
cd /tmp/runs
for r in *.log; do tr '\r' '\n' < $r | grep -v "^\s*$" | tail -25; cp $r $OUT/; done
for d in */; do cp -f $d/songs.json $d/songs.md $OUT/ 2>/dev/null; done
if [ "$COLLECT" = 1 ]; then
  for d in */*/; do s=$(basename $d); tar czf $OUT/$s.tgz --exclude=ckpt --exclude=resume --exclude='*.lock' --exclude=best.tmp --exclude=policy -C $(dirname $d) $s; done
  tar czf - -C /tmp xla | split -b 15M - $OUT/xla.tgz.   # the compilation cache, for the next machine
  du -sh /tmp/xla; ls -la $OUT
fi
