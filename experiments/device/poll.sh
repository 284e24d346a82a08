#!/usr/bin/env bash
# Wait (WAIT seconds, default 540) while the commands that start.sh began run (their process groups), then show its log's tail and copy logs to $OUT.
# A `train` run (a directory with resume/) comes back at every poll without its full checkpoint, split into 15 MB
# parts (<run>.tgz.aa, .ab, ...), so that a lost machine loses little; its policy export only with COLLECT=1.
# With COLLECT=1 also: each song's stage dirs of a `songs` run (no checkpoints), each run of a sweep (a folder of
# runs under /tmp/runs: its policy, metrics and log), and the compilation cache.
WAIT=${WAIT:-540}; t=0
running() { for p in /tmp/runs/*.pid; do kill -0 -- -$(cat $p) 2>/dev/null && return 0; done; return 1; }
while running && [ $t -lt $WAIT ]; do sleep 10; t=$((t+10)); done
running && echo "RUNNING after ${t}s" || echo "DONE after ${t}s"
cd /tmp/runs
for r in *.log */*.log; do [ -f $r ] && tr '\r' '\n' < $r | grep -v "^\s*$" | tail -${TAIL:-25}; done; cp *.log $OUT/
for d in */; do d=${d%/}
  if [ -d $d/resume ]; then       # paused while packed: orbax keeps the newest finished step whole
    groups=$(sed 's/^/-/' /tmp/runs/*.pid); kill -STOP -- $groups 2>/dev/null
    tar czf - --exclude=ckpt --exclude='*.lock' $([ "$COLLECT" = 1 ] || echo --exclude=policy) $d | split -b 15M - $OUT/$d.tgz.
    kill -CONT -- $groups 2>/dev/null
  else
    cp -f $d/songs.json $d/songs.md $OUT/ 2>/dev/null
  fi
done
if [ "$COLLECT" = 1 ]; then
  for d in */*/; do d=${d%/}; [ -d $(dirname $d)/resume ] && continue; s=$(basename $d)
    keep=(--exclude=policy); [ -d $d/resume ] && keep=()    # a sweep's run (run.sh): its policy is what is judged
    tar czf $OUT/$s.tgz --exclude=ckpt --exclude=resume --exclude='*.lock' --exclude=best.tmp "${keep[@]}" \
      -C $(dirname $d) $s $([ -f $d.log ] && echo $s.log); done
  tar czf - -C /tmp xla | split -b 15M - $OUT/xla.tgz.   # the compilation cache, for the next machine
  du -sh /tmp/xla; ls -la $OUT
fi
