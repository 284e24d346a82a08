"""Procedural training material for the two hands, so that no (copyrighted) song corpus is needed.

The paper trained its general left-hand policy on 500 song tracks it could not publish and its right hand on
procedural picking patterns. Here both come from a seed: `left_exercises` writes scales, arpeggios, chord
progressions and long jumps over a documented chord-shape vocabulary (`CHORD_SHAPES`), drawn so that every shape
visits the whole neck; `right_patterns` writes picking/strumming patterns balanced over the 21 contiguous string
sets. Both return ordinary `Song`s; the RL env turns them into timelines and samples windows from them.
`coverage` summarises how balanced a list of songs is.

Conventions (as in `song.py`): index 0 = string 1 = high E, MUTE = -1, OPEN = 0, frets 1..22.
Playability of everything produced here: pressed frets (>= 1) of a note, and of its chord hint, lie within a
4-fret span (max - min <= 3) with at most 4 distinct frets, and every sounding string of an arpeggio note is in
its chord hint at the same fret.

Determinism: one `numpy.random.default_rng(seed)` is consumed song after song, so the first k songs of a call with
n_songs >= k are the same for the same seed.
"""
from __future__ import annotations

import dataclasses
from fractions import Fraction
from typing import Iterable, Sequence

import numpy as np

from dexguitar.music.song import MUTE, OPEN, Note, Song
from dexguitar.world.guitar import N_FRETS, N_STRINGS, OPEN_MIDI

MAX_SPAN = 3           # max - min of the pressed frets of one hand shape (four consecutive frets)
MAX_DISTINCT_FRETS = 4  # four fingers; a barre counts as one fret
X = MUTE               # short name for the tables below

BUCKETS = ((1, 5), (6, 10), (11, 15), (16, 22))  # neck regions for `coverage`
_NOTE_NAMES = ("C", "C#", "D", "D#", "E", "F", "F#", "G", "G#", "A", "A#", "B")


# --------------------------------------------------------------------------------------------------------------
# Chord-shape vocabulary
# --------------------------------------------------------------------------------------------------------------

@dataclasses.dataclass(frozen=True)
class ChordShape:
    """A named left-hand shape, frets high E -> low E (string 1 ... 6).

    movable=True: entries are MUTE or an offset >= 0 from the root fret (0 = *at* the root fret, not open); the
        shape slides along the neck and has no open strings. The root fret is the shape's lowest pressed fret
        (the barre fret for barre chords).
    movable=False: a fixed open-position chord; entries are absolute (MUTE, OPEN or fret).
    """

    name: str
    frets: tuple[int, ...]
    movable: bool = True
    family: str = ""

    @property
    def strings(self) -> tuple[int, ...]:
        """Strings (1-based) the shape sounds."""
        return tuple(i + 1 for i, f in enumerate(self.frets) if f != MUTE)


def _shapes() -> list[ChordShape]:
    m = []

    def add(family, name, frets, movable=True):
        m.append(ChordShape(name, tuple(frets), movable, family))

    # E-shape barre chords: root on string 6, index finger barres all six strings at the root fret.
    add("barre", "E-shape major", (0, 0, 1, 2, 2, 0))
    add("barre", "E-shape minor", (0, 0, 0, 2, 2, 0))
    add("barre", "E-shape 7", (0, 0, 1, 0, 2, 0))
    add("barre", "E-shape m7", (0, 0, 0, 0, 2, 0))
    add("barre", "E-shape maj7", (0, 0, 1, 1, 2, 0))
    # A-shape barre chords: root on string 5, barre over strings 1-5, string 6 muted.
    add("barre", "A-shape major", (0, 2, 2, 2, 0, X))
    add("barre", "A-shape minor", (0, 1, 2, 2, 0, X))
    add("barre", "A-shape 7", (0, 2, 0, 2, 0, X))
    add("barre", "A-shape m7", (0, 1, 0, 2, 0, X))
    add("barre", "A-shape maj7", (0, 2, 1, 2, 0, X))
    # D- and C-shapes moved up the neck (root on string 4 / string 5 at root+3).
    add("barre", "D-shape major", (2, 3, 2, 0, X, X))
    add("barre", "D-shape minor", (1, 3, 2, 0, X, X))
    add("barre", "C-shape major", (0, 1, 0, 2, 3, X))
    # Power chords: root + fifth (+ octave), rooted on strings 6, 5, 4 (the B string shifts the octave by one).
    add("power", "power 2-string root 6", (X, X, X, X, 2, 0))
    add("power", "power 3-string root 6", (X, X, X, 2, 2, 0))
    add("power", "power 2-string root 5", (X, X, X, 2, 0, X))
    add("power", "power 3-string root 5", (X, X, 2, 2, 0, X))
    add("power", "power 2-string root 4", (X, X, 2, 0, X, X))
    add("power", "power 3-string root 4", (X, 3, 2, 0, X, X))
    # Root-position triads on adjacent string sets (root on the lowest string of the set).
    add("triad", "triad major strings 4-5-6", (X, X, X, 0, 2, 3))
    add("triad", "triad minor strings 4-5-6", (X, X, X, 0, 1, 3))
    add("triad", "triad major strings 3-4-5", (X, X, 0, 2, 3, X))
    add("triad", "triad minor strings 3-4-5", (X, X, 0, 1, 3, X))
    add("triad", "triad major strings 2-3-4", (X, 0, 1, 2, X, X))
    add("triad", "triad minor strings 2-3-4", (X, 0, 0, 2, X, X))
    add("triad", "triad major strings 1-2-3", (0, 2, 2, X, X, X))
    add("triad", "triad minor strings 1-2-3", (0, 1, 2, X, X, X))
    # Dyads: major sixths on string pairs one apart, major/minor thirds on adjacent pairs, octaves.
    add("dyad", "sixth strings 1+3", (0, X, 0, X, X, X))
    add("dyad", "sixth strings 2+4", (X, 0, X, 0, X, X))
    add("dyad", "sixth strings 3+5", (X, X, 0, X, 1, X))
    add("dyad", "sixth strings 4+6", (X, X, X, 0, X, 1))
    add("dyad", "major third strings 1+2", (0, 1, X, X, X, X))
    add("dyad", "minor third strings 1+2", (0, 2, X, X, X, X))
    add("dyad", "major third strings 2+3", (X, 0, 0, X, X, X))
    add("dyad", "minor third strings 2+3", (X, 0, 1, X, X, X))
    add("dyad", "major third strings 3+4", (X, X, 0, 1, X, X))
    add("dyad", "minor third strings 3+4", (X, X, 0, 2, X, X))
    add("dyad", "octave strings 4+6", (X, X, X, 2, X, 0))
    add("dyad", "octave strings 3+5", (X, X, 2, X, 0, X))
    add("dyad", "octave strings 2+4", (X, 3, X, 0, X, X))
    add("dyad", "octave strings 1+3", (3, X, 0, X, X, X))
    # Common open chords: fixed, absolute frets.
    add("open", "open C", (0, 1, 0, 2, 3, X), movable=False)
    add("open", "open G", (3, 0, 0, 0, 2, 3), movable=False)
    add("open", "open D", (2, 3, 2, 0, X, X), movable=False)
    add("open", "open A", (0, 2, 2, 2, 0, X), movable=False)
    add("open", "open Am", (0, 1, 2, 2, 0, X), movable=False)
    add("open", "open Em", (0, 0, 0, 2, 2, 0), movable=False)
    add("open", "open Dm", (1, 3, 2, 0, X, X), movable=False)
    add("open", "open E", (0, 0, 1, 2, 2, 0), movable=False)
    return m


CHORD_SHAPES: list[ChordShape] = _shapes()
SHAPES_BY_NAME: dict[str, ChordShape] = {s.name: s for s in CHORD_SHAPES}


def chord_positions(shape: ChordShape | str) -> list[tuple[int, ...]]:
    """Every absolute placement of a shape on the 22-fret neck, lowest root fret first.

    Movable shapes: root fret 1..22 with every pressed fret within 1..22. Fixed open shapes: their one placement.
    """
    if isinstance(shape, str):
        shape = SHAPES_BY_NAME[shape]
    if not shape.movable:
        return [shape.frets]
    top = max(f for f in shape.frets if f != MUTE)
    return [tuple(MUTE if f == MUTE else root + f for f in shape.frets) for root in range(1, N_FRETS - top + 1)]


def _check_shape(shape: ChordShape) -> None:
    pressed = [f for f in shape.frets if f > 0] if not shape.movable else [f for f in shape.frets if f != MUTE]
    assert len(shape.frets) == N_STRINGS and len(shape.strings) >= 2, shape
    if shape.movable:
        assert min(pressed) == 0, f"{shape.name}: movable offsets must start at 0"
    assert max(pressed) - min(pressed) <= MAX_SPAN and len(set(pressed)) <= MAX_DISTINCT_FRETS, shape.name


for _s in CHORD_SHAPES:
    _check_shape(_s)

# Every (shape, placement) pair: the population that chord draws are uniform over (balanced neck coverage).
CHORD_PLACEMENTS: list[tuple[ChordShape, tuple[int, ...]]] = [(s, p) for s in CHORD_SHAPES for p in chord_positions(s)]


def _shape_key(frets: Sequence[int]) -> tuple[bool, tuple[int, ...]] | None:
    """Lookup key of a left-hand shape: open shapes by absolute frets, pressed-only shapes relative to their
    lowest fret (so every placement of a movable shape has the same key)."""
    if sum(f != MUTE for f in frets) < 2:
        return None
    if any(f == OPEN for f in frets):
        return (False, tuple(frets))
    low = min(f for f in frets if f > 0)
    return (True, tuple(MUTE if f == MUTE else f - low for f in frets))


_SHAPE_LOOKUP = {(s.movable, s.frets): s.name for s in CHORD_SHAPES}
assert len(_SHAPE_LOOKUP) == len(CHORD_SHAPES), "two vocabulary shapes have the same pattern"


def shape_name(frets: Sequence[int]) -> str | None:
    """Name of the vocabulary shape these absolute frets are a placement of, or None."""
    key = _shape_key(frets)
    return _SHAPE_LOOKUP.get(key) if key is not None else None


# --------------------------------------------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------------------------------------------

def _single(string: int, fret: int) -> tuple[int, ...]:
    """Frets of a note that sounds one string (1-based)."""
    f = [MUTE] * N_STRINGS
    f[string - 1] = int(fret)
    return tuple(f)


REST = (MUTE,) * N_STRINGS


def _pick(rng: np.random.Generator, items: Sequence, weights: Sequence[float] | None = None):
    """One element of a Python sequence (rng.choice would turn tuples into arrays)."""
    if weights is None:
        return items[int(rng.integers(len(items)))]
    p = np.asarray(weights, dtype=float)
    return items[int(rng.choice(len(items), p=p / p.sum()))]


def _tempo(rng: np.random.Generator, tempo_range) -> float:
    lo, hi = tempo_range
    return float(rng.integers(int(lo), int(hi) + 1))


def _draw_chord(rng: np.random.Generator) -> tuple[ChordShape, tuple[int, ...]]:
    """Uniform over (shape, placement) pairs: each movable shape is seen at every root fret, not just open
    position (the open chords, one placement each, are correspondingly rare)."""
    return CHORD_PLACEMENTS[int(rng.integers(len(CHORD_PLACEMENTS)))]


F = Fraction
STEADY = (F(1, 4), F(1, 8), F(1, 16), F(1, 12))                       # incl. eighth-note triplets
HOLDS = (F(1, 16), F(3, 32), F(1, 8), F(3, 16), F(1, 4), F(3, 8), F(1, 2))  # 1/16 .. 1/2, also dotted
HOLD_WEIGHTS = (1, 1, 2, 2, 3, 2, 2)


# --------------------------------------------------------------------------------------------------------------
# Left hand
# --------------------------------------------------------------------------------------------------------------

SCALES = {
    "major": (0, 2, 4, 5, 7, 9, 11),
    "minor pentatonic": (0, 3, 5, 7, 10),
    "chromatic": tuple(range(12)),
}


def scale_box(start: int, root: int, scale: str) -> list[tuple[int, int]]:
    """(string, fret) of the scale notes inside the 4-fret box start..start+3, by ascending pitch.

    A 4-fret box over six strings never holds one pitch twice (neighbouring strings are 4-5 semitones apart)."""
    pcs = set(SCALES[scale])
    notes = [(s, f) for s in range(1, N_STRINGS + 1) for f in range(start, start + MAX_SPAN + 1)
             if (OPEN_MIDI[s - 1] + f - root) % 12 in pcs]
    return sorted(notes, key=lambda sf: OPEN_MIDI[sf[0] - 1] + sf[1])


def scale_run(start: int, root: int, scale: str) -> list[tuple[int, int]]:
    """The longest stretch of the box that steps through consecutive scale degrees, by ascending pitch.

    With one finger per fret some degrees fall just outside the box (fret start-1 or start+4); a run must not
    skip them, so it stops there. The chromatic exercise keeps the whole box (four frets on every string)."""
    box = scale_box(start, root, scale)
    if scale == "chromatic":
        return box
    pcs = SCALES[scale]
    pitch = [OPEN_MIDI[s - 1] + f for s, f in box]

    def next_degree(p):
        return next(q for q in range(p + 1, p + 13) if (q - root) % 12 in pcs)

    best, cur = (0, 1), 0
    for i in range(1, len(box) + 1):
        if i == len(box) or pitch[i] != next_degree(pitch[i - 1]):
            if i - cur > best[1] - best[0]:
                best = (cur, i)
            cur = i
    return box[best[0]:best[1]]


def scale_positions(root: int, scale: str) -> list[int]:
    """Box start frets whose run covers at least one octave of the scale."""
    return [p for p in range(1, N_FRETS - MAX_SPAN + 1) if len(scale_run(p, root, scale)) >= len(SCALES[scale])]


def _left_scale(rng, n):
    """Runs through a scale in random 4-fret boxes across the neck, one note per step."""
    scale = _pick(rng, list(SCALES))
    root = int(rng.integers(12))
    starts = scale_positions(root, scale)
    dur = _pick(rng, STEADY)
    notes: list[Note] = []
    while len(notes) < n:
        run = scale_run(_pick(rng, starts), root, scale)
        direction = _pick(rng, ("up", "down", "up-down", "down-up"))
        seq = {"up": run, "down": run[::-1], "up-down": run + run[-2::-1], "down-up": run[::-1] + run[1:]}[direction]
        notes += [Note(dur, _single(s, f)) for s, f in seq]
    return notes, f"scale {_NOTE_NAMES[root]} {scale}"


def _left_arpeggio(rng, n):
    """Chord shapes picked string by string while the hand holds the chord (hint on every note, paper Fig. 13)."""
    dur = _pick(rng, STEADY[1:])
    notes: list[Note] = []
    while len(notes) < n:
        _, chord = _draw_chord(rng)
        low_to_high = [s for s in range(N_STRINGS, 0, -1) if chord[s - 1] != MUTE]
        pattern = _pick(rng, ("up", "down", "up-down", "random"))
        if pattern == "up":
            seq = low_to_high
        elif pattern == "down":
            seq = low_to_high[::-1]
        elif pattern == "up-down":
            seq = low_to_high + low_to_high[-2:0:-1]
        else:
            seq = [low_to_high[i] for i in rng.permutation(len(low_to_high))]
        seq = seq * int(rng.integers(1, 3))
        notes += [Note(dur, _single(s, chord[s - 1]), chord=chord) for s in seq]
    return notes, "arpeggio"


def _left_chords(rng, n):
    """A progression of chord shapes, uniform over (shape, placement), each held 1/16 .. 1/2 (also dotted)."""
    notes = [Note(_pick(rng, HOLDS, HOLD_WEIGHTS), _draw_chord(rng)[1]) for _ in range(n)]
    return notes, "chords"


def _left_jumps(rng, n):
    """Single notes that move at least 7 frets each time: long-distance shifts of the hand."""
    notes: list[Note] = []
    prev = int(rng.integers(1, N_FRETS + 1))
    for _ in range(n):
        far = [f for f in range(1, N_FRETS + 1) if abs(f - prev) >= 7]
        prev = _pick(rng, far)
        notes.append(Note(_pick(rng, HOLDS[2:], HOLD_WEIGHTS[2:]), _single(int(rng.integers(1, N_STRINGS + 1)), prev)))
    return notes, "jumps"


LEFT_KINDS = {"scale": (_left_scale, 0.25), "arpeggio": (_left_arpeggio, 0.25),
              "chords": (_left_chords, 0.3), "jumps": (_left_jumps, 0.2)}


def _sprinkle(rng, notes: list[Note], n: int, p_repeat=0.06, p_rest=0.04) -> list[Note]:
    """Occasional repeated notes and rests (a rest never first), cut to n notes."""
    out: list[Note] = []
    for note in notes:
        out.append(note)
        u = rng.random()
        if u < p_repeat:
            out.append(note)
        elif u < p_repeat + p_rest:
            out.append(Note(_pick(rng, (F(1, 8), F(1, 4))), REST))
        if len(out) >= n:
            break
    return out[:n]


def left_exercises(seed: int, n_songs: int, notes_per_song: int = 40, tempo_range=(60, 160)) -> list[Song]:
    """Left-hand training songs: scales, arpeggios, chord progressions and long jumps, with rests and repeats.

    The kind of each song is drawn with weights `LEFT_KINDS`; its title says which, e.g.
    "left-exercise-3 (arpeggio)" or "left-exercise-0 (scale A minor pentatonic)".
    """
    if notes_per_song < 1:
        raise ValueError("notes_per_song must be >= 1")
    rng = np.random.default_rng(seed)
    kinds = list(LEFT_KINDS)
    songs = []
    for i in range(n_songs):
        kind = _pick(rng, kinds, [LEFT_KINDS[k][1] for k in kinds])
        tempo = _tempo(rng, tempo_range)
        notes, label = LEFT_KINDS[kind][0](rng, notes_per_song)
        songs.append(Song(tempo, _sprinkle(rng, notes, notes_per_song), f"left-exercise-{i} ({label})"))
    return songs


# --------------------------------------------------------------------------------------------------------------
# Right hand
# --------------------------------------------------------------------------------------------------------------

# The 21 contiguous string sets (lowest-numbered string, highest-numbered string): 6 singles ... 1 full strum.
STRING_SETS: list[tuple[int, int]] = [(lo, lo + w - 1) for w in range(1, N_STRINGS + 1)
                                      for lo in range(1, N_STRINGS - w + 2)]


def set_name(lo: int, hi: int) -> str:
    return str(lo) if lo == hi else f"{lo}-{hi}"


def _strum(s: tuple[int, int]) -> tuple[int, ...]:
    """All strings lo..hi open, the rest muted: the right hand only sees which strings to pick."""
    return tuple(OPEN if s[0] <= k <= s[1] else MUTE for k in range(1, N_STRINGS + 1))


class _SetBalancer:
    """Running counts per string set; draws prefer the least-used sets so that all 21 stay balanced."""

    def __init__(self, margin: int = 6):
        self.counts = {s: 0 for s in STRING_SETS}
        self.margin = margin

    def pick(self, rng, allowed: Sequence[tuple[int, int]]) -> tuple[int, int]:
        low = min(self.counts[s] for s in allowed)
        return _pick(rng, [s for s in allowed if self.counts[s] <= low + self.margin])

    def note(self, s: tuple[int, int], dur) -> Note:
        self.counts[s] += 1
        return Note(dur, _strum(s))


def _right_single(rng, n, bal, dur):
    """Random single strings, sometimes picked twice in a row."""
    singles = [s for s in STRING_SETS if s[0] == s[1]]
    notes = []
    while len(notes) < n:
        s = bal.pick(rng, singles)
        notes += [bal.note(s, dur) for _ in range(int(rng.integers(1, 3)))]
    return notes, "single"


def _right_run(rng, n, bal, dur):
    """Neighbouring strings up and down: a window of 1..3 strings slides across 3+ positions and back
    (e.g. 6-5-4-3 then 3-4-5-6)."""
    notes = []
    while len(notes) < n:
        w = int(rng.integers(1, 4))
        k = int(rng.integers(3, N_STRINGS - w + 2))        # positions of the window
        first = int(rng.integers(1, N_STRINGS - w - k + 3))  # lowest-numbered string of the whole run
        sets = [(lo, lo + w - 1) for lo in range(first + k - 1, first - 1, -1)]  # low pitch -> high pitch
        seq = sets + sets[::-1] if rng.random() < 0.5 else sets[::-1] + sets
        notes += [bal.note(s, dur) for s in seq]
    return notes, "run"


def _right_strum(rng, n, bal, dur):
    """Repeated strums of one string set (full six strings or partial) at a steady rhythm, 4..8 per set."""
    notes = []
    while len(notes) < n:
        s = bal.pick(rng, STRING_SETS)
        notes += [bal.note(s, dur) for _ in range(int(rng.integers(4, 9)))]
    return notes, "strum"


def _right_partial(rng, n, bal, dur):
    """A different partial chord (2..6 contiguous strings) on every beat."""
    multi = [s for s in STRING_SETS if s[1] > s[0]]
    return [bal.note(bal.pick(rng, multi), dur) for _ in range(n)], "partial"


RIGHT_KINDS = {"single": (_right_single, 0.15), "run": (_right_run, 0.3),
               "strum": (_right_strum, 0.3), "partial": (_right_partial, 0.25)}


def right_patterns(seed: int, n_songs: int, notes_per_song: int = 40, tempo_range=(60, 180)) -> list[Song]:
    """Right-hand picking/strumming songs; every played string is OPEN, no effects.

    Each song has one steady rhythm (1/4, 1/8, 1/16 or eighth triplets) and one kind (`RIGHT_KINDS`); string sets
    are drawn least-used-first across the whole call, so the 21 contiguous sets are balanced. Title e.g.
    "right-pattern-2 (strum)".
    """
    if notes_per_song < 1:
        raise ValueError("notes_per_song must be >= 1")
    rng = np.random.default_rng(seed)
    bal = _SetBalancer()
    kinds = list(RIGHT_KINDS)
    songs = []
    for i in range(n_songs):
        kind = _pick(rng, kinds, [RIGHT_KINDS[k][1] for k in kinds])
        tempo = _tempo(rng, tempo_range)
        dur = _pick(rng, STEADY)
        notes, label = RIGHT_KINDS[kind][0](rng, notes_per_song, bal, dur)
        for extra in notes[notes_per_song:]:  # keep the balancer's counts equal to what is emitted
            bal.counts[_set_of(extra.frets)] -= 1
        songs.append(Song(tempo, notes[:notes_per_song], f"right-pattern-{i} ({label})"))
    return songs


def paper_right_patterns(seed: int, n_songs: int, notes_per_song: int = 40) -> list[Song]:
    """The authors' procedural right-hand goals (reference §3.4) as songs: every note one of the 21 contiguous
    string sets, uniformly, on open strings, lasting U{5..44} frames. At 225 BPM a 1/64 note lasts exactly one
    60 Hz frame, so a note of d frames is written as d/64."""
    if notes_per_song < 1:
        raise ValueError("notes_per_song must be >= 1")
    rng = np.random.default_rng(seed)
    songs = []
    for i in range(n_songs):
        notes = []
        for _ in range(notes_per_song):
            lo, hi = STRING_SETS[int(rng.integers(len(STRING_SETS)))]
            frets = tuple(OPEN if lo <= k <= hi else MUTE for k in range(1, N_STRINGS + 1))
            notes.append(Note(Fraction(int(rng.integers(5, 45)), 64), frets))
        songs.append(Song(225, notes, f"paper-pattern-{i}"))
    return songs


def _set_of(frets: Sequence[int]) -> tuple[int, int] | None:
    played = [k for k, f in enumerate(frets, start=1) if f != MUTE]
    if played and played[-1] - played[0] + 1 == len(played):
        return (played[0], played[-1])
    return None


# --------------------------------------------------------------------------------------------------------------
# Coverage
# --------------------------------------------------------------------------------------------------------------

def bucket_name(fret: int) -> str | None:
    for lo, hi in BUCKETS:
        if lo <= fret <= hi:
            return f"{lo}-{hi}"
    return None


def coverage(songs: Iterable[Song]) -> dict:
    """Balance statistics of generated songs.

    Per sounding note, its left-hand frets are the chord hint if any, else its own frets.
      shapes: vocabulary shape name -> notes whose left-hand frets are a placement of it;
      shape_buckets: shape name -> {position bucket -> count};
      positions: bucket of the lowest pressed left-hand fret ("open" when nothing is pressed) -> notes;
      string_sets: picked strings of each note as a contiguous set "lo-hi" (or "k"), else "other" -> notes;
      chord_fraction: fraction of sounding notes where two or more strings sound.
    """
    names = [f"{lo}-{hi}" for lo, hi in BUCKETS]
    out = {"songs": 0, "notes": 0, "rests": 0, "chords": 0,
           "shapes": {s.name: 0 for s in CHORD_SHAPES},
           "shape_buckets": {s.name: {b: 0 for b in names} for s in CHORD_SHAPES},
           "positions": {b: 0 for b in names + ["open"]},
           "string_sets": {set_name(*s): 0 for s in STRING_SETS} | {"other": 0}}
    for song in songs:
        out["songs"] += 1
        for note in song.notes:
            if note.is_rest:
                out["rests"] += 1
                continue
            out["notes"] += 1
            out["chords"] += note.is_chord
            hand = note.chord if note.chord is not None else note.frets
            pressed = [f for f in hand if f > 0]
            bucket = bucket_name(min(pressed)) if pressed else "open"
            out["positions"][bucket] += 1
            name = shape_name(hand)
            if name is not None:
                out["shapes"][name] += 1
                if bucket != "open":
                    out["shape_buckets"][name][bucket] += 1
            picked = tuple(MUTE if not p else 0 for p in note.picked)
            s = _set_of(picked)
            out["string_sets"][set_name(*s) if s else "other"] += 1
    out["chord_fraction"] = out["chords"] / out["notes"] if out["notes"] else 0.0
    return out
