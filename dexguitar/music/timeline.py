"""A `Song` as static-shape arrays, so that jitted code indexes it with traced note numbers.

A `Timeline` is a pytree of jnp arrays only (no per-song Python ints), padded to a note capacity N, so that one
jitted env serves every song and songs of different lengths stack into one batch. Which notes are being played, and
for how many frames each, is the song cursor's business (`cursor`): a window of notes re-timed and shifted per episode.

Conventions
-----------
* Time: the control rate is `fps` (60 Hz). A whole note is 4 quarter-note beats, so at `tempo` BPM the shortest
  note lasts `shortest * 4 * 60 * fps / tempo` frames (`shortest * 14400 / tempo` at 60 Hz). As in the paper
  (Limitations) the tempo is rounded so that this is a whole number of frames n, round-half-even as numpy does,
  and never below `min_frames` = 5: the authors' code keeps every note at least 5 frames long (reference §3.3), since
  shorter notes cannot be played by the hands at all. Example: 1/16 notes at 105 BPM -> 8.57 -> 9 frames -> the
  effective tempo is 100 BPM.
* Onsets round the cumulative position, onset[i] = round(cumsum(whole)[:i] * frames_per_whole), so rounding
  errors never accumulate. Durations are kept exactly as `ticks` (integer multiples of one tick = 1/ticks_per_whole
  of a whole note, ticks_per_whole = the least common multiple of the denominators), so that the jitted
  `cursor.note_frames` re-times a song in int32 to the same frames as `from_song`, ties included.
* `from_song` refuses songs outside the limits of `timing` (tempo, shortest note, length, tick resolution).
* Left-hand goal per string (`left`, the paper's convention, which flips the song's MUTE=-1 / OPEN=0): k > 0 press
  fret k; -1 open (played, must not be pressed); 0 don't care. A chord hint fills the strings the note mutes.
* Rows >= n_notes are padding (ticks 0) and are never read as notes.
"""
from __future__ import annotations

from fractions import Fraction
from typing import Any, Sequence

import flax.struct
import jax
import jax.numpy as jnp
import numpy as np

from dexguitar.music.song import MUTE, OPEN, Song
from dexguitar.music.timing import (  # noqa: F401 (the rounding helpers are part of this module's interface)
    MIN_TEMPO, effective_tempo, frames_per_whole, shortest_frames, ticks_per_whole, validate)
from dexguitar.world.guitar import N_FRETS, N_STRINGS

GOAL_NOTES = 5                                # current note + 4 upcoming in the goal vectors
GOAL_SIZE = GOAL_NOTES * (N_STRINGS + 1)      # 35
TIMER_FRAMES = 20                             # timer encoding: -1 at 0 frames, 0 at 20, +1 at >= 40


@flax.struct.dataclass
class Timeline:
    """One song (numpy arrays, from `from_song`) or a batch of songs (device arrays with a leading axis, from `stack`
    or `batch`) as N note rows."""

    left: jax.Array         # int32 (N, 6): left-hand goal; k>0 press fret k, -1 open, 0 don't care
    pick: jax.Array         # bool (N, 6): strings the right hand picks (`Note.picked`)
    frets: jax.Array        # int32 (N, 6): what sounds, in the song's convention (MUTE -1, OPEN 0, fret k)
    effects: jax.Array      # int32 (N, 6): `Effect` flags
    whole: jax.Array        # float32 (N,): note length in whole notes (0 for padding)
    ticks: jax.Array        # int32 (N,): exact note length in ticks (0 for padding); whole = ticks / ticks_per_whole
    ticks_per_whole: jax.Array  # int32 (): tick resolution of this song
    onset: jax.Array        # int32 (N + 1,): first frame of each note at the written tempo; onset[n_notes:] == n_frames
    n_notes: jax.Array      # int32 ()
    n_frames: jax.Array     # int32 (): length at the written tempo, after rounding
    tempo: jax.Array        # float32 (): effective tempo after rounding
    base_tempo: jax.Array   # float32 (): tempo as written in the song
    plan: Any = None        # `planner.Plan` of the left hand, frame-indexed (`EnvConfig.feedforward`)
    plan_right: Any = None  # ... of the right hand (`EnvConfig.right_feedforward`)

    @property
    def note_capacity(self) -> int:
        return self.whole.shape[-1]


# ----------------------------------------------------------------------------------------------------- building

def left_code(frets) -> np.ndarray:
    """Song convention (MUTE -1, OPEN 0, fret k) -> left-hand goal convention (0 don't care, -1 open, k)."""
    f = np.asarray(frets)
    return np.where(f > 0, f, np.where(f == OPEN, -1, 0)).astype(np.int32)


def from_song(song: Song, *, note_capacity: int | None = None, fps: int = 60, min_frames: int = 5) -> Timeline:
    """Build a `Timeline` of numpy arrays (exact; `stack` / `batch` move batches to the device, where their fixed
    capacities keep the programs that read them from being compiled again). The capacity defaults to the number of
    notes.

    A song outside the limits of `timing.validate` raises `SongError` (naming the note or the tempo)."""
    validate(song, fps=fps, min_frames=min_frames)
    notes = song.notes
    n_notes = len(notes)
    tpw = ticks_per_whole([n.duration for n in notes])   # one tick = 1/tpw whole note
    ticks = np.array([int(n.duration * tpw) for n in notes], dtype=np.int64)
    s = int(ticks.min())
    n_short = shortest_frames(song.tempo, Fraction(s, tpw), fps, min_frames)
    cum = np.concatenate([[0], np.cumsum(ticks)])
    onset = np.array([round(Fraction(int(c) * n_short, s)) for c in cum], dtype=np.int64)  # round half-even
    n_frames = int(onset[-1])

    N = n_notes if note_capacity is None else int(note_capacity)
    if N < n_notes:
        raise ValueError(f"note capacity {N} < {n_notes} notes in the song")

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
    tempo = effective_tempo(n_short * tpw / s, fps)

    return Timeline(
        left=left, pick=pick, frets=frets, effects=effects, whole=whole, ticks=ticks_pad,
        ticks_per_whole=np.int32(tpw), onset=onset_pad, n_notes=np.int32(n_notes), n_frames=np.int32(n_frames),
        tempo=np.float32(tempo), base_tempo=np.float32(song.tempo))


def pad(tl: Timeline, note_capacity: int) -> Timeline:
    """Grow one (unbatched) timeline to a larger note capacity with neutral padding."""
    dn = note_capacity - tl.note_capacity
    if dn < 0:
        raise ValueError(f"cannot shrink a timeline from {tl.note_capacity} to {note_capacity} notes")

    def rows(x, value):         # on the host: no device computation, so nothing is compiled for a new size
        x = np.asarray(x)
        return np.pad(x, [(0, dn)] + [(0, 0)] * (x.ndim - 1), constant_values=np.asarray(value))

    return tl.replace(
        left=rows(tl.left, 0), pick=rows(tl.pick, False), frets=rows(tl.frets, MUTE), effects=rows(tl.effects, 0),
        whole=rows(tl.whole, 0), ticks=rows(tl.ticks, 0), onset=rows(tl.onset, tl.n_frames))


def stack(timelines: Sequence[Timeline]) -> Timeline:
    """Pad every timeline to the largest N and stack them along a new leading batch axis."""
    N = max(t.note_capacity for t in timelines)
    return _stack([pad(t, N) for t in timelines])


def _stack(timelines: Sequence[Timeline]) -> Timeline:
    """Stack equal-capacity timelines along a new axis, on the host."""
    # device_put, not jnp.asarray: a plain transfer, which compiles nothing (jnp.asarray compiles a small program per
    # shape, again after every `learn.tracing.fresh_trace`)
    return jax.tree.map(lambda *xs: jax.device_put(np.stack([np.asarray(x) for x in xs])), *timelines)


# ----------------------------------------------------------------------------------------------------- goal codes

def timer_code(frames) -> jax.Array:
    """Frames -> [-1, 1]: clip(frames / 20, 0, 2) - 1."""
    return jnp.clip(jnp.asarray(frames, jnp.float32) / TIMER_FRAMES, 0.0, 2.0) - 1.0


def fret_code(k) -> jax.Array:
    """Left-hand goal value of a string: k > 0 -> k/22, open (-1) -> -1, don't care (0) -> 0.

    The reference encodes g/12, which wraps around at fret 12 (fret 12 looks like open); this monotone map into
    [-1, 1] does not."""
    k = jnp.asarray(k, jnp.float32)
    return jnp.where(k > 0, k / N_FRETS, k)


def goal_vector(values, valid, timer) -> jax.Array:
    """(5, 6) per-string values + (5,) timer codes -> the (35,) note-major goal; invalid notes are zeros."""
    values = jnp.where(valid[:, None], values, 0.0)
    return jnp.concatenate([values, timer[:, None]], axis=1).reshape(GOAL_SIZE).astype(jnp.float32)


# ------------------------------------------------------------------------------------------ batches of fixed size

# The authors' longest song has 337 notes: with 256 it alone needed its own programs (75 s each on an H100).
MIN_NOTES = 512


def capacity(n: int, least: int) -> int:
    """The power of two >= max(n, least): song batches grow in a few sizes, so programs compiled for one size serve
    every song set that fits it."""
    return 1 << max(int(n), int(least), 1).__sub__(1).bit_length()


def batch(timelines: Sequence[Timeline], *, songs: int | None = None, notes: int | None = None) -> Timeline:
    """Stack timelines into a batch of fixed capacities (default: powers of two, at least `MIN_NOTES`), filling up
    with empty songs, which have no notes and are never drawn."""
    songs = songs or capacity(len(timelines), 1)
    notes = notes or capacity(max(t.note_capacity for t in timelines), MIN_NOTES)
    if len(timelines) > songs:
        raise ValueError(f"{len(timelines)} songs do not fit a batch of {songs}")
    padded = [pad(t, notes) for t in timelines]
    empty = jax.tree.map(lambda x: np.zeros(np.shape(x), np.asarray(x).dtype), padded[0]).replace(
        ticks_per_whole=np.int32(1), base_tempo=np.float32(120.0), tempo=np.float32(120.0))
    return _stack(padded + [empty] * (songs - len(padded)))


def as_batch(songs) -> Timeline:
    """A song batch: a list of `Song`s or timelines stacked, a batch as it is."""
    if isinstance(songs, (list, tuple)):
        return stack([s if isinstance(s, Timeline) else from_song(s) for s in songs])
    return songs
