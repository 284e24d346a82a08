"""sync_hold.py with a reward of 3 per completed both-hands hold (a device trial)."""
import dataclasses
import runpy

CONFIG = runpy.run_path("/tmp/code/experiments/sync_hold.py")["CONFIG"]
ENV = dataclasses.replace(runpy.run_path("/tmp/code/experiments/sync_hold.py")["ENV"], hold_reward=3.0)
