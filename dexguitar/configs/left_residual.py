"""The left hand as a residual on the IK planner (`EnvConfig(feedforward=True)`, `planner/plans.py`): the
env adds the planner's action for the song frame, so the policy, whose output starts near zero, starts as the planner
(mean left F1 0.993 on the authors' songs) and PPO learns only corrections. The songs as written (the planner plans
them so), the sizes and PPO clip of left_songs (one GPU), and a 25-iteration critic warm-up (the critic starts fresh;
see right_songs). Exploration starts at a std of 0.02 of a half range instead of 0.1: the planner's window F1 falls
by a third at 0.01 of action noise (docs/results.md, "The learned hands"). No residual trained so far plays better
than the planner it starts from."""
import dataclasses

from dexguitar.configs import left_songs as _base
from dexguitar.envs import EnvConfig

CONFIG = dataclasses.replace(_base.CONFIG, actor_warmup=25, log_std_init=-3.9)
ENV = EnvConfig(shift_prob=0.0, tempo_prob=0.0, feedforward=True)
