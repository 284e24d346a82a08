"""The left hand on given songs as written, warm-started from another left policy (`dexguitar songs` starts it from
models/policies/left_official15, the one left hand of the 15 official songs): the recipe of left_songs.py (PPO clip
0.3) with a 25-iteration critic warm-up, since the critic starts fresh (right_songs.py: PPO on a random critic's
advantages undoes a warm-started actor). On super_mario this reached song F1 0.971 in 4.2 minutes, compilation
included, against 0.419 after 3 minutes from scratch (results/official_songs.md)."""
from dexguitar.envs import EnvConfig
from dexguitar.learn.trainer import TrainConfig

CONFIG = TrainConfig(hand="left", num_envs=4096, horizon=8, minibatch=4096, epochs=5, actor_lr=1e-4,
                     critic_lr=3e-4, disc_lr=1e-4, disc_steps=8, clip=0.3, iterations=1_000_000,
                     iterations_per_call=25, actor_warmup=25)
ENV = EnvConfig(shift_prob=0.0, tempo_prob=0.0)
