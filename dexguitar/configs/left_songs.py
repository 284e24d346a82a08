"""The left hand on given songs, as written (the authors' song-specific recipe switches fret shift and tempo change
off, reference §3.4): the sizes and learning rates of left_gpu, 4096 envs on one GPU, and a PPO clip of 0.3
instead of the paper's 0.2 (docs/results.md, "The learned hands": the policy's progress per iteration is bounded by
the clip; 0.3 learned faster on turkish_march and on super_mario, which it was not tuned on)."""
import dataclasses

from dexguitar.configs import left_gpu as _base
from dexguitar.envs import EnvConfig

CONFIG = dataclasses.replace(_base.CONFIG, clip=0.3)
ENV = EnvConfig(shift_prob=0.0, tempo_prob=0.0)
