"""The general left hand's recipe sweep (results/general_left/): experiments/left_general.py as it is, the control.
Every variant starts from the same partly trained general hand (`INIT=`, see left_sweep/run.sh)."""
import os
import runpy

CONFIG = runpy.run_path(os.path.join(os.path.dirname(__file__), "..", "left_general.py"))["CONFIG"]
