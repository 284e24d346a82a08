"""The sweep's starting point: dexguitar/configs/left_songs.py as it was before the sweep (left_gpu on the songs as
written, PPO clip 0.2, the paper's)."""
from dexguitar.configs.left_gpu import CONFIG  # noqa: F401 - the sweep's CONFIG
from dexguitar.envs import EnvConfig

ENV = EnvConfig(shift_prob=0.0, tempo_prob=0.0)
