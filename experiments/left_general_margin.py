"""The anchored general left hand (left_general_anchored.py) paid for the room it leaves at each press (issue 11,
item 2).

Why: on held-out procedural songs the planner's held presses leave under 1 mm to the press distance or a fret wire
in 2-33 % of their steps, and miss in 4-32 % (experiments/press_margins.py), and a few micrometres there flip a note
(results/general_left/session30/). Eq. 7 cannot see that room: Eq. 4 is flat within millimetres and r_correct is a
step. Two changes:

- `EnvConfig.margin_reward`: each string's column gains its press margin over 3 mm, clipped to [-1, 1]
  (`rewards.margin_reward`), a smooth reward for pressing deeper and nearer the middle of the fret and for keeping
  other fingers clear of open strings;
- exploration at 0.0005 of a half range (network std 0.05 at an action scale of 0.01), a quarter of the anchored
  recipe's, so that PPO's gradient is that of the margins rather than of their average over a wider blur.

Measured (results/general_left/session34/, one H100, 128 songs, 9.8e7 samples in 15 minutes): the reward did not
rise, the residual stayed at a prior KL of 0.005 per state, and the hand plays as the planner with a micro-offset
(0.771 against the planner's 0.772 with offsets on 48 held-out songs; 0.988 against 0.987 on the official ones).

    dexguitar train --hand left --style general --procedural 128 --config experiments/left_general_margin.py \\
        --out runs/left-general-margin --max-minutes 7.5
"""
import dataclasses
import math

from dexguitar.configs import left_general_anchored as _anchored

CONFIG = dataclasses.replace(_anchored.CONFIG, log_std_init=math.log(0.05))
ENV = dataclasses.replace(_anchored.ENV, margin_reward=1.0)
