"""What the left hand must be able to do in a set of songs, and how much of a test set a training set shows it.

The left hand's goal in a note (per string: k > 0 press fret k, -1 leave open, 0 don't care; `timeline.left_code`
with the chord hint filling the strings the note mutes) splits into
- shape: the goal with each pressed fret counted from the lowest pressed fret (1 = lowest), open and don't-care
  strings kept: what the fingers form. The fret-shift augmentation of training keeps it (open strings stay open);
- position: the lowest pressed fret (0 when nothing is pressed): where on the neck the hand is;
- span: highest minus lowest pressed fret; pressed: how many strings are pressed;
- jump: |position change| between consecutive notes that press something: how far the hand travels.
A chord is a note that presses two or more strings (reference §11). A test note is covered *exactly* when its goal
occurs in training and *up to a shift* when its shape does; otherwise its distance is the fewest strings whose goal
differs from that of some training shape (1 = one string off).
"""
from __future__ import annotations

from collections import Counter
from typing import Iterable, Sequence

import numpy as np

from dexguitar.music.song import Note, Song
from dexguitar.music.timeline import left_code

Goal = tuple[int, ...]
FRAMES_PER_WHOLE_AT_1_BPM = 4 * 60 * 60  # a whole note is 4 beats; 60 s per minute; 60 frames per second
BUCKETS = ((1, 5), (6, 10), (11, 15), (16, 22))  # neck regions for the position summary


def goal(note: Note) -> Goal:
    """The left hand's goal in a note, as the env builds it."""
    g = left_code(note.frets)
    if note.chord is not None:
        g = np.where(np.asarray(note.frets) < 0, left_code(note.chord), g)
    return tuple(int(x) for x in g)


def pressed(g: Goal) -> list[int]:
    return [f for f in g if f > 0]


def position(g: Goal) -> int:
    return min(pressed(g), default=0)


def span(g: Goal) -> int:
    p = pressed(g)
    return max(p) - min(p) if p else 0


def shape(g: Goal) -> Goal:
    """Pressed frets counted from the lowest pressed one (which becomes 1); open/don't-care strings unchanged."""
    low = position(g)
    return tuple(f - low + 1 if f > 0 else f for f in g)


def is_chord(g: Goal) -> bool:
    return len(pressed(g)) >= 2


def bucket(fret: int) -> str:
    """Neck region of a position: "open" (nothing pressed) or "lo-hi"."""
    return next((f"{lo}-{hi}" for lo, hi in BUCKETS if lo <= fret <= hi), "open")


def song_goals(song: Song) -> list[Goal]:
    """Goals of the notes that sound, in order (rests leave the hand free and are skipped)."""
    return [goal(n) for n in song.notes if not n.is_rest]


def jumps(goals: Sequence[Goal]) -> list[int]:
    """|position change| between consecutive goals that press something."""
    pos = [position(g) for g in goals if pressed(g)]
    return [abs(b - a) for a, b in zip(pos, pos[1:])]


def note_frames(song: Song) -> list[int]:
    """Length of each sounding note in 60 Hz frames at the song's tempo (before any clipping)."""
    return [round(float(n.duration) * FRAMES_PER_WHOLE_AT_1_BPM / song.tempo) for n in song.notes if not n.is_rest]


def _fractions(counter: Counter) -> dict:
    total = sum(counter.values())
    return {str(k): v / total for k, v in sorted(counter.items())} if total else {}


def distribution(songs: Iterable[Song]) -> dict:
    """What a set of songs asks of the left hand: counts, and fractions of notes per class (of songs per shortest
    note: the tempo the hand must keep up with)."""
    songs = list(songs)
    goals = [g for s in songs for g in song_goals(s)]
    chords = [g for g in goals if is_chord(g)]
    held = [g for g in goals if pressed(g)]
    return {
        "songs": len(songs), "notes": len(goals), "chords": len(chords),
        "distinct_shapes": len({shape(g) for g in goals}),
        "distinct_chord_shapes": len({shape(g) for g in chords}),
        "distinct_chords": len(set(chords)),
        "pressed_strings": _fractions(Counter(len(pressed(g)) for g in goals)),
        "buckets": _fractions(Counter(bucket(position(g)) for g in goals)),
        "positions": _fractions(Counter(position(g) for g in held)),
        "spans": _fractions(Counter(span(g) for g in held)),
        "jumps": _fractions(Counter(j for s in songs for j in jumps(song_goals(s)))),
        "note_frames": _fractions(Counter(f for s in songs for f in note_frames(s))),
        "shortest_frames": _fractions(Counter(min(note_frames(s)) for s in songs if s.n_notes)),
    }


def distance(a: Goal, b: Goal) -> int:
    """Strings whose goal differs."""
    return sum(x != y for x, y in zip(a, b))


def nearest(target: Goal, candidates: np.ndarray) -> int:
    """Smallest `distance` from a shape to any row of `candidates` (k, 6); 6 when there are none."""
    if len(candidates) == 0:
        return len(target)
    return int((candidates != np.asarray(target)).sum(axis=1).min())


def _share(items: Sequence, covered) -> float:
    return sum(map(covered, items)) / len(items) if items else float("nan")


def _covered(items: Sequence[Goal], goals: set, shapes: set, shape_array: np.ndarray) -> dict:
    """Fractions of `items` covered exactly and up to a shift; distances of the others to the nearest shape."""
    far = [nearest(shape(g), shape_array) for g in items if shape(g) not in shapes]
    return {"count": len(items), "exact": _share(items, lambda g: g in goals),
            "shift": _share(items, lambda g: shape(g) in shapes),
            "nearest": {str(k): v / len(items) for k, v in sorted(Counter(far).items())}}


def coverage(test: Iterable[Song], train: Iterable[Song]) -> dict:
    """How much of what the test songs ask of the left hand the training songs show it.

    notes / chords: per sounding note / per chord note of the test songs; distinct_chords: each distinct chord goal
    once. Each gives the fraction covered exactly and up to a shift, and `nearest`: the fraction at each distance
    (strings off) among those not covered up to a shift. positions / spans / jumps: the fraction of test notes
    (transitions) whose value occurs in training at all. per_song: chord coverage per test song.
    """
    test, train = list(test), list(train)
    train_goals = [g for s in train for g in song_goals(s)]
    goals, shapes = set(train_goals), {shape(g) for g in train_goals}
    shape_array = np.array(sorted(shapes), dtype=np.int32).reshape(-1, 6)
    per_song = {s.title: [g for g in song_goals(s)] for s in test}
    notes = [g for gs in per_song.values() for g in gs]
    chords = [g for g in notes if is_chord(g)]
    held = [g for g in notes if pressed(g)]
    seen_pos = {position(g) for g in train_goals if pressed(g)}
    seen_span = {span(g) for g in train_goals if pressed(g)}
    seen_jump = {j for s in train for j in jumps(song_goals(s))}
    test_jumps = [j for gs in per_song.values() for j in jumps(gs)]
    return {
        "notes": _covered(notes, goals, shapes, shape_array),
        "chords": _covered(chords, goals, shapes, shape_array),
        "distinct_chords": _covered(sorted(set(chords)), goals, shapes, shape_array),
        "positions": _share(held, lambda g: position(g) in seen_pos),
        "spans": _share(held, lambda g: span(g) in seen_span),
        "jumps": _share(test_jumps, lambda j: j in seen_jump),
        "per_song": {title: {k: v for k, v in _covered([g for g in gs if is_chord(g)], goals, shapes,
                                                       shape_array).items() if k != "nearest"}
                     for title, gs in per_song.items() if any(is_chord(g) for g in gs)},
    }
