"""A `Song` as static-shape arrays at the control rate, so an env can index it with traced frame numbers.

A `Timeline` is a pytree of jnp arrays only (no per-song Python ints), padded to a note capacity N and a frame
capacity T, so that one jitted env serves every song and songs of different lengths stack into one batch.

Conventions
-----------
* Time: the control rate is `fps` (60 Hz). A whole note is 4 quarter-note beats, so at `tempo` BPM the shortest
  note lasts `shortest * 4 * 60 * fps / tempo` frames (`shortest * 14400 / tempo` at 60 Hz). As in the paper
  (Limitations) the tempo is rounded so that this is a whole number of frames n, round-half-even as numpy does,
  and never below `min_frames` = 5: the authors' code keeps every note at least 5 frames long (reference §3.3), since
  shorter notes cannot be played by the hands at all. Example: 1/16 notes at 105 BPM -> 8.57 -> 9 frames -> the
  effective tempo is 100 BPM.
* Onsets round the cumulative position, onset[i] = round(cumsum(whole)[:i] * frames_per_whole), so rounding
  errors never accumulate. Onsets are computed in exact integer arithmetic on `ticks` (durations as integer
  multiples of one tick = 1 / ticks_per_whole of a whole note), so the jitted `retime` gives the same frames as
  `from_song`, ties included.
* Left-hand goal per string (`left`, the paper's convention, which flips the song's MUTE=-1 / OPEN=0): k > 0 press
  fret k; -1 open (played, must not be pressed); 0 don't care. A chord hint fills the strings the note mutes.
* Rows >= n_notes are padding (or notes dropped by `retime` for lack of frame capacity) and are never read as notes.
  Rows with ticks > 0 are the song's notes: `retime` uses all of them, so a truncated timeline can be re-timed back.
"""
from __future__ import annotations

import math
from fractions import Fraction
from typing import Sequence

import flax.struct
import jax
import jax.numpy as jnp
import numpy as np

from dexguitar.music.song import MUTE, OPEN, Song
from dexguitar.world.guitar import N_FRETS, N_STRINGS

GOAL_NOTES = 5                                # current note + 4 upcoming in the goal vectors
GOAL_SIZE = GOAL_NOTES * (N_STRINGS + 1)      # 35
TIMER_FRAMES = 20                             # timer encoding: -1 at 0 frames, 0 at 20, +1 at >= 40
MIN_TEMPO = 30.0                              # `random_tempo` never goes below this
_BIG = np.int32(2**30)


@flax.struct.dataclass
class Timeline:
    """One song (or a batch of songs, with a leading axis) at the control rate. N notes, T frames of capacity."""

    left: jax.Array         # int32 (N, 6): left-hand goal; k>0 press fret k, -1 open, 0 don't care
    pick: jax.Array         # bool (N, 6): strings the right hand picks (`Note.picked`)
    frets: jax.Array        # int32 (N, 6): what sounds, in the song's convention (MUTE -1, OPEN 0, fret k)
    effects: jax.Array      # int32 (N, 6): `Effect` flags
    whole: jax.Array        # float32 (N,): note length in whole notes (0 for padding)
    ticks: jax.Array        # int32 (N,): exact note length in ticks (0 for padding); whole = ticks / ticks_per_whole
    ticks_per_whole: jax.Array  # int32 (): tick resolution of this song
    onset: jax.Array        # int32 (N + 1,): first frame of each note; onset[n_notes:] == n_frames
    note_of_frame: jax.Array  # int32 (T,): note sounding at each frame; n_notes past the end
    n_notes: jax.Array      # int32 ()
    n_frames: jax.Array     # int32 ()
    tempo: jax.Array        # float32 (): effective tempo after rounding
    base_tempo: jax.Array   # float32 (): tempo asked for (as written in the song, or as given to `retime`)

    @property
    def note_capacity(self) -> int:
        return self.whole.shape[-1]

    @property
    def frame_capacity(self) -> int:
        return self.note_of_frame.shape[-1]


# ----------------------------------------------------------------------------------------------------- rounding

def shortest_frames(tempo, shortest_whole, fps: int = 60, min_frames: int = 5) -> int:
    """Frames of the shortest note after rounding: max(round(shortest * 240 * fps / tempo), min_frames, 1).

    The product is formed exactly (Fractions) and rounded half-to-even with numpy, so a tie such as 22.5 rounds the
    same way as the float32 computation in the jitted `retime`.
    """
    x = _fraction(shortest_whole) * 240 * fps / _fraction(tempo)
    return int(max(np.round(float(x)), min_frames, 1))


def frames_per_whole(tempo, shortest_whole, fps: int = 60, min_frames: int = 5) -> float:
    """Rounded frames per whole note: the shortest note gets a whole number of frames (see module docstring)."""
    return shortest_frames(tempo, shortest_whole, fps, min_frames) / float(_fraction(shortest_whole))


def effective_tempo(frames_per_whole_: float, fps: int = 60) -> float:
    """Tempo (BPM) at which a whole note lasts `frames_per_whole_` frames: 240 * fps / frames_per_whole."""
    return 240.0 * fps / frames_per_whole_


def _fraction(x) -> Fraction:
    return x if isinstance(x, (Fraction, int)) else Fraction(float(x))


def _round_ratio(c, n, s):
    """round(c * n / s) half-to-even, in int32 without forming c * n (c can be large): c = q s + r."""
    q, r = c // s, c % s
    p = r * n
    base = q * n + p // s
    rem2 = 2 * (p % s)
    up = (rem2 > s) | ((rem2 == s) & (base % 2 == 1))
    return base + up.astype(base.dtype)


# ----------------------------------------------------------------------------------------------------- building

def left_code(frets) -> np.ndarray:
    """Song convention (MUTE -1, OPEN 0, fret k) -> left-hand goal convention (0 don't care, -1 open, k)."""
    f = np.asarray(frets)
    return np.where(f > 0, f, np.where(f == OPEN, -1, 0)).astype(np.int32)


def from_song(song: Song, *, note_capacity: int | None = None, frame_capacity: int | None = None,
              fps: int = 60, min_frames: int = 5) -> Timeline:
    """Build a `Timeline` (numpy, exact) and move it to jnp. Capacities default to the exact size."""
    notes = song.notes
    n_notes = len(notes)
    den = math.lcm(*(n.duration.denominator for n in notes))
    nums = [n.duration.numerator * (den // n.duration.denominator) for n in notes]
    g = math.gcd(*nums)
    ticks = np.array([x // g for x in nums], dtype=np.int64)
    tpw = den // g                               # one tick = 1/tpw whole note; the gcd keeps ticks small
    s = int(ticks.min())
    n_short = shortest_frames(song.tempo, Fraction(s, tpw), fps, min_frames)
    n_slow = shortest_frames(MIN_TEMPO, Fraction(s, tpw), fps, min_frames)  # largest n `retime` should see
    if ticks.sum() >= 2**31 or s * n_slow >= 2**31 or s * 240 * fps >= 2**24 or tpw * n_slow >= 2**24:
        # int32 ticks for `retime`, and exact float32 for its rounding of the shortest note
        raise ValueError(f"song durations too fine for int32 ticks (ticks per whole {tpw}, shortest {s} ticks)")
    cum = np.concatenate([[0], np.cumsum(ticks)])
    onset = np.array([round(Fraction(int(c) * n_short, s)) for c in cum], dtype=np.int64)  # round half-even
    n_frames = int(onset[-1])

    N = n_notes if note_capacity is None else int(note_capacity)
    T = n_frames if frame_capacity is None else int(frame_capacity)
    if N < n_notes:
        raise ValueError(f"note capacity {N} < {n_notes} notes in the song")
    if T < n_frames:
        raise ValueError(f"frame capacity {T} < {n_frames} frames in the song")

    frets = np.full((N, N_STRINGS), MUTE, np.int32)
    frets[:n_notes] = [n.frets for n in notes]
    left = left_code(frets)
    for i, n in enumerate(notes):
        if n.chord is not None:
            left[i] = np.where(frets[i] == MUTE, left_code(n.chord), left[i])
    pick = np.zeros((N, N_STRINGS), bool)
    pick[:n_notes] = [n.picked for n in notes]
    effects = np.zeros((N, N_STRINGS), np.int32)
    effects[:n_notes] = [[int(e) for e in n.effects] for n in notes]
    whole = np.zeros(N, np.float32)
    whole[:n_notes] = [float(n.duration) for n in notes]
    ticks_pad = np.zeros(N, np.int32)
    ticks_pad[:n_notes] = ticks
    onset_pad = np.full(N + 1, n_frames, np.int32)
    onset_pad[:n_notes + 1] = onset
    t = np.arange(T)
    nof = np.where(t < n_frames, np.searchsorted(onset_pad, t, side="right") - 1, n_notes).astype(np.int32)
    tempo = np.float32(240 * fps * s) / np.float32(tpw * n_short)   # same float32 op as `retime`

    return Timeline(
        left=jnp.asarray(left), pick=jnp.asarray(pick), frets=jnp.asarray(frets), effects=jnp.asarray(effects),
        whole=jnp.asarray(whole), ticks=jnp.asarray(ticks_pad), ticks_per_whole=jnp.int32(tpw),
        onset=jnp.asarray(onset_pad), note_of_frame=jnp.asarray(nof), n_notes=jnp.int32(n_notes),
        n_frames=jnp.int32(n_frames), tempo=jnp.float32(tempo), base_tempo=jnp.float32(song.tempo))


def pad(tl: Timeline, note_capacity: int, frame_capacity: int) -> Timeline:
    """Grow one (unbatched) timeline to larger capacities with neutral padding."""
    N, T = tl.note_capacity, tl.frame_capacity
    dn, dt = note_capacity - N, frame_capacity - T
    if dn < 0 or dt < 0:
        raise ValueError(f"cannot shrink a timeline from ({N}, {T}) to ({note_capacity}, {frame_capacity})")

    def rows(x, value):
        return jnp.pad(x, [(0, dn)] + [(0, 0)] * (x.ndim - 1), constant_values=value)

    return tl.replace(
        left=rows(tl.left, 0), pick=rows(tl.pick, False), frets=rows(tl.frets, MUTE), effects=rows(tl.effects, 0),
        whole=rows(tl.whole, 0), ticks=rows(tl.ticks, 0),
        onset=jnp.concatenate([tl.onset, jnp.full(dn, tl.n_frames, jnp.int32)]),
        note_of_frame=jnp.concatenate([tl.note_of_frame, jnp.full(dt, tl.n_notes, jnp.int32)]))


def stack(timelines: Sequence[Timeline]) -> Timeline:
    """Pad every timeline to the largest N and T and stack them along a new leading batch axis."""
    N = max(t.note_capacity for t in timelines)
    T = max(t.frame_capacity for t in timelines)
    padded = [pad(t, N, T) for t in timelines]
    return jax.tree.map(lambda *xs: jnp.stack(xs), *padded)


# ----------------------------------------------------------------------------------------------------- lookup (jit)

def note_at(tl: Timeline, frame) -> jax.Array:
    """Index of the note sounding at `frame` (n_notes at or past the end; frames < 0 count as frame 0)."""
    frame = jnp.asarray(frame, jnp.int32)
    i = tl.note_of_frame[jnp.clip(frame, 0, tl.frame_capacity - 1)]
    return jnp.where(frame >= tl.n_frames, tl.n_notes, i).astype(jnp.int32)


def frames_left(tl: Timeline, frame) -> jax.Array:
    """Frames until the current note ends (>= 1 inside the song, 0 past the end)."""
    frame = jnp.asarray(frame, jnp.int32)
    i = note_at(tl, frame)
    end = tl.onset[jnp.minimum(i + 1, tl.note_capacity)]
    return jnp.where(i < tl.n_notes, end - frame, 0).astype(jnp.int32)


def timer_code(frames) -> jax.Array:
    """Frames -> [-1, 1]: clip(frames / 20, 0, 2) - 1."""
    return jnp.clip(jnp.asarray(frames, jnp.float32) / TIMER_FRAMES, 0.0, 2.0) - 1.0


def _window(tl: Timeline, frame):
    """Rows, validity and timer codes of the GOAL_NOTES notes starting at the current one."""
    i = note_at(tl, frame)
    j = i + jnp.arange(GOAL_NOTES)
    valid = j < tl.n_notes
    rows = jnp.minimum(j, tl.note_capacity - 1)
    dur = tl.onset[rows + 1] - tl.onset[rows]
    frames = jnp.where(valid, dur, 0).at[0].set(frames_left(tl, frame))
    return rows, valid, timer_code(frames)


def fret_code(k) -> jax.Array:
    """Left-hand goal value of a string: k > 0 -> k/22, open (-1) -> -1, don't care (0) -> 0."""
    k = jnp.asarray(k, jnp.float32)
    return jnp.where(k > 0, k / N_FRETS, k)


def goal_vector(values, valid, timer) -> jax.Array:
    """(5, 6) per-string values + (5,) timer codes -> the (35,) note-major goal; invalid notes are zeros."""
    values = jnp.where(valid[:, None], values, 0.0)
    return jnp.concatenate([values, timer[:, None]], axis=1).reshape(GOAL_SIZE).astype(jnp.float32)


def left_goal(tl: Timeline, frame) -> jax.Array:
    """float32 (35,): 5 notes x [6 fret values, timer], note-major.

    Fret value: k > 0 -> k/22, open -> -1, don't care -> 0. The reference encodes g/12, which wraps around at fret
    12 (fret 12 looks like open); we use this monotone map into [-1, 1] instead. Timer: slot 0 the frames left in the
    current note, slots 1-4 the note's full duration; see `timer_code`. Past the end: zeros and timer -1.
    """
    rows, valid, timer = _window(tl, frame)
    return goal_vector(fret_code(tl.left[rows]), valid, timer)


def right_goal(tl: Timeline, frame, done=None) -> jax.Array:
    """float32 (35,): 5 notes x [6 pick flags, timer]; the current note's flags exclude the strings in `done`
    (bool (6,), strings already picked during this note), so a picked string stops asking to be picked."""
    rows, valid, timer = _window(tl, frame)
    flags = tl.pick[rows]
    if done is not None:
        flags = flags.at[0].set(flags[0] & ~jnp.asarray(done, bool))
    return goal_vector(flags.astype(jnp.float32), valid, timer)


# ------------------------------------------------------------------------------------------ augmentation (jit)

def shift(tl: Timeline, offset) -> Timeline:
    """Move every pressed fret (goal, chord-derived and sounding) by `offset`, keeping the chord shape.

    Open and muted strings are unchanged. Not clipped: take `offset` from `shift_range` to stay within 1..22.
    """
    offset = jnp.asarray(offset, jnp.int32)
    return tl.replace(left=jnp.where(tl.left > 0, tl.left + offset, tl.left),
                      frets=jnp.where(tl.frets > 0, tl.frets + offset, tl.frets))


def shift_range(tl: Timeline):
    """(lo, hi): the offsets that keep every pressed fret of the song's notes within 1..22; (0, 0) if none."""
    song = (tl.ticks > 0)[:, None]
    vals = jnp.concatenate([tl.left, tl.frets], axis=1)
    pressed = song & (vals > 0)
    lo_fret = jnp.min(jnp.where(pressed, vals, _BIG))
    hi_fret = jnp.max(jnp.where(pressed, vals, 0))
    any_ = jnp.any(pressed)
    return (jnp.where(any_, 1 - lo_fret, 0).astype(jnp.int32),
            jnp.where(any_, N_FRETS - hi_fret, 0).astype(jnp.int32))


def random_shift(key, tl: Timeline) -> Timeline:
    """Shift by an offset drawn uniformly from `shift_range` (both ends included)."""
    lo, hi = shift_range(tl)
    return shift(tl, jax.random.randint(key, (), lo, hi + 1))


def retime(tl: Timeline, tempo, *, fps: int = 60, min_frames: int = 5) -> Timeline:
    """Recompute onsets, note_of_frame, n_frames and tempo for a new tempo (same rounding as `from_song`).

    The shortest note is taken over all the song's notes (ticks > 0). Shapes stay fixed: if the song no longer fits
    in T frames, n_frames = min(frames, T) and notes starting at or past T are dropped (n_notes shrinks, the last
    kept note is cut at T); their rows stay, so re-timing faster brings them back. `base_tempo` becomes `tempo`.
    For an integer tempo the result equals `from_song` of the song at that tempo. The int32 arithmetic is checked by
    `from_song` for tempos >= 30 BPM (`MIN_TEMPO`).
    """
    N, T = tl.note_capacity, tl.frame_capacity
    tempo = jnp.asarray(tempo, jnp.float32)
    song = tl.ticks > 0
    n_song = jnp.sum(song).astype(jnp.int32)
    s = jnp.min(jnp.where(song, tl.ticks, _BIG))
    x = (s * (240 * fps)).astype(jnp.float32) / (tl.ticks_per_whole.astype(jnp.float32) * tempo)
    n = jnp.maximum(jnp.round(x), max(min_frames, 1)).astype(jnp.int32)
    cum = jnp.concatenate([jnp.zeros(1, jnp.int32), jnp.cumsum(jnp.where(song, tl.ticks, 0))])
    onset = _round_ratio(cum, n, s)
    n_frames = jnp.minimum(onset[n_song], T)
    idx = jnp.arange(N + 1)
    n_notes = jnp.sum((idx[:N] < n_song) & (onset[:N] < T)).astype(jnp.int32)
    onset = jnp.where(idx < n_notes, onset, n_frames).astype(jnp.int32)
    t = jnp.arange(T)
    nof = jnp.where(t < n_frames, jnp.searchsorted(onset, t, side="right") - 1, n_notes).astype(jnp.int32)
    eff = (s * (240 * fps)).astype(jnp.float32) / (tl.ticks_per_whole * n).astype(jnp.float32)
    return tl.replace(onset=onset, note_of_frame=nof, n_notes=n_notes, n_frames=n_frames.astype(jnp.int32),
                      tempo=eff, base_tempo=tempo)


def random_tempo(key, tl: Timeline, max_delta: int = 20, *, fps: int = 60, min_frames: int = 5) -> Timeline:
    """Re-time at base_tempo + U{-max_delta..max_delta} BPM, never below 30 BPM."""
    delta = jax.random.randint(key, (), -max_delta, max_delta + 1)
    tempo = jnp.maximum(tl.base_tempo + delta, MIN_TEMPO)
    return retime(tl, tempo, fps=fps, min_frames=min_frames)
