"""left_general_scaled_quiet.py without the imitation rewards (`disc_weight=0`): PPO on the string rewards alone.

In the scaled and quiet residual runs the string rewards stayed flat (0.935 -> 0.922 per step) while both
discriminator rewards rose all along (wrist 0.006 -> 0.055 in 5 minutes, 0.008 -> 0.197 in 17), and the mean
action got worse on held-out windows. The hypothesis tested here: each reward column's advantage is
standardized on its own before weighting (Eq. 9), so a reward that is easy to raise steers the mean even at a weight
of 0.05: here the motion style of the reference clip, which the planner's pressing poses do not share.

Measured (results/general_left/session17/, one H100, 5 minutes, 2.5e7 samples): about as the quiet run. Held-out
windows 0.835 -> 0.777; official songs 0.949 -> 0.929. The discriminator rewards rose as much as with their weight,
so that rise is the discriminators drifting, and the imitation reward is not what moves the mean.

    dexguitar train --hand left --style general --procedural 64 --config experiments/left_general_scaled_task.py \\
        --out runs/left-general-task --max-minutes 5
"""
import dataclasses
import os
import runpy

_quiet = runpy.run_path(os.path.join(os.path.dirname(__file__), "left_general_scaled_quiet.py"))
CONFIG = dataclasses.replace(_quiet["CONFIG"], disc_weight=0.0)
ENV = _quiet["ENV"]
