#!/usr/bin/env bash
# On the device: install MuJoCo (.data/site.txz from slim_site.sh when there, else the wheels of .data/whl/ or
# .whl/), unpack the code (.data/code.tgz, else a copy of this working tree) into /tmp/code, a run carried from an
# earlier machine (.data/run.tgz) into /tmp/runs and a compilation cache (.data/xla.tgz) into /tmp/xla; start a
# shell command in the background (CMD, default `dexguitar songs $SONGS $MODE --out /tmp/runs/$RUN "$@"`; a
# `dexguitar` on PATH runs the code snapshot), then wait like poll.sh. On a warm machine that already ran it, the setup is skipped, so
# `WAIT=560 bash /tmp/poll.sh && RUN=b CMD=... bash .data/start.sh` chains a second run after the first.
if [ ! -f /tmp/poll.sh ]; then
ok() { PYTHONPATH=/tmp/site python3 -c "import mujoco, mujoco.mjx; print('mujoco', mujoco.__version__)"; }
[ -f .data/site.txz ] && tar xJf .data/site.txz -C /tmp && rm -rf /tmp/site && mv /tmp/slim /tmp/site
ok || { rm -rf /tmp/site; python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --target \
  /tmp/site $(ls .data/whl/*.whl 2>/dev/null || ls .whl/*.whl) && ok; } || exit 1
mkdir -p /tmp/code /tmp/runs
if [ -f .data/code.tgz ]; then tar xzf .data/code.tgz -C /tmp/code
else cp -r dexguitar experiments models pyproject.toml /tmp/code/; fi
cp .data/poll.sh /tmp/poll.sh
mkdir -p /tmp/bin && printf '#!/bin/sh\nexec python3 -c "import sys; from dexguitar.cli import main; sys.exit(main())" "$@"\n' \
  > /tmp/bin/dexguitar && chmod +x /tmp/bin/dexguitar
[ -f .data/run.tgz ] && tar xzf .data/run.tgz -C /tmp/runs && echo "carried run: $(ls /tmp/runs)"
# A compilation cache brought back from an earlier machine of the same kind (COLLECT=1 packs it) skips the compiles.
[ -f .data/xla.tgz ] && tar xzf .data/xla.tgz -C /tmp && echo "cache: $(ls /tmp/xla | wc -l) programs"
fi
export REPO=$PWD                      # CMD may read carried files from there ($REPO/.data/...)
cd /tmp/code
export PYTHONPATH=/tmp/site:/tmp/code PYTHONUNBUFFERED=1 DEXGUITAR_CACHE=/tmp/xla PATH=/tmp/bin:$PATH
nvidia-smi --query-gpu=name,memory.total --format=csv,noheader
[ -z "${CMD:-}" ] && CMD="dexguitar songs $SONGS $MODE --out /tmp/runs/$RUN $*"
setsid nohup bash -c "$CMD" > /tmp/runs/${RUN:-run}.log 2>&1 < /dev/null &
echo $! > /tmp/runs/${RUN:-run}.pid  # its process group; poll.sh waits on it (a pattern would match this call too)
sleep 2
bash /tmp/poll.sh
