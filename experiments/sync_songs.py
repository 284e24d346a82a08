"""Synchronization in `dexguitar songs`: sync_gpu.py with a 50-iteration critic warm-up, for the reason of
right_songs.py: the synchronizer starts as the identity (its last layer is zero) but its critic starts fresh, and PPO
on a random critic's advantages moves a warm-started actor. Measured (results/official_songs.md): come_as_you_are
0.778 -> 0.953 with it; on wipe_out the pair got worse with it (0.918 -> 0.873) and without it (0.945 -> 0.918), so
the warm-up is not what decides there."""
from dexguitar.learn.trainer import TrainConfig

CONFIG = TrainConfig(hand="duet", num_envs=4096, horizon=8, minibatch=4096, epochs=5, actor_lr=1e-4,
                     critic_lr=3e-4, disc_lr=1e-4, disc_steps=8, iterations=1_000_000, iterations_per_call=25,
                     actor_warmup=50)
