"""The left hand on one GPU: 4096 envs, the paper's horizon, epochs and clip; minibatches of 4096 (8 per epoch) and
learning rates raised for the 16x larger minibatch (the paper's 5e-6 suits 80 updates of 256 samples per 4096)."""
from dexguitar.learn.trainer import TrainConfig

CONFIG = TrainConfig(hand="left", num_envs=4096, horizon=8, minibatch=4096, epochs=5, actor_lr=1e-4,
                     critic_lr=3e-4, disc_lr=1e-4, disc_steps=8, iterations=1_000_000, iterations_per_call=25)
