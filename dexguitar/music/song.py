"""The music data type every reader produces and every later stage consumes.

A `Song` is a tempo plus a sequence of `Note`s. A note is one time slot of the tab: what each of the six strings
does during it (mute, open, or pressed at a fret), how long it lasts as an exact fraction of a whole note, which
strings carry an effect (tie, hammer-on, pull-off, slide), and an optional chord hint for the left hand (the
arpeggio demo of the paper, Fig. 13). A note whose six strings are all muted is a rest.

Strings are numbered 1 (high E) ... 6 (low E); `frets[0]` is string 1, as in the authors' tab files.
"""
from __future__ import annotations

import dataclasses
import enum
from fractions import Fraction
from pathlib import Path
from typing import Sequence

from dexguitar.errors import InputError, read_input, special_file
from dexguitar.world.guitar import N_FRETS, N_STRINGS, open_pitches

MUTE = -1  # string not played during the note
OPEN = 0   # string played without pressing any fret
# Tab files larger than this are refused unread: 40x the largest tab we have (25 KB), while the slowest reader
# (ASCII) takes ~4 s and ~120 MB per MiB.
MAX_FILE_BYTES = 2**20


class SongError(InputError):
    """Bad input in a tab file: the message names the file, the position in it and what was expected."""


def check_file(path: str | Path, what: str = "a tab file") -> None:
    """`SongError` when `path` is a special file (FIFO, device, socket) or a directory, before anything opens it."""
    kind = special_file(path)
    if kind is not None:
        raise SongError(path, None, f"is {kind}, not {what}")


def read_bytes(path: Path, limit: int = MAX_FILE_BYTES) -> bytes:
    """The bytes of a tab file; `SongError` if it is missing, a special file (`read_input` looks before it opens),
    unreadable or larger than `limit` (each reader says what an empty file is not)."""
    return read_input(path, "a tab file", SongError, limit, " (real tabs are tens of KB)", empty_ok=True)


def check_playable(song: "Song", path: str | Path | None = None, where: str | None = None) -> "Song":
    """`song`, or `SongError` when it has nothing to play: every note a rest (all six strings muted). The one rule
    for every format; `readers.read_tab` applies it to what each reader returns."""
    if song.n_notes == 0:
        n = len(song.notes)
        rests = "its one note is a rest" if n == 1 else f"all {n} notes are rests"
        raise SongError(path, where, f"nothing to play: {rests} (every string muted)")
    return song


class Effect(enum.IntFlag):
    """Per-string effects. A tied, hammered, pulled or slid-to string sounds without a new pick."""

    NONE = 0
    TIE = 1       # the string keeps sounding from the previous note
    HAMMER = 2    # hammer-on: sounded by the left hand onto a higher fret
    PULL = 4      # pull-off: sounded by the left hand onto a lower fret
    SLIDE = 8     # slide into this fret from the previous one on the same string

    @property
    def not_picked(self) -> bool:
        return bool(self & (Effect.TIE | Effect.HAMMER | Effect.PULL | Effect.SLIDE))


NO_EFFECTS = (Effect.NONE,) * N_STRINGS


@dataclasses.dataclass(frozen=True)
class Note:
    """One time slot of a tab.

    duration: exact length as a fraction of a whole note (1/4 = a quarter note; triplet eighth = 1/12).
    frets: per string, MUTE (-1), OPEN (0) or the fret 1..22; index 0 = string 1 (high E).
    effects: per string `Effect` flags.
    chord: optional left-hand chord hint, per string MUTE (-1, not in the chord), OPEN or fret; the left hand
        holds this shape while the right hand picks only `frets` (paper Fig. 13).
    """

    duration: Fraction
    frets: tuple[int, ...]
    effects: tuple[Effect, ...] = NO_EFFECTS
    chord: tuple[int, ...] | None = None

    def __post_init__(self):
        object.__setattr__(self, "duration", Fraction(self.duration))
        object.__setattr__(self, "frets", tuple(int(f) for f in self.frets))
        object.__setattr__(self, "effects", tuple(Effect(e) for e in self.effects))
        if self.chord is not None:
            object.__setattr__(self, "chord", tuple(int(f) for f in self.chord))
        if self.duration <= 0:
            raise ValueError(f"note duration must be positive, got {self.duration}")
        for name in ("frets", "effects", "chord"):
            value = getattr(self, name)
            if value is not None and len(value) != N_STRINGS:
                raise ValueError(f"note {name} must have {N_STRINGS} entries, got {len(value)}")
        for values in (self.frets, self.chord or ()):
            for f in values:
                if not MUTE <= f <= N_FRETS:
                    raise ValueError(f"fret {f} out of range [{MUTE}, {N_FRETS}]")

    @property
    def is_rest(self) -> bool:
        return all(f == MUTE for f in self.frets)

    @property
    def played(self) -> tuple[int, ...]:
        """Strings (1-based) that sound in this note."""
        return tuple(i + 1 for i, f in enumerate(self.frets) if f != MUTE)

    @property
    def picked(self) -> tuple[bool, ...]:
        """Per string: does the right hand pick it (played and not sounded by a tie/hammer/pull/slide)?"""
        return tuple(f != MUTE and not e.not_picked for f, e in zip(self.frets, self.effects))

    @property
    def is_chord(self) -> bool:
        """Two or more strings sound together."""
        return len(self.played) >= 2

    @property
    def pitches(self) -> tuple[int, ...]:
        """MIDI pitches of the sounding strings, high string first."""
        return tuple(open_pitches()[i] + f for i, f in enumerate(self.frets) if f != MUTE)


@dataclasses.dataclass(frozen=True)
class Song:
    """A tempo (quarter-note beats per minute) and its notes."""

    tempo: float
    notes: tuple[Note, ...]
    title: str = ""

    def __post_init__(self):
        object.__setattr__(self, "notes", tuple(self.notes))
        if not self.tempo > 0:
            raise ValueError(f"tempo must be positive, got {self.tempo}")
        if not self.notes:
            raise ValueError("a song needs at least one note")

    @property
    def whole_notes(self) -> Fraction:
        return sum((n.duration for n in self.notes), Fraction(0))

    @property
    def seconds(self) -> float:
        """Length at the nominal tempo: a whole note lasts 4 beats."""
        return float(self.whole_notes * 4 * 60 / Fraction(self.tempo).limit_denominator(10**6))

    @property
    def n_notes(self) -> int:
        """Notes that sound (rests not counted)."""
        return sum(not n.is_rest for n in self.notes)

    @property
    def n_chords(self) -> int:
        return sum(n.is_chord for n in self.notes)

    @property
    def frets_used(self) -> tuple[int, int] | None:
        """(lowest, highest) pressed fret, or None when only open strings and rests occur."""
        pressed = [f for n in self.notes for f in n.frets if f > 0]
        return (min(pressed), max(pressed)) if pressed else None

    def replace(self, **changes) -> "Song":
        return dataclasses.replace(self, **changes)


def make_note(duration, frets: Sequence[int], effects: Sequence[int] | None = None,
              chord: Sequence[int] | None = None) -> Note:
    """Convenience constructor used by readers and tests."""
    return Note(Fraction(duration), tuple(frets), tuple(effects) if effects is not None else NO_EFFECTS,
                tuple(chord) if chord is not None else None)
