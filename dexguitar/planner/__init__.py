"""The IK planner: hand-made motions that play any song with our hands, no learning. It is the teacher and the
baseline of the learned hands, never part of a learned policy: an env plays its plans only where its config asks for
a feedforward (`EnvConfig.feedforward`, `right_feedforward`).

How it plays, per hand (the rules in prose: docs/planner.md):
1. Keyframes in the guitar frame: fingertips on the press points, hand positions of one finger per fret, pairs and
   barres (`left`); pick strokes across the target strings (`right`).
2. Joint targets by least squares on the env model's kinematics (`world.kinematics`), solved to convergence so that
   a plan does not depend on the CPU's rounding, joined by minimum-jerk moves (`tracking`).
3. `Tracker`: PD targets whose simulated next state is the desired one, an open-loop action sequence for the env.
4. Both hands (duet): the left hand is planned and simulated first; the right hand crosses each note's strings once
   the simulated left hand holds the note.
`plans` turns songs into per-frame `Plan`s, made in worker processes and cached on disk; `perform.scripted` plays
them through the envs and prints their F1.

    tracking    Notes, min_jerk, converge (bounded least squares), Tracker
    right       ScriptedRight, LeftTiming, RIGHT_PLANNER_VERSION
    left        ScriptedLeft, PLANNER_VERSION
    plans       Plan, attach, prepare, plan_songs, constants, cache_dir
"""
from dexguitar.planner.left import PLANNER_VERSION, ScriptedLeft
from dexguitar.planner.plans import Plan, attach, cache_dir, constants, left_plans, plan_songs, prepare
from dexguitar.planner.right import RIGHT_PLANNER_VERSION, LeftTiming, ScriptedRight
from dexguitar.planner.tracking import Notes, Tracker

__all__ = ["PLANNER_VERSION", "RIGHT_PLANNER_VERSION", "Notes", "Tracker", "ScriptedLeft", "ScriptedRight",
           "LeftTiming", "Plan", "attach", "prepare", "plan_songs", "left_plans", "constants", "cache_dir"]
