"""A point of the general left hand's recipe sweep: base.py without the fret-shift and tempo augmentation. The
procedural material already spans the neck, and the song recipe learned several times faster without both
(issue 10)."""
import os
import runpy

from dexguitar.envs import EnvConfig

CONFIG = runpy.run_path(os.path.join(os.path.dirname(__file__), "base.py"))["CONFIG"]
ENV = EnvConfig(shift_prob=0.0, tempo_prob=0.0)
