"""The general left hand as a residual on the IK planner, trained gently (issue 11, item 2).

left_general_residual.py moved the planner too far: over 4.5 H100-minutes its KL per update had a median of 0.6
(synchronizers: 0.04), and zero-shot F1 on the official songs fell from 0.891 to 0.824 (results/general_left/
README.md, fourteenth session). Here the actor's learning rate adapts to hold a KL of 0.01 per minibatch step
(`TrainConfig.kl_target`), and exploration starts at a std of 0.005 of a half range instead of 0.02: the planner's
window F1 is 0.580 at 0.005 and 0.294 at 0.02 (results/planner_noise.md), so the rollouts PPO learns from look like
the deterministic playing that is judged.

Measured (results/official_songs.md, sixteenth session, one H200): it does not train. Window F1 0.551 in the critic
warm-up; the first actor updates after it moved the policy by a KL of 52,000, every episode then ended in a
termination, and F1 stayed 0.000 for 550 iterations with the learning rate at its floor (1e-6). Kept as the record of
that run (results/general_left/session16/gentle_residual/). The cause (seventeenth session): the adaptive rate had
climbed to its ceiling of 1e-2 during the warm-up, where the still actor's KL is 0. The rate now holds through a
warm-up (left_general_scaled.py).

    dexguitar train --hand left --style general --procedural 256 --config experiments/left_general_gentle.py \
        --out runs/left-general-gentle --max-minutes 19
"""
import dataclasses

from dexguitar.configs import left_general_residual as _residual

CONFIG = dataclasses.replace(_residual.CONFIG, kl_target=0.01, actor_lr=1e-5, log_std_init=-5.3, actor_warmup=50)
ENV = _residual.ENV
