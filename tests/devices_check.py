"""Data-parallel training on forced CPU devices (run by tests/test_devices.py in its own process, because the device
count is fixed when JAX starts): one iteration on 1 and on 4 devices from the same state, then a run saved on 4
devices resumed on 1 (the one-device program of the first comparison again: two programs, not three). Prints one
JSON line."""
import json
import sys
from pathlib import Path

import jax
import numpy as np

from dexguitar.learn.devices import Placement
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
state = trainer.init()
params = {}
for n in (1, 4):
    where = Placement(n)
    shardings, whole = where.shardings(state), where.replicated(trainer.data)
    new, _ = trainer.make_train_chunk(1, where)(where.put(state, shardings), where.put(trainer.data, whole))
    params[n] = jax.device_get(new.params)
    devices = {d.id for leaf in jax.tree.leaves(new.env) for d in leaf.sharding.device_set}
    assert len(devices) == n, devices
diff = max(float(np.max(np.abs(np.asarray(a) - np.asarray(b))))
           for a, b in zip(jax.tree.leaves(params[1]), jax.tree.leaves(params[4])))
moved = max(float(np.max(np.abs(np.asarray(a) - np.asarray(b))))
            for a, b in zip(jax.tree.leaves(params[1]), jax.tree.leaves(state.params)))
first = train(trainer, out_dir, iterations=1, devices=4, progress=False, log=lambda m: None)
second = train(trainer, out_dir, iterations=2, devices=1, resume=True, progress=False, log=lambda m: None)
rows = [json.loads(r) for r in (out_dir / "metrics.jsonl").read_text().splitlines()]
print(json.dumps({"devices": len(jax.devices()), "max_diff": diff, "moved": moved,
                  "iterations": [r["iteration"] for r in rows], "second": second["iteration"]}))
