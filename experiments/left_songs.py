"""The left hand on given songs, as written (the authors' song-specific recipe switches fret shift and tempo change
off, reference §3.4): the sizes and learning rates of left_gpu.py, 4096 envs on one GPU, and a PPO clip of 0.3
instead of the paper's 0.2 (results/left_sweep.md: the policy's progress per iteration is bounded by the clip; 0.3
learned faster on turkish_march and on super_mario, which it was not tuned on)."""
from dexguitar.envs import EnvConfig
from dexguitar.learn.trainer import TrainConfig

CONFIG = TrainConfig(hand="left", num_envs=4096, horizon=8, minibatch=4096, epochs=5, actor_lr=1e-4,
                     critic_lr=3e-4, disc_lr=1e-4, disc_steps=8, clip=0.3, iterations=1_000_000,
                     iterations_per_call=25)
ENV = EnvConfig(shift_prob=0.0, tempo_prob=0.0)
