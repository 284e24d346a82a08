"""The general left hand as a residual on the IK planner : the recipe of left_residual (one GPU) on the
balanced procedural material (`dexguitar train --hand left --style general --procedural N`), none of the authors'
songs.

The planner has seen no song, so a residual on it starts general; PPO learns corrections that hold across chords,
lines and jumps anywhere on the neck. No fret shift or tempo change: the material already spans the neck and tempi,
and the planned feedforward belongs to the notes as written."""
from dexguitar.configs.left_residual import CONFIG, ENV  # noqa: F401 - this module's CONFIG and ENV
