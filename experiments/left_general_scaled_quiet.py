"""left_general_scaled.py with exploration ten times quieter: a std of 0.0005 of a half range (network std 0.05 at
an action scale of 0.01).

The scaled residual's PPO lowered its std from 0.005 to 0.0022 and moved its mean for the worse: on held-out windows
its mean action plays F1 0.748 against the zero residual's 0.835, and it is ahead only at a noise of 0.005 (0.696
against 0.671; results/general_left/session17/scaled_residual/). At 0.0005 the planner's noisy rollouts play about as
its mean does, so what PPO improves is the played mean, not the survival of noise.

Measured (results/general_left/session17/, one H100, 5 minutes, 2.5e7 samples): the mean still got worse. Held-out
windows 0.835 -> 0.784; official songs 0.949 -> 0.916.

    dexguitar train --hand left --style general --procedural 64 --config experiments/left_general_scaled_quiet.py \\
        --out runs/left-general-quiet --max-minutes 5
"""
import dataclasses
import math
import os
import runpy

_scaled = runpy.run_path(os.path.join(os.path.dirname(__file__), "left_general_scaled.py"))
CONFIG = dataclasses.replace(_scaled["CONFIG"], log_std_init=math.log(0.05))
ENV = _scaled["ENV"]
