"""Synchronization on one GPU: 4096 duet envs and the sizes and learning rates of left_gpu (the paper's Table S1
scaled to the 16x larger minibatch). The env is `sync.SYNC_ENV`: the target song as written, 20 s episodes."""
from dexguitar.learn.trainer import TrainConfig

CONFIG = TrainConfig(hand="duet", num_envs=4096, horizon=8, minibatch=4096, epochs=5, actor_lr=1e-4,
                     critic_lr=3e-4, disc_lr=1e-4, disc_steps=8, iterations=1_000_000, iterations_per_call=25)
