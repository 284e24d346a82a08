#!/bin/bash
# On a machine of several GPUs (carry .data: site.txz; models/policies may stay behind): the general left hand's
# training (`make train-left-general`'s recipe, 256 procedural songs) spread over N of its GPUs, 4096 envs on each.
#   bash scaling.sh bench 1 2 4     ITER iterations (default 250) on 1 GPU, then 2, then 4, each a run of its own
#                                   (SONGS procedural songs, default 256: a fresh machine plans them first; MB: a
#                                   minibatch of MB samples per GPU instead of the recipe's 16384 over all of them)
#   bash scaling.sh long N MIN      the 8e8-sample run on N GPUs (8e8 / (4096 N envs x 8 steps) iterations: 6104 at
#                                   N = 4) for MIN minutes, resuming /tmp/runs/long on a warm machine, or the compact
#                                   state carried in .data/long.tgz on a fresh one
# Logs and metrics into $OUT; `long` also the run without its full checkpoint (config.json, metrics.jsonl, resume/ in
# parts long.tgz.aa, .ab: `cat long.tgz.* > .data/long.tgz` for the next machine) and the exported policy
# (policy.tgz). A fresh machine plans the songs first (cached in /tmp/plans).
# A dry run on a CPU: ENVS (per device), CONFIG and PY (the interpreter) replace 4096, the recipe and python3.
set -e
[ -d /tmp/site ] || { tar xJf .data/site.txz -C /tmp && mv /tmp/slim /tmp/site; }
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 DEXGUITAR_CACHE=/tmp/xla DEXGUITAR_PLANS=/tmp/plans \
  NCCL_NVLS_ENABLE=0
nvidia-smi -L > $OUT/gpus.txt || true
E=${ENVS:-4096}                 # envs per GPU
train() {
  ${PY:-python3} -c "import sys; from dexguitar.cli import main; sys.exit(main())" train --hand left --style general \
    --procedural ${SONGS:-256} --config ${CONFIG:-left_general_anchored} "$@"
}
MODE=$1; shift
if [ "$MODE" = bench ]; then
  for N in "$@"; do
    rm -rf /tmp/runs/bench$N
    t=$SECONDS
    train --devices $N --envs $((E * N)) --iterations ${ITER:-250} --out /tmp/runs/bench$N \
      $([ -n "$MB" ] && echo --minibatch $((MB * N))) 2>&1 \
      | tee $OUT/bench$N.log | grep -v "it/s" | tail -3
    echo "command seconds: $((SECONDS - t))" | tee -a $OUT/bench$N.log
    cp /tmp/runs/bench$N/metrics.jsonl $OUT/bench$N.metrics.jsonl
  done
else
  N=$1; RUN=/tmp/runs/long
  [ -d $RUN ] || [ ! -f .data/long.tgz ] || { mkdir -p /tmp/runs && tar xzf .data/long.tgz -C /tmp/runs; }
  t=$SECONDS
  train --devices $N --envs $((E * N)) --iterations $((800000000 / (E * N * 8) + 1)) --out $RUN \
    --max-minutes $2 $([ -d $RUN ] && echo --resume) 2>&1 | tee -a $OUT/long.log | grep -v "it/s" | tail -6
  echo "command seconds: $((SECONDS - t))" | tee -a $OUT/long.log
  cp $RUN/metrics.jsonl $OUT/long.metrics.jsonl
  tar czf - --exclude=ckpt --exclude=policy -C /tmp/runs long | split -b 15M - $OUT/long.tgz.   # $OUT: 16 MiB a file
  tar czf $OUT/policy.tgz -C $RUN policy
fi
