"""The general left hand as a residual on the IK planner, held to it by a prior.

Why freely trained residuals drift (an action scaled by 0.01 and a KL-adaptive rate; docs/results.md, "The learned
hands"): on a hand that already plays most notes the advantages are mostly noise, and PPO's step moved the mean
anyway. Their adaptive rate sat at its floor of 1e-6 with the KL per minibatch still above its target, so each step
was Adam's step of about the rate per weight in a direction set by noise: a random walk of the mean, away from a
planner whose F1 halves at a noise of 0.01 of a half range. Three changes:

- a prior: the loss adds 0.1 x KL(pi || N(0, std)) = 0.1 x sum mu^2 / 2 std^2 (`TrainConfig.prior_kl`), so the mean
  returns to the planner unless the advantages keep paying for a correction;
- a fixed rate of 3e-6 and minibatches of 16384 (2 per epoch instead of 8): fewer, less noisy steps;
- exploration at 0.002 of a half range (network std 0.2 at an action scale of 0.01), the std `left_general` samples
  with, which costs the planner 0.02 of window F1; no imitation reward (the planner's motion is the style).

Measured (docs/results.md, "The learned hands"; one H100, 9.8 minutes of training, 6.9e7 samples): stable, the
mean residual 4e-5 of a half range (rms) where the planner goes. Against the planner with constant offsets of that
size (the exact plan is a lucky draw: 0.809 exact, 0.764 with offsets, on 48 held-out songs) it is level on the
official songs (0.988 against 0.986) and 0.016 below on the held-out ones (0.748 against 0.764); on 48 of its own
training songs 0.014 below (0.742 against 0.756). Not better than the planner, even where it trained.

    dexguitar train --hand left --style general --procedural 256 --config left_general_anchored \\
        --out runs/left-general-anchored --max-minutes 7
"""
import dataclasses
import math

from dexguitar.configs import left_general_residual as _residual

CONFIG = dataclasses.replace(_residual.CONFIG, action_scale=0.01, log_std_init=math.log(0.2), kl_target=0.0,
                             actor_lr=3e-6, actor_warmup=50, minibatch=16384, disc_weight=0.0, prior_kl=0.1)
ENV = _residual.ENV
