"""The sweep's starting point: experiments/left_songs.py as it was before the sweep (left_gpu.py on the songs as
written, PPO clip 0.2, the paper's)."""
import os
import runpy

from dexguitar.envs import EnvConfig

_gpu = runpy.run_path(os.path.join(os.path.dirname(__file__), "..", "left_gpu.py"))
CONFIG = _gpu["CONFIG"]
ENV = EnvConfig(shift_prob=0.0, tempo_prob=0.0)
