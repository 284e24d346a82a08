"""Scoring the notes: per-note precision, recall and F1 exactly as the paper defines them (Sec. 6.1), as streaming
tallies that the env keeps while it plays.

A note is judged string by string. True positives:
- left hand: a target string (goal fret k > 0) pressed at fret k *continuously* for at least 2/3 of the note;
  predicted = non-mute strings pressed (any fret) continuously for at least 2/3 of the note;
- right hand: a target string picked once and only once, in a consistent order (no error flagged on it);
  predicted = strings picked at all during the note;
- both hands: picked correctly, pressed correctly (open strings: not pressed) at the moment of the pick, and kept so
  continuously for at least 2/3 of the note's duration after the pick; predicted and targets as for the right hand.
  The paper's rule (3) counts that hold from the pick, not up to the note's end: a string picked late in a note
  (the last strings of a strum on a short repeated chord) that stays pressed into the next note still sounds right.
  So a note's both-hands verdict can stay open into the next note, and is final at the end of the next note
  (`close` returns it then, as "both"; a hold still open then is wrong). The last note of a song is judged within
  itself ("both_now"). Counting the hold only inside the note, as this module did before, scored the same
  synchronized snow pair 0.80 instead of 0.92.
precision = TP / predicted and recall = TP / targets, with 0/0 = 1 (a rest played as a rest is perfect).

The env updates a `NoteTally` every control step and closes it at the end of each note; offline evaluation replays
recorded press/pick arrays through the same two functions, so training curves and reports cannot disagree.
"""
from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from flax import struct

from dexguitar.world.guitar import N_STRINGS


@struct.dataclass
class NoteTally:
    run_ok: jnp.ndarray     # int32 (6,): current run of frames pressed at the target fret (left)
    best_ok: jnp.ndarray    # int32 (6,): longest such run in this note
    run_on: jnp.ndarray     # int32 (6,): current run of frames pressed at any fret
    best_on: jnp.ndarray    # int32 (6,)
    picks: jnp.ndarray      # int32 (6,): crossings of each string during this note
    errors: jnp.ndarray     # bool (6,): string tackled wrongly (not a target, repeated, out of order, not ready)
    held: jnp.ndarray       # int32 (6,): frames pressed correctly since the first pick, while unbroken; -1 = no pick
    held_best: jnp.ndarray  # int32 (6,): longest run of correct pressing that started with a correct pick
    press_at_pick: jnp.ndarray  # bool (6,): the string was pressed correctly when it was picked
    # the previous note's both-hands verdict, open while a hold that began with its pick runs on into this note
    prev_need: jnp.ndarray      # int32 (6,): frames of that hold still needed (0: nothing open)
    prev_goal: jnp.ndarray      # int32 (6,): the previous note's left goal (what the hold must keep)
    prev_tp: jnp.ndarray        # bool (6,): the previous note's strings handled correctly so far
    prev_picked: jnp.ndarray    # bool (6,): its predicted strings
    prev_targets: jnp.ndarray   # bool (6,): its target strings


def empty_tally() -> NoteTally:
    z = jnp.zeros(N_STRINGS, jnp.int32)
    f = jnp.zeros(N_STRINGS, bool)
    return NoteTally(z, z, z, z, z, f, z - 1, z, f, z, z, f, f, f)


def left_ok(press, goal):
    """Per string: is it in its expected state? press = detected fret (0 none); goal: k>0 press k, -1 open, 0 mute."""
    return jnp.where(goal > 0, press == goal, jnp.where(goal < 0, press == 0, True))


def update(tally: NoteTally, press, goal, picked=None, errors=None) -> NoteTally:
    """One control step. press: int (6,) detected frets; goal: int (6,) left goal of the note;
    picked: bool (6,) strings crossed by the pick this step; errors: bool (6,) strings tackled wrongly this step."""
    ok = (goal > 0) & (press == goal)
    run_ok = jnp.where(ok, tally.run_ok + 1, 0)
    on = press > 0
    run_on = jnp.where(on, tally.run_on + 1, 0)
    tally = tally.replace(run_ok=run_ok, best_ok=jnp.maximum(tally.best_ok, run_ok),
                          run_on=run_on, best_on=jnp.maximum(tally.best_on, run_on))
    if picked is None:
        return tally
    errors = jnp.zeros(N_STRINGS, bool) if errors is None else errors
    going = (tally.prev_need > 0) & left_ok(press, tally.prev_goal)        # the previous note's open holds
    prev_need = jnp.where(going, tally.prev_need - 1, 0)
    tally = tally.replace(prev_need=prev_need, prev_tp=tally.prev_tp | (going & (prev_need == 0)))
    state_ok = left_ok(press, goal)
    first = picked & (tally.picks == 0)
    held = jnp.where(first, jnp.where(state_ok, 1, 0),
                     jnp.where((tally.held > 0) & state_ok, tally.held + 1, jnp.where(tally.held > 0, 0, tally.held)))
    return tally.replace(picks=tally.picks + picked.astype(jnp.int32), errors=tally.errors | errors,
                         held=held, held_best=jnp.maximum(tally.held_best, held),
                         press_at_pick=tally.press_at_pick | (first & state_ok))


def hold_frames(frames):
    """Frames a hold must last in a note of `frames` frames: 2/3 of it, rounded up (3 * run >= 2 * frames)."""
    return (2 * frames + 2) // 3


def _picked_right(tally: NoteTally, targets):
    """bool (6,): target strings picked once and only once, with no error flagged (the right hand's true positives)."""
    return targets & (tally.picks == 1) & ~tally.errors


def holds_completed(before: NoteTally, after: NoteTally, frames, targets):
    """bool (6,): strings whose both-hands verdict became right in this step (`update` took `before` to `after`):
    a target picked once, cleanly, while pressed right, held so for 2/3 of its note's `frames` from the pick,
    within the note or, for the previous note's open holds, into this one (as `close` judges them)."""
    need = hold_frames(frames)
    within = _picked_right(after, targets) & after.press_at_pick & (after.held >= need) & (before.held < need)
    across = (before.prev_need > 0) & (after.prev_need == 0) & after.prev_tp
    return within | across


def _prf(tp, predicted, targets):
    tp, predicted, targets = (jnp.sum(x.astype(jnp.float32)) for x in (tp, predicted, targets))
    precision = jnp.where(predicted > 0, tp / jnp.maximum(predicted, 1.0), 1.0)
    recall = jnp.where(targets > 0, tp / jnp.maximum(targets, 1.0), 1.0)
    f1 = jnp.where(precision + recall > 0, 2 * precision * recall / jnp.maximum(precision + recall, 1e-9), 0.0)
    return jnp.stack([precision, recall, f1, tp, predicted, targets])


def close(tally: NoteTally, frames, goal, targets=None):
    """End of a note of `frames` frames. Returns (scores, the next note's tally): scores maps a hand to
    [precision, recall, f1, tp, predicted, targets] (float32 (6,)): "left" and, when picks were tallied (targets =
    the note's pick targets), "right", "both" (the previous note's, final now; all counts 0 before the first note)
    and "both_now" (this note judged within itself: final for a song's last note)."""
    need = 2 * frames                              # "at least 2/3 of the note": 3 * run >= 2 * frames
    out = {"left": _prf((goal > 0) & (3 * tally.best_ok >= need), (goal != 0) & (3 * tally.best_on >= need),
                        goal > 0)}
    fresh = empty_tally()
    if targets is not None:
        right_tp = _picked_right(tally, targets)
        picked = tally.picks > 0
        out["right"] = _prf(right_tp, picked, targets)
        good = right_tp & tally.press_at_pick
        done = good & (3 * tally.held_best >= need)
        open_ = good & ~done & (tally.held > 0)    # held since the pick up to the note's end, not yet long enough
        out["both"] = _prf(tally.prev_tp, tally.prev_picked, tally.prev_targets)
        out["both_now"] = _prf(done, picked, targets)
        fresh = fresh.replace(prev_need=jnp.where(open_, hold_frames(frames) - tally.held, 0), prev_goal=goal,
                              prev_tp=done, prev_picked=picked, prev_targets=targets)
    return out, fresh


def per_note_both(both, both_now):
    """Per-note both-hands scores from the values a recording holds at its note ends, in order (NumPy, (K, 6)):
    the end of note k+1 gives note k's final verdict; the last note's is its own ("both_now")."""
    return np.concatenate([both[1:], both_now[-1:]]) if len(both) else both
