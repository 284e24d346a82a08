"""How many rows each device multiplies in the training chunk, on forced CPU devices (issue 12).

A matrix product through a layer of 256, 512 or 1024 units is counted by its rows: the rollout's envs, the values at
T + 1 steps and PPO's minibatches. With a minibatch of 16 on 4 devices, a device whose rows include 16 computes the
whole minibatch's gradient; after the split each multiplies 4. `--whole` compiles as before the split. About a
minute on a 2-core CPU:

    XLA_FLAGS=--xla_force_host_platform_device_count=4 JAX_PLATFORMS=cpu python experiments/update_rows.py [--whole]
"""
import collections
import re
import sys

from dexguitar.learn.devices import Placement
from dexguitar.learn.trainer import Trainer, TrainConfig
from dexguitar.music import library
from dexguitar.music import timeline as TL

if __name__ == "__main__":
    if "--whole" in sys.argv:
        split_update = Trainer.ppo_update
        Trainer.ppo_update = lambda self, ts, batch, key, split=None: split_update(self, ts, batch, key, None)
    cfg = TrainConfig(hand="right", num_envs=8, horizon=4, minibatch=16, epochs=1, iterations_per_call=1)
    trainer = Trainer(cfg, [TL.from_song(library.load("ode_to_joy"))], None)
    where = Placement(4)
    state = where.placed_shapes(trainer.state_shapes)
    text = trainer.make_train_chunk(1, where).lower(state, where.put(trainer.data, where.replicated(
        trainer.data))).compile().as_text()
    rows = collections.Counter(int(r) for r in re.findall(r"= f32\[(\d+),(?:256|512|1024)\]\S* dot\(", text))
    print(f"{where.n} devices, {cfg.num_envs} envs, minibatch {cfg.minibatch}: matrix products by rows "
          f"{dict(sorted(rows.items()))}")
