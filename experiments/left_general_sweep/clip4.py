"""A point of the general left hand's recipe sweep: base.py with PPO clip 0.4 (the knob of the song recipe,
results/left_sweep.md)."""
import dataclasses
import os
import runpy

CONFIG = dataclasses.replace(runpy.run_path(os.path.join(os.path.dirname(__file__), "base.py"))["CONFIG"], clip=0.4)
