"""Data-parallel training on forced CPU devices (run by tests/test_devices.py in its own process, because the device
count is fixed when JAX starts): one `train` iteration on 4 devices and one on 1 from the same first state, then the
4-device run resumed on 1 (the 1-device run's program again, reused in the process: two programs, not three), and a
1-device run that loads that program from its file, as a later process would. Also the row counts of the programs'
matrix products: on 4 devices each computes a quarter of a minibatch.
Prints one JSON line."""
import json
import re
import sys
from pathlib import Path

import jax
import numpy as np

from dexguitar.learn import checkpoint as C
from dexguitar.learn import executable
from dexguitar.learn.run import train
from dexguitar.learn.trainer import Trainer, TrainConfig
from dexguitar.music import library
from dexguitar.music import timeline as TL

cache, out_dir = sys.argv[1], Path(sys.argv[2])
jax.config.update("jax_compilation_cache_dir", cache)
jax.config.update("jax_persistent_cache_min_compile_time_secs", 2.0)
# the smallest training program that has every part the devices split (envs, rollout, PPO, normalizers): the right
# hand without its discriminator, which compiles the fastest of the three scenes on a CPU
cfg = TrainConfig(hand="right", num_envs=4, horizon=4, minibatch=8, epochs=2, iterations_per_call=1)
trainer = Trainer(cfg, [TL.from_song(library.load("ode_to_joy"))], None)
start = trainer.init()
messages = []
params, dot_rows = {}, {}
for n in (4, 1):
    before = set(executable._LIVE)
    train(trainer, out_dir / f"on{n}", iterations=1, devices=n, progress=False, log=messages.append)
    params[n] = jax.device_get(C.restore(out_dir / f"on{n}" / "ckpt", start)[0].params)
    # the rows of each matrix product through a 256-wide layer in the program one device runs (PPO's minibatches,
    # the rollout's envs, the values at T + 1 steps)
    text = executable._LIVE[(set(executable._LIVE) - before).pop()].as_text()
    dot_rows[n] = sorted({int(r) for r in re.findall(r"= f32\[(\d+),256\]\S* dot\(", text)})
diff = max(float(np.max(np.abs(np.asarray(a) - np.asarray(b))))
           for a, b in zip(jax.tree.leaves(params[1]), jax.tree.leaves(params[4])))
moved = max(float(np.max(np.abs(np.asarray(a) - np.asarray(b))))
            for a, b in zip(jax.tree.leaves(params[1]), jax.tree.leaves(jax.device_get(start.params))))
second = train(trainer, out_dir / "on4", iterations=2, devices=1, resume=True, progress=False, log=messages.append)
# a later process on this machine: the 1-device program loaded from its file runs on the first device, not on all 4
executable._LIVE.clear()
later = train(trainer, out_dir / "later", iterations=1, devices=1, progress=False, log=messages.append)
rows = [json.loads(r) for r in (out_dir / "on4" / "metrics.jsonl").read_text().splitlines()]
print(json.dumps({"devices": len(jax.devices()), "max_diff": diff, "moved": moved, "dot_rows": dot_rows,
                  "split": [m for m in messages if m.startswith("4 devices")],
                  "chunks": [m.split(" the training chunk")[0] for m in messages if "the training chunk" in m],
                  "iterations": [r["iteration"] for r in rows], "second": second["iteration"],
                  "later": later["iteration"]}))
