"""The song cursor: which notes a hand is playing and how far into the current one it is.

A `Window` is a rest followed by consecutive notes of one song of a `Timeline` batch, each with its duration in
control frames; a `Cursor` is a window, the row being played and the frames elapsed in it. Everything the envs need
of a song goes through here: sampling a training window (random song, start and length, fret shift keeping the chord
shape, tempo change, notes capped in length: reference §3.4), the whole song for evaluation, the tempo rounding that
makes the shortest note a whole number of frames (see `timeline`), and the goal vectors of the next five notes.
All functions are pure and jit/vmap-able; the songs are an argument, so one compiled program serves every song set
of the same capacities.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

from dexguitar.music import timeline as TL
from dexguitar.world.guitar import N_FRETS, N_STRINGS


@struct.dataclass
class Window:
    """The notes being played: rows 0 .. n-1 are valid, row 0 is the grace rest."""

    left: jnp.ndarray      # int32 (W, 6) left-hand goal code (k > 0 press fret k, -1 open, 0 don't care)
    pick: jnp.ndarray      # bool (W, 6) strings the right hand picks
    frets: jnp.ndarray     # int32 (W, 6) what sounds (MUTE -1, OPEN 0, fret k)
    dur: jnp.ndarray       # int32 (W,) frames of each row
    n: jnp.ndarray         # int32 () valid rows
    song: jnp.ndarray      # int32 () index of the song in the batch
    first: jnp.ndarray     # int32 () song note index of row 1
    start: jnp.ndarray     # int32 () song frame of row 0 (the frame index of a song's `plan`)


@struct.dataclass
class Cursor:
    window: Window
    note: jnp.ndarray          # int32 row being played
    note_frame: jnp.ndarray    # int32 frames elapsed in it

    @property
    def over(self):
        """Every row of the window has been played."""
        return self.note >= self.window.n


def start(window: Window) -> Cursor:
    return Cursor(window, jnp.int32(0), jnp.int32(0))


def song_weights(songs: TL.Timeline):
    """Log-probabilities of drawing each song of a batch: proportional to its notes; padding songs never."""
    n = songs.n_notes.astype(jnp.float32)
    return jnp.where(n > 0, jnp.log(jnp.maximum(n, 1.0)), -jnp.inf)


def note_frames(ticks, valid, ticks_per_whole, tempo, min_frames: int):
    """Frames of each note at `tempo`: the shortest valid note is rounded to a whole number of frames (at least
    `min_frames`), the rest follow from exact integer onsets, so rounding errors never accumulate (`timeline`)."""
    shortest = jnp.min(jnp.where(valid, ticks, jnp.iinfo(jnp.int32).max))
    x = (shortest * (240 * 60)).astype(jnp.float32) / (ticks_per_whole.astype(jnp.float32) * tempo)
    n_short = jnp.maximum(jnp.round(x), min_frames).astype(jnp.int32)
    cum = jnp.concatenate([jnp.zeros(1, jnp.int32), jnp.cumsum(jnp.where(valid, ticks, 0))])
    return jnp.where(valid, jnp.diff(round_ratio(cum, n_short, shortest)), 0)


def round_ratio(c, n, s):
    """round(c * n / s) half-to-even in int32 without forming c * n (c can be large): c = q s + r. Matches the exact
    Fraction rounding of `timeline.from_song`."""
    q, r = c // s, c % s
    p = r * n
    base = q * n + p // s
    rem2 = 2 * (p % s)
    up = (rem2 > s) | ((rem2 == s) & (base % 2 == 1))
    return base + up.astype(base.dtype)


def shift_frets(left, frets, valid, key, prob: float):
    """With probability `prob`, move every pressed fret by one offset that keeps them all on the neck (the chord
    shape is kept; open and muted strings stay)."""
    k_p, k_offset = jax.random.split(key)
    pressed = valid[:, None] & (left > 0)
    lo = 1 - jnp.min(jnp.where(pressed, left, N_FRETS))
    hi = N_FRETS - jnp.max(jnp.where(pressed, left, 1))
    offset = jnp.where(jax.random.uniform(k_p) < prob, jax.random.randint(k_offset, (), lo, hi + 1), 0)
    offset = jnp.where(jnp.any(pressed), offset, 0)
    return jnp.where(left > 0, left + offset, left), jnp.where(frets > 0, frets + offset, frets)


def sample_window(songs: TL.Timeline, key, capacity: int, *, sequential: bool, window_notes=(10, 20),
                  rest_frames: int = 5, max_note_frames: int = 50, min_frames: int = 5, shift_prob: float = 0.0,
                  tempo_prob: float = 0.0, tempo_delta: int = 20, fill_strum_gaps: bool = True,
                  even_notes: bool = False, song=None) -> Window:
    """A window of `capacity` rows. Training: a rest + n-1 notes (n ~ U{window_notes}) of a random song from a
    random start, augmented. Sequential: a rest, then song `song` whole from its start (the authors' grace rest:
    the first note is not judged before the hand has had time to move).

    The paper's start is uniform over the starts of whole windows of m = n-1 notes, so a song's first and last notes
    lie in 1/m as many windows as its middle notes. `even_notes` draws the start over the m-1 positions before the
    song as well and cuts the window at the song's ends: every note then lies in as many windows as any other."""
    k_song, k_len, k_start, k_shift, k_tempo, k_p = jax.random.split(key, 6)
    if song is None:
        song = jax.random.categorical(k_song, song_weights(songs))
    song = jnp.asarray(song, jnp.int32)
    n_song = songs.n_notes[song]
    if sequential:
        n, first = n_song, jnp.int32(0)
    else:
        n = jnp.minimum(jax.random.randint(k_len, (), window_notes[0], window_notes[1]) - 1, n_song)
        if even_notes:                     # starts 1-m .. N-1 (n is m here), the window cut to the song
            at = jax.random.randint(k_start, (), 1 - n, n_song)
            first = jnp.maximum(at, 0)
            n = jnp.minimum(at + n, n_song) - first
        else:
            first = jax.random.randint(k_start, (), 0, jnp.maximum(n_song - n, 0) + 1)
    valid = jnp.arange(capacity - 1) < n
    idx = jnp.clip(first + jnp.arange(capacity - 1), 0, songs.left.shape[1] - 1)

    def take(x, fill):
        return jnp.where(valid.reshape((-1,) + (1,) * (x.ndim - 2)), x[song][idx], fill)
    left, pick, frets, ticks = take(songs.left, 0), take(songs.pick, False), take(songs.frets, -1), take(
        songs.ticks, 0)
    tempo = songs.base_tempo[song]
    if not sequential:
        bump = jax.random.randint(k_tempo, (), -tempo_delta, tempo_delta + 1)
        tempo = jnp.where(jax.random.uniform(k_p) < tempo_prob, jnp.maximum(tempo + bump, TL.MIN_TEMPO), tempo)
    dur = note_frames(ticks, valid, songs.ticks_per_whole[song], tempo, min_frames)
    start = jnp.int32(0)
    if songs.plan is not None or songs.plan_right is not None:    # a planned song's frames: nothing shifted or capped
        onset = songs.onset[song]
        dur = jnp.where(valid, jnp.diff(onset)[idx], 0)
        start = onset[jnp.minimum(first, onset.shape[0] - 1)]
    elif not sequential:
        dur = jnp.minimum(dur, max_note_frames)
        left, frets = shift_frets(left, frets, valid, k_shift, shift_prob)

    def rest(x, v):
        return jnp.concatenate([jnp.full((1,) + x.shape[1:], v, x.dtype), x])
    left, pick, frets, dur = rest(left, 0), rest(pick, False), rest(frets, -1), rest(dur, rest_frames)
    if fill_strum_gaps:       # strings between the outer targets of a strum are targets too (reference §3.6)
        i = jnp.arange(N_STRINGS)
        lo = jnp.min(jnp.where(pick, i, N_STRINGS), axis=1, keepdims=True)
        hi = jnp.max(jnp.where(pick, i, -1), axis=1, keepdims=True)
        pick = (i >= lo) & (i <= hi)
    return Window(left, pick, frets, dur.astype(jnp.int32), (n + 1).astype(jnp.int32), song, first, start)


# ------------------------------------------------------------------------------------------------ goals

def rows(cursor: Cursor):
    """Rows note .. note+4 of the window (clipped) and their validity."""
    j = cursor.note + jnp.arange(TL.GOAL_NOTES)
    capacity = cursor.window.dur.shape[-1]
    return jnp.minimum(j, capacity - 1), j < cursor.window.n


def timers(cursor: Cursor, rows_, valid):
    """Timer codes: frames left in the current note, then the upcoming notes' full durations."""
    frames = jnp.where(valid, cursor.window.dur[rows_], 0).at[0].add(-cursor.note_frame)
    return TL.timer_code(jnp.where(valid, frames, 0))


def left_goal(cursor: Cursor):
    """(35,) the left hand's goal: 5 notes x (6 fret codes + timer)."""
    r, valid = rows(cursor)
    return TL.goal_vector(TL.fret_code(cursor.window.left[r]), valid, timers(cursor, r, valid))


def right_goal(cursor: Cursor, done):
    """(35,) the right hand's goal: 5 notes x (6 pick flags + timer); the current note's strings in `done` (already
    picked) no longer ask to be picked."""
    r, valid = rows(cursor)
    flags = cursor.window.pick[r]
    flags = flags.at[0].set(flags[0] & ~done)
    return TL.goal_vector(flags.astype(jnp.float32), valid, timers(cursor, r, valid))


def current(cursor: Cursor):
    """(left-hand goal code (6,), pick targets (6,), frames of the current row) of the note being played."""
    w, i = cursor.window, jnp.minimum(cursor.note, cursor.window.dur.shape[-1] - 1)
    return w.left[i], w.pick[i] & ~cursor.over, w.dur[i]


def song_frame(cursor: Cursor):
    """The song frame being played (the row of a `Plan`): the window's start + the frames of the rows played."""
    w = cursor.window
    played = jnp.sum(jnp.where(jnp.arange(w.dur.shape[-1]) < cursor.note, w.dur, 0))
    return w.start + played + cursor.note_frame


def advance(cursor: Cursor):
    """One frame on: (cursor, the current note ended with this frame)."""
    _, _, dur = current(cursor)
    frame = cursor.note_frame + 1
    end = frame >= dur
    return cursor.replace(note=jnp.where(end, cursor.note + 1, cursor.note),
                          note_frame=jnp.where(end, 0, frame)), end
