"""The general left hand as a residual on the IK planner whose action is scaled down (issue 11, item 2).

A residual must correct the planner by thousandths of a half range. With the network's action used as it is, Adam,
which moves every weight by about its learning rate, shifts the mean by many exploration stds per step even at
1e-6 (left_general_gentle.py). Here the network's action is multiplied by 0.01 (`TrainConfig.action_scale`), so
its std of 0.5 explores at 0.005 of a half range, as the gentle run did, while the network itself learns at the
usual sizes. The actor's rate adapts to a KL of 0.01 per minibatch step from 1e-4, and is held through the 50
iterations of critic warm-up (the gentle run's rate had climbed to its ceiling of 1e-2 in its warm-up).

Measured (results/general_left/session17/, one H200, 17 minutes, 1.0e8 samples): stable, but no better than the
planner. Window F1 0.569 -> 0.620 came from the std falling to 0.0022, not from the mean. With the mean action,
zero-shot on the official songs fell from 0.949 to 0.905 (chords above 0.8: 87 % -> 76 %), and held-out windows
fell from 0.835 to 0.748.

    dexguitar train --hand left --style general --procedural 256 --config experiments/left_general_scaled.py \\
        --out runs/left-general-scaled --max-minutes 20
"""
import dataclasses
import math

from dexguitar.configs import left_general_residual as _residual

CONFIG = dataclasses.replace(_residual.CONFIG, action_scale=0.01, log_std_init=math.log(0.5), kl_target=0.01,
                             actor_lr=1e-4, actor_warmup=50)
ENV = _residual.ENV
