"""Synchronization in `dexguitar songs`: sync_gpu.py with a 50-iteration critic warm-up. The synchronizer starts as
the identity (its last layer is zero) but the critic starts fresh, and PPO on a random critic's advantages moved a
good pair away from it: on wipe_out both hands' F1 fell from 0.945 to 0.918 in 3 minutes of synchronization without
the warm-up, the right hand's from 0.993 to 0.980 (results/official_songs.md)."""
from dexguitar.learn.trainer import TrainConfig

CONFIG = TrainConfig(hand="duet", num_envs=4096, horizon=8, minibatch=4096, epochs=5, actor_lr=1e-4,
                     critic_lr=3e-4, disc_lr=1e-4, disc_steps=8, iterations=1_000_000, iterations_per_call=25,
                     actor_warmup=50)
