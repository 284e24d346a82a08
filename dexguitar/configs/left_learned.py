"""The learned left hand: a policy network alone at run time, taught by the IK planner on the general material.

The planner labels every state the student visits (`EnvConfig.teacher`: its planned action plus a pull back to the
planned pose), and the actor's loss adds the labels' negative log-likelihood to PPO's (`TrainConfig.teacher_weight`):
DAgger with a true expert, on the student's own states, inside the PPO loop. Its std is learned by the same
likelihood, so exploration shrinks to what the student cannot yet imitate. The songs as written (the plans belong to
the notes), the sizes of left_gpu. At run time nothing is planned: the exported policy sees what the paper's policy
sees (2 frames of link states and 5 upcoming notes).

Measured (docs/results.md, "The learned hands"; one H200, 256 songs): the student fits the labels to 0.19-0.31 of a
half range (rms) and plays the official songs zero-shot at 0.07-0.08 after 2.8e7-1.08e8 samples, with a teacher
weight of 1 or 100 and with the label damped (`--set env.teacher_damping=0.1 --set env.teacher_finger_damping=0.03`).
The planner's hand itself falls from 0.80 to 0.46 with noise of 0.01 on its actions. The student errs most in the
finger joints that put a finger on a string: the labels carry the planner's fingering, which the observation does not
show (an MLP fitting the labels offline plays 0.006, and 0.162 when it also sees the plan's finger pose).

    dexguitar train --hand left --style general --procedural 256 --config left_learned --out runs/left-learned
"""
import dataclasses
import math

from dexguitar.configs import left_gpu as _gpu
from dexguitar.envs import EnvConfig

CONFIG = dataclasses.replace(_gpu.CONFIG, teacher_weight=1.0, log_std_init=math.log(0.05))
ENV = EnvConfig(shift_prob=0.0, tempo_prob=0.0, teacher=True)
