#!/usr/bin/env bash
# Wheels: .data/whl/ when there (only what training needs, so a compilation cache fits the carry), else .whl/.
# On the device: install the wheels, unpack the code snapshot into /tmp/code, start `dexguitar songs` in the
# background (RUN, SONGS, MODE from the environment, other arguments passed on), then wait like poll.sh.
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --target /tmp/site $(ls .data/whl/*.whl 2>/dev/null || ls .whl/*.whl) || exit 1
mkdir -p /tmp/code /tmp/runs && tar xzf .data/code.tgz -C /tmp/code && cp .data/poll.sh /tmp/poll.sh
# A compilation cache brought back from an earlier machine of the same kind (COLLECT=1 packs it) skips the compiles.
[ -f .data/xla.tgz ] && tar xzf .data/xla.tgz -C /tmp && echo "cache: $(ls /tmp/xla | wc -l) programs"
cd /tmp/code
export PYTHONPATH=/tmp/site:/tmp/code PYTHONUNBUFFERED=1 DEXGUITAR_CACHE=/tmp/xla
nvidia-smi --query-gpu=name,memory.total --format=csv,noheader
setsid nohup python3 -c "import sys; from dexguitar.cli import main; sys.exit(main())" songs $SONGS $MODE \
  --out /tmp/runs/$RUN "$@" > /tmp/runs/$RUN.log 2>&1 < /dev/null &
sleep 2
bash /tmp/poll.sh
