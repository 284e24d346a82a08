"""The sweep's starting point: experiments/left_songs.py as it was before the sweep (PPO clip 0.2, the paper's)."""
from dexguitar.envs import EnvConfig
from dexguitar.learn.trainer import TrainConfig

CONFIG = TrainConfig(hand="left", num_envs=4096, horizon=8, minibatch=4096, epochs=5, actor_lr=1e-4,
                     critic_lr=3e-4, disc_lr=1e-4, disc_steps=8, iterations=1_000_000, iterations_per_call=25)
ENV = EnvConfig(shift_prob=0.0, tempo_prob=0.0)
