#!/bin/bash
# On the device (carry .data; models/policies holding left_general and right_mixed): `dexguitar sync` for one host
# call, several times over one cache (issue 10, "compile once", `learn/executable.py`). Without an argument: a first
# run (empty caches: the chunk compiled beside the first state and kept), a later run (the chunk loaded from its
# file), then, with the chunk files removed, a run whose chunk comes out of JAX's persistent cache and one that loads
# what that run kept. With `seeds`: a first run, then runs with another seed and another number of iterations, which
# the chunk does not read (`executable.OUTSIDE_THE_CHUNK`): each loads the first run's chunk file. With `load`: where a
# later run's 10 s go: a first run if no chunk file is kept, a later one with XLA's compiler stages logged, then
# experiments/chunk_load.py times the file's load alone in a fresh process, twice.
[ -d /tmp/site/mujoco ] || { tar xJf .data/site.txz -C /tmp && rm -rf /tmp/site && mv /tmp/slim /tmp/site; }
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 DEXGUITAR_CACHE=/tmp/xla DEXGUITAR_PLANS=/tmp/plans
nvidia-smi --query-gpu=name --format=csv,noheader | tee $OUT/gpu.txt
D() { python3 -c "import sys; from dexguitar.cli import main; sys.exit(main())" "$@"; }
S=${SONG:-.data/official/spring_overture.json}
sync1() {
  t=$SECONDS
  D sync --song $S --left models/policies/left_general --right models/policies/right_mixed \
    --config sync_hold --out /tmp/runs/$1 --stop-after-calls 1 --no-eval "${@:2}" > $OUT/$1.log 2>&1
  echo "$1: rc $? $((SECONDS - t)) s; $(grep -E 'training chunk' $OUT/$1.log | cut -c1-160)" | tee -a $OUT/times.txt
}
if [ "$1" = seeds ]; then
  sync1 seed1 --seed 1
  sync1 seed2 --seed 2
  sync1 seed3_longer --seed 3 --iterations 999
elif [ "$1" = load ]; then
  ls /tmp/xla/chunks/*.exe > /dev/null 2>&1 || sync1 first
  TF_CPP_MIN_LOG_LEVEL=0 TF_CPP_VMODULE=gpu_compiler=1,nvptx_compiler=1 sync1 later
  grep -E "RunHloPasses|RunBackend|ptx|Deserializ" $OUT/later.log | head -20 | tee -a $OUT/times.txt
  for i in 1 2; do python3 experiments/chunk_load.py /tmp/xla | tee -a $OUT/load.jsonl; done
else
  sync1 first
  sync1 later
  rm -f /tmp/xla/chunks/*.exe
  sync1 resaved
  sync1 reloaded
fi
ls -la /tmp/xla/chunks | tee -a $OUT/times.txt
