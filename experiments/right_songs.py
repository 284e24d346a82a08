"""The right hand on given songs' picking, as written (no tempo change), warm-started from the general right hand
(`dexguitar songs` starts it from models/policies/right_mixed): the sizes of right_gpu.py."""
from dexguitar.envs import EnvConfig
from dexguitar.learn.trainer import TrainConfig

CONFIG = TrainConfig(hand="right", num_envs=4096, horizon=8, minibatch=4096, epochs=5, actor_lr=1e-4,
                     critic_lr=3e-4, disc_lr=1e-4, disc_steps=8, iterations=1_000_000, iterations_per_call=25)
ENV = EnvConfig(shift_prob=0.0, tempo_prob=0.0)
