"""A point of the left-hand recipe sweep (results/left_sweep.md): experiments/left_sweep/base.py with
gamma=0.9."""
import dataclasses
import os
import runpy

_base = runpy.run_path(os.path.join(os.path.dirname(__file__), "base.py"))
CONFIG = dataclasses.replace(_base["CONFIG"], gamma=0.9)
ENV = _base["ENV"]
