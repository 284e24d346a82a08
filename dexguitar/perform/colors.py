"""String colours as in the paper's Fig. 1, so a video shows at a glance what each hand got right.

- yellow: a string to pick is in its expected state (pressed at the goal fret, or free when it is played open) and
  waits for the pick: the left hand has done its part;
- green: picked once, as a target, while in its expected state (the right note sounded);
- red: picked but wrong: pressed at the wrong fret / not pressed / pressed when it should ring open, not a target
  of the note, or picked a second time;
- grey (the strings' metal) otherwise.
The "so far" state is per note: it resets when the next note starts, like the env's per-note bookkeeping.
`string_colors` is the pure rule for one step; `rollout_colors` applies it to a whole recorded performance; `legend`
names the colours in the video's caption.
"""
from __future__ import annotations

import numpy as np
from dexguitar.world.guitar import N_STRINGS

GREY = np.array([0.8, 0.8, 0.78, 1.0], np.float32)      # the scene's "metal" material
YELLOW = np.array([1.0, 0.82, 0.05, 1.0], np.float32)
GREEN = np.array([0.1, 0.85, 0.2, 1.0], np.float32)
RED = np.array([0.95, 0.1, 0.08, 1.0], np.float32)
# The video's legend (`legend`), one line a colour; grey, the strings' own colour, needs none.
LEGEND = (("yellow", "pressed, ready to pick"), ("green", "picked right"), ("red", "picked wrong"))


def in_state(goal_left, press) -> np.ndarray:
    """Per string: is it as the left hand should hold it? goal k > 0: pressed at fret k; -1 (open): not pressed;
    0 (mute / don't care): always. Same rule as `metrics.left_ok`, in numpy."""
    goal, press = np.asarray(goal_left), np.asarray(press)
    return np.where(goal > 0, press == goal, np.where(goal < 0, press == 0, True))


def string_colors(goal_left, pick_targets, press, picked_so_far, picked_ok_so_far) -> np.ndarray:
    """(6, 4) rgba for one step. goal_left: int (6,) left goal code of the current note; pick_targets: bool (6,);
    press: int (6,) detected frets (0 none); picked_so_far: bool (6,) picked at least once in this note;
    picked_ok_so_far: bool (6,) picked correctly (see `update_so_far`)."""
    targets = np.asarray(pick_targets, bool)
    picked = np.asarray(picked_so_far, bool)
    ok = np.asarray(picked_ok_so_far, bool)
    ready = targets & in_state(goal_left, press) & ~picked
    out = np.tile(GREY, (N_STRINGS, 1))
    out[ready] = YELLOW
    out[picked & ok] = GREEN
    out[picked & ~ok] = RED
    return out


def update_so_far(picked_so_far, picked_ok_so_far, picks, goal_left, pick_targets, press):
    """Add one step's picks to the note's state: a pick is correct when the string is a target, was not picked
    before in the note and is in its expected state at that moment; a second pick makes it wrong."""
    picks = np.asarray(picks, bool)
    before = np.asarray(picked_so_far, bool)
    good = picks & ~before & np.asarray(pick_targets, bool) & in_state(goal_left, press)
    ok = np.where(picks, good, np.asarray(picked_ok_so_far, bool))
    return before | picks, ok


def rollout_colors(press, picks, note, goal_left_rows, pick_rows) -> np.ndarray:
    """(T, 6, 4) colours of a recorded performance. press (T, 6), picks (T, 6): per-step `info`; note (T,): the
    window row (note) each step belongs to (`play.play` gives it as `row`, from the rows' durations);
    goal_left_rows (N, 6), pick_rows (N, 6): `state.window.left` / `.pick`. The state resets when `note`
    changes; colours after the picks of step t (what the pick just did shows in the same frame)."""
    press = np.asarray(press)
    picks = np.asarray(picks, bool)
    note = np.asarray(note)
    goal_left_rows, pick_rows = np.asarray(goal_left_rows), np.asarray(pick_rows, bool)
    T = len(press)
    out = np.empty((T, N_STRINGS, 4), np.float32)
    picked = ok = np.zeros(N_STRINGS, bool)
    for t in range(T):
        if t == 0 or note[t] != note[t - 1]:
            picked = ok = np.zeros(N_STRINGS, bool)
        r = int(np.clip(note[t], 0, len(goal_left_rows) - 1))
        picked, ok = update_so_far(picked, ok, picks[t], goal_left_rows[r], pick_rows[r], press[t])
        out[t] = string_colors(goal_left_rows[r], pick_rows[r], press[t], picked, ok)
    return out


def color_names(colors) -> list[str]:
    """'grey' / 'yellow' / 'green' / 'red' per string, for reports and tests."""
    names = {"grey": GREY, "yellow": YELLOW, "green": GREEN, "red": RED}
    return [next((k for k, v in names.items() if np.allclose(c, v)), "other") for c in np.asarray(colors)]


def legend() -> str:
    """The caption lines that name the string colours (`LEGEND`), as the video shows them under its F1."""
    return "\n".join(f"{name}: {meaning}" for name, meaning in LEGEND)
