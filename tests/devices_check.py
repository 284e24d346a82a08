"""Data-parallel training on forced CPU devices (run by tests/test_devices.py in its own process, because the device
count is fixed when JAX starts): one `train` iteration on 4 devices and one on 1 from the same first state, then the
4-device run resumed on 1 (the 1-device run's program again, reused in the process: two programs, not three).
Prints one JSON line."""
import json
import sys
from pathlib import Path

import jax
import numpy as np

from dexguitar.learn import checkpoint as C
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
params = {}
for n in (4, 1):
    train(trainer, out_dir / f"on{n}", iterations=1, devices=n, progress=False, log=messages.append)
    params[n] = jax.device_get(C.restore(out_dir / f"on{n}" / "ckpt", start)[0].params)
diff = max(float(np.max(np.abs(np.asarray(a) - np.asarray(b))))
           for a, b in zip(jax.tree.leaves(params[1]), jax.tree.leaves(params[4])))
moved = max(float(np.max(np.abs(np.asarray(a) - np.asarray(b))))
            for a, b in zip(jax.tree.leaves(params[1]), jax.tree.leaves(jax.device_get(start.params))))
second = train(trainer, out_dir / "on4", iterations=2, devices=1, resume=True, progress=False, log=messages.append)
rows = [json.loads(r) for r in (out_dir / "on4" / "metrics.jsonl").read_text().splitlines()]
print(json.dumps({"devices": len(jax.devices()), "max_diff": diff, "moved": moved,
                  "split": [m for m in messages if m.startswith("4 devices")],
                  "chunks": [m.split(" the training chunk")[0] for m in messages if "the training chunk" in m],
                  "iterations": [r["iteration"] for r in rows], "second": second["iteration"]}))
