"""Whole notes -> control frames, exactly, and the limits of the songs dexguitar accepts.

A song is played at the control rate `fps` (60 Hz) with its tempo rounded so that the shortest note lasts a whole
number of frames, at least `min_frames` (5): see `timeline` for the rounding. Durations are counted in integer ticks,
one tick = 1/ticks_per_whole of a whole note with ticks_per_whole the least common multiple of the denominators, so
that the envs' note windows (`cursor.note_frames`, jitted) compute onsets in int32.

`validate` refuses a song, with a `SongError` naming the note or the tempo and why, when
* the tempo lies outside TEMPO_RANGE (20..400 quarter-note BPM);
* a note lasts less than one frame at the written tempo. The shortest note is stretched to `min_frames`, so this
  bounds the slow-down to 5x; a 1/100000 note at 120 BPM (0.0012 frames) would slow the song 4000x;
* the song lasts more than MAX_SECONDS after rounding (at 60 Hz: 108,000 frames);
* its durations need a tick so fine that the int32 onset arithmetic would overflow (or the float32 rounding of the
  shortest note would not be exact), e.g. notes of 1/7, 1/11, ..., 1/23 (one tick = 1/7436429 of a whole note).
Every tab reader validates the song it returns; `timeline.from_song` validates songs built in code.
"""
from __future__ import annotations

import math
from fractions import Fraction
from pathlib import Path
from typing import Sequence

import numpy as np

from dexguitar.music.song import Song, SongError

TEMPO_RANGE = (20.0, 400.0)   # BPM: from below the slowest marking (grave, ~25-45) to 400, which even in 1/4 notes
                              # is 6.7 notes a second; 1e9 BPM is a typo, not a tempo
MIN_TEMPO = 30.0              # the training windows (`cursor.sample_window`) never re-time below this
MAX_SECONDS = 30 * 60         # longer than any piece played in one go (the longest rock songs run ~25 min)
_INT32 = 2**31                # onsets and tick products are int32 in the envs' windows (`cursor.note_frames`)
_FLOAT32_EXACT = 2**24        # integers up to this are exact in float32 (the rounding of the shortest note)


def ticks_per_whole(durations: Sequence[Fraction]) -> int:
    """The least common multiple of the denominators: every duration is a whole number of 1/ticks_per_whole."""
    return math.lcm(*(Fraction(d).denominator for d in durations))


def shortest_frames(tempo, shortest_whole, fps: int = 60, min_frames: int = 5) -> int:
    """Frames of the shortest note after rounding: max(round(shortest * 240 * fps / tempo), min_frames, 1).

    The product is formed exactly (Fractions) and rounded half-to-even, so a tie such as 22.5 rounds the same way
    as the float32 computation in the jitted `cursor.note_frames`.
    """
    x = _fraction(shortest_whole) * 240 * fps / _fraction(tempo)
    return int(max(np.round(float(x)), min_frames, 1))


def frames_per_whole(tempo, shortest_whole, fps: int = 60, min_frames: int = 5) -> float:
    """Rounded frames per whole note: the shortest note gets a whole number of frames (see `timeline`)."""
    return shortest_frames(tempo, shortest_whole, fps, min_frames) / float(_fraction(shortest_whole))


def effective_tempo(frames_per_whole_: float, fps: int = 60) -> float:
    """Tempo (BPM) at which a whole note lasts `frames_per_whole_` frames: 240 * fps / frames_per_whole."""
    return 240.0 * fps / frames_per_whole_


def _fraction(x) -> Fraction:
    return x if isinstance(x, (Fraction, int)) else Fraction(float(x))


def check_tempo(tempo) -> None:
    """Raise ValueError (the reason) unless `tempo` lies in TEMPO_RANGE; readers add the file and position."""
    lo, hi = TEMPO_RANGE
    if not lo <= tempo <= hi:
        raise ValueError(f"tempo {tempo:g} BPM is outside {lo:g}..{hi:g} (quarter-note beats per minute)")


def check_timing(tempo, durations: Sequence[Fraction], path: str | Path | None = None, where: str | None = None,
                 *, fps: int = 60, min_frames: int = 5) -> None:
    """Raise `SongError` unless notes of these durations (whole notes) at `tempo` are within the module's limits.
    The error names `path` and the note as "WHERE, note I" (I 0-based)."""
    def at(i):
        return f"{where}, note {i}" if where else f"note {i}"

    try:
        check_tempo(tempo)
    except ValueError as e:
        raise SongError(path, where, str(e)) from None
    durations = [Fraction(d) for d in durations]
    i = min(range(len(durations)), key=durations.__getitem__)
    shortest = durations[i]
    x = shortest * 240 * fps / _fraction(tempo)
    if x < 1:
        raise SongError(path, at(i), f"this note (duration {shortest}) lasts {float(x):.2g} frames at {tempo:g} BPM; "
                                     f"a note must last at least one frame (1/{fps} s), i.e. 1/{240 * fps / tempo:g} "
                                     f"of a whole note at this tempo (the shortest note is then stretched to "
                                     f"{min_frames} frames, which slows the song at most {min_frames}x)")
    n = shortest_frames(tempo, shortest, fps, min_frames)
    limit = MAX_SECONDS * fps
    end = Fraction(0)
    for j, d in enumerate(durations):
        end += d
        frames = round(end * n / shortest)
        if frames > limit:
            raise SongError(path, at(j), f"this note (duration {d}) ends at frame {frames}, past the limit of "
                                         f"{limit} frames ({MAX_SECONDS // 60} min at {fps} Hz) for a song")
    tpw = ticks_per_whole(durations)
    ticks = [int(d * tpw) for d in durations]
    slow = min(tempo, MIN_TEMPO)                  # the slowest tempo the envs' windows use
    s, m = min(ticks), max(ticks)
    n_s = shortest_frames(slow, Fraction(s, tpw), fps, min_frames)
    n_m = shortest_frames(slow, Fraction(m, tpw), fps, min_frames)   # a window may hold just the longest note
    if sum(ticks) >= _INT32 or s * 240 * fps >= _FLOAT32_EXACT or tpw * n_s >= _FLOAT32_EXACT:
        j = max(range(len(durations)), key=lambda k: durations[k].denominator)
        raise SongError(path, at(j), f"durations too fine to time exactly: with this note (duration {durations[j]}) "
                                     f"the song needs a tick of 1/{tpw} whole note, beyond the int32 timing of the "
                                     f"timeline; write the durations on a common grid such as 1/64 or 1/48")
    if m * 240 * fps >= _INT32 or m * n_m >= _INT32:
        j = ticks.index(m)
        raise SongError(path, at(j), f"this note (duration {durations[j]}) is {m} ticks of 1/{tpw} whole note, too "
                                     f"many for the int32 timing of note windows; split it into tied notes or write "
                                     f"the song on a coarser grid")


def validate(song: Song, path: str | Path | None = None, where: str | None = None, *, fps: int = 60,
             min_frames: int = 5) -> Song:
    """`check_timing` of the song's tempo and note durations; returns the song."""
    check_timing(song.tempo, [n.duration for n in song.notes], path, where, fps=fps, min_frames=min_frames)
    return song


__all__ = ["TEMPO_RANGE", "MIN_TEMPO", "MAX_SECONDS", "ticks_per_whole", "shortest_frames", "frames_per_whole",
           "effective_tempo", "check_tempo", "check_timing", "validate"]
