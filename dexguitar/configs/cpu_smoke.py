"""A tiny configuration for any CPU: 4 envs, 2 iterations; for the tests, the notebooks' tiny mode and checking
that a command runs (`dexguitar train --song ode_to_joy --config cpu_smoke --out /tmp/run`). It learns nothing."""
from dexguitar.learn.trainer import TrainConfig

CONFIG = TrainConfig(num_envs=4, horizon=4, minibatch=8, epochs=2, disc_steps=2, disc_buffer=64, disc_batch=16,
                     iterations=2, iterations_per_call=1)
