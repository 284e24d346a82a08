"""A point of the left-hand recipe sweep (results/left_sweep.md): experiments/left_sweep/base.py with
num_envs=1024, minibatch=1024."""
import dataclasses
import os
import runpy

_base = runpy.run_path(os.path.join(os.path.dirname(__file__), "base.py"))
CONFIG = dataclasses.replace(_base["CONFIG"], num_envs=1024, minibatch=1024)
ENV = _base["ENV"]
