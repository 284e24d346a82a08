"""PPO on from a policy distilled from the IK planner (`dexguitar distill`, then `train --init-from`): the sizes of
left_general.py on the same material, with a critic that learns for 40 iterations before the actor moves (it starts
from nothing while the actor already plays) and a 10x smaller actor learning rate, so that PPO refines the cloned
hand instead of unlearning it."""
import dataclasses
import os
import runpy

GENERAL = runpy.run_path(os.path.join(os.path.dirname(__file__), "left_general.py"))["CONFIG"]
CONFIG = dataclasses.replace(GENERAL, actor_lr=1e-5, actor_warmup=40)
