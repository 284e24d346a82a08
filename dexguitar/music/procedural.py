"""Procedural training material for the two hands, so that no (copyrighted) song corpus is needed.

The paper trained its general left-hand policy on 500 song tracks it could not publish and its right hand on
procedural picking patterns. Here both come from a seed: `left_exercises` writes scales, arpeggios, chord
progressions and long jumps over a documented chord-shape vocabulary (`CHORD_SHAPES`), drawn so that every shape
visits the whole neck; `left_general` is the general left hand's material: every voicing of 17 chord qualities
that one hand holds in a 4-fret box (`chord_voicings`), drawn balanced over families and neck regions and played
as strums, fingerpicking, let-ring arpeggios, arpeggios with chord hints, double stops and pedal points, plus
two-/three-voice writing and scale lines in positions from the open one to fret 19, and jumps (the paper names
poor chord coverage as its general policy's weakness; `dexguitar.music.coverage` measures it); `right_patterns`
writes picking/strumming patterns balanced over the 21 contiguous string sets. All return ordinary `Song`s; the
RL env turns them into timelines and samples windows from them. `coverage` summarises how balanced a list of
songs is.

Conventions (as in `song.py`): index 0 = string 1 = high E, MUTE = -1, OPEN = 0, frets 1..22.
Playability of everything produced here: pressed frets (>= 1) of a note, and of its chord hint, lie within a
4-fret span (max - min <= 3) with at most 4 distinct frets (`left_general`: at most 4 fingers as the left-hand
reward counts them, `finger_groups`), and every sounding string of an arpeggio note is in its chord hint at the
same fret.

Determinism: one `numpy.random.default_rng(seed)` is consumed song after song, so the first k songs of a call with
n_songs >= k are the same for the same seed.
"""
from __future__ import annotations

import dataclasses
import functools
import itertools
from fractions import Fraction
from typing import Iterable, Sequence

import numpy as np

from dexguitar.errors import UserError
from dexguitar.music.song import MUTE, OPEN, Effect, Note, Song
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
LINE_SCALES = SCALES | {  # `left_general` also plays these (`left_exercises` keeps drawing from SCALES)
    "natural minor": (0, 2, 3, 5, 7, 8, 10),
    "harmonic minor": (0, 2, 3, 5, 7, 8, 11),
    "major pentatonic": (0, 2, 4, 7, 9),
}


def scale_box(start: int, root: int, scale: str) -> list[tuple[int, int]]:
    """(string, fret) of the scale notes inside the 4-fret box start..start+3, by ascending pitch.

    A 4-fret box over six strings never holds one pitch twice (neighbouring strings are 4-5 semitones apart).
    start 0 is the open position: open strings and frets 1..3."""
    pcs = set(LINE_SCALES[scale])
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
    pcs = LINE_SCALES[scale]
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
# Left hand, general material: a chord vocabulary derived from harmony, played in every texture
# --------------------------------------------------------------------------------------------------------------

QUALITIES = {  # chord symbol suffix -> semitones above the root: the common qualities of tonal and popular music
    "5": (0, 7), "": (0, 4, 7), "m": (0, 3, 7), "sus2": (0, 2, 7), "sus4": (0, 5, 7), "dim": (0, 3, 6),
    "aug": (0, 4, 8), "6": (0, 4, 7, 9), "m6": (0, 3, 7, 9), "7": (0, 4, 7, 10), "maj7": (0, 4, 7, 11),
    "m7": (0, 3, 7, 10), "m7b5": (0, 3, 6, 10), "dim7": (0, 3, 6, 9), "7sus4": (0, 5, 7, 10),
    "add9": (0, 2, 4, 7), "madd9": (0, 2, 3, 7),
}
FIFTH = 7                    # the tone guitarists leave out of four-tone chords
MIN_VOICING_STRINGS = 3      # two-string shapes come as parts of voicings (double stops, pinches)
OPEN_POSITION = 4            # first position: open strings with frets 1..4 (one finger per fret)
FAMILIES = ("power", "open position", "open strings higher up", "3 strings", "4 strings", "5-6 strings")


@dataclasses.dataclass(frozen=True)
class Voicing:
    """One way to hold a chord: absolute frets high E -> low E (MUTE, OPEN or fret), root pitch class, quality."""

    frets: tuple[int, ...]
    root: int
    quality: str

    @property
    def name(self) -> str:
        """Chord symbol, e.g. "Am7"."""
        return _NOTE_NAMES[self.root] + self.quality

    @property
    def strings(self) -> tuple[int, ...]:
        """Sounding strings (1-based), high to low."""
        return tuple(i + 1 for i, f in enumerate(self.frets) if f != MUTE)

    @property
    def position(self) -> int:
        return min(f for f in self.frets if f > 0)

    @property
    def family(self) -> str:
        """The classes draws are balanced over (`FAMILIES`): power chords; voicings with open strings in the
        first position or higher up; voicings without, by number of strings (triads on string sets ... barres)."""
        if self.quality == "5":
            return "power"
        if OPEN in self.frets:
            return "open position" if self.position <= OPEN_POSITION else "open strings higher up"
        return {3: "3 strings", 4: "4 strings"}.get(len(self.strings), "5-6 strings")


def finger_groups(frets: Sequence[int]) -> int:
    """Fingers a shape needs, as the left-hand reward counts them (`envs.rewards.finger_order`): strings pressed
    at one fret share a finger (a barre) unless a string between them is open or pressed at a lower fret."""
    n = 0
    for a, fa in enumerate(frets):
        if fa <= 0:
            continue
        shared = any(frets[b] == fa and not any(frets[m] == OPEN or 0 < frets[m] < fa for m in range(a + 1, b))
                     for b in range(a + 1, N_STRINGS))
        n += not shared
    return n


def _voicings_in_box(box: int, root: int, quality: str) -> Iterable[tuple[int, ...]]:
    """Voicings of one chord that a hand holds in frets box..box+3, open strings allowed.

    Rules of common practice: the sounding strings are neighbours (>= 3 of them); every chord tone sounds (the
    fifth may be left out of four-tone chords); any chord tone may be the bass (inversions, slash chords such as
    C/G or G/B); at least one string is pressed. (`chord_voicings` keeps those that need at most 4 fingers.)"""
    steps = QUALITIES[quality]
    tones = {(root + t) % 12 for t in steps}
    needed = tones - {(root + FIFTH) % 12} if len(steps) >= 4 else tones
    options = [[f for f in (OPEN, *range(box, box + MAX_SPAN + 1)) if (OPEN_MIDI[s] + f) % 12 in tones]
               for s in range(N_STRINGS)]
    for top in range(N_STRINGS):                                      # index of the highest sounding string
        for bass in range(top + MIN_VOICING_STRINGS - 1, N_STRINGS):  # ... and of the lowest
            for part in itertools.product(*options[top:bass + 1]):
                if max(part) == OPEN:
                    continue
                if not needed <= {(OPEN_MIDI[top + k] + f) % 12 for k, f in enumerate(part)}:
                    continue
                yield (MUTE,) * top + part + (MUTE,) * (N_STRINGS - 1 - bass)


@functools.lru_cache(maxsize=None)
def chord_voicings() -> tuple[Voicing, ...]:
    """Every voicing (`_voicings_in_box`) of every chord (12 roots x `QUALITIES`) in every 4-fret box of the neck
    that needs at most 4 fingers (`finger_groups`): about 41,000.

    A shape that spells several chords is named after the first quality of `QUALITIES` that spells it, then the
    lowest root (A C E is Am, not C6 without its fifth)."""
    seen: dict[tuple[int, ...], Voicing] = {}
    for quality in QUALITIES:
        for root in range(12):
            for box in range(1, N_FRETS - MAX_SPAN + 1):
                for frets in _voicings_in_box(box, root, quality):
                    if frets not in seen and finger_groups(frets) <= MAX_DISTINCT_FRETS:
                        seen[frets] = Voicing(frets, root, quality)
    return tuple(seen.values())


@functools.lru_cache(maxsize=None)
def _voicing_index() -> dict[int, dict[tuple[str, int], tuple[Voicing, ...]]]:
    """Voicings by position, then (family, bass string), so that draws can be balanced and constrained cheaply."""
    index: dict[int, dict[tuple[str, int], list[Voicing]]] = {}
    for v in chord_voicings():
        index.setdefault(v.position, {}).setdefault((v.family, v.strings[-1]), []).append(v)
    return {p: {k: tuple(v) for k, v in groups.items()} for p, groups in index.items()}


P_NEAR = 0.5     # chance that the next chord stays within NEAR frets of the last (progressions mostly move little)
NEAR = 2
FAR = 5          # a jump moves the hand at least this many frets


def draw_voicing(rng, prev: int | None = None, far: bool = False, below: int = N_STRINGS + 1) -> Voicing:
    """A voicing balanced over neck buckets and `FAMILIES`: bucket uniform (or, after a chord at position `prev`,
    with chance P_NEAR a position within NEAR frets, or with far=True at least FAR frets away), then a family
    found there uniform, then uniform. below: every sounding string must be higher than this one (pedal tones)."""
    index = _voicing_index()
    if far:
        positions = [p for p in range(1, N_FRETS + 1) if abs(p - prev) >= FAR]
    elif prev is not None and rng.random() < P_NEAR:
        positions = [p for p in range(1, N_FRETS + 1) if abs(p - prev) <= NEAR]
    else:
        lo, hi = _pick(rng, BUCKETS)
        positions = range(lo, hi + 1)
    groups: dict[str, list[tuple[Voicing, ...]]] = {}
    for p in positions:
        for (family, bass), voicings in index.get(p, {}).items():
            if bass < below:
                groups.setdefault(family, []).append(voicings)
    if not groups:  # nothing of that kind near `prev`: start afresh
        return draw_voicing(rng, below=below)
    family = groups[_pick(rng, sorted(groups))]
    return _pick(rng, _pick(rng, family, [len(v) for v in family]))


def _part(voicing: Voicing, strings: Iterable[int], extra: dict[int, int] | None = None) -> tuple[int, ...]:
    """Frets of a note that sounds some strings of a voicing (and `extra` {string: fret})."""
    keep = set(strings)
    frets = [f if i + 1 in keep else MUTE for i, f in enumerate(voicing.frets)]
    for s, f in (extra or {}).items():
        frets[s - 1] = f
    return tuple(frets)


UNITS = (F(1, 8), F(1, 12), F(1, 16), F(1, 24), F(1, 32))  # the shortest note of a song
SHORTEST_FRAMES = (5, 15)   # shortest note of the official songs, in frames (reference §11)
TEMPO_RANGE = (50, 225)     # their tempos
FRAMES_PER_WHOLE_AT_1_BPM = 4 * 60 * 60  # a whole note is 4 beats; 60 s per minute; 60 frames per second
STEADY_MULTIPLES = (1, 1, 1, 2)         # lines and picked patterns: mostly the unit
HELD_MULTIPLES = (1, 2, 3, 4, 6, 8)     # strummed chords and jumps


def _rhythm(rng) -> tuple[float, Fraction]:
    """Tempo and shortest note such that the shortest note lasts 5..15 frames (uniform) at 50..225 BPM."""
    frames = int(rng.integers(SHORTEST_FRAMES[0], SHORTEST_FRAMES[1] + 1))
    units = [u for u in UNITS if TEMPO_RANGE[0] <= u * FRAMES_PER_WHOLE_AT_1_BPM / frames <= TEMPO_RANGE[1]]
    unit = _pick(rng, units)
    return float(round(unit * FRAMES_PER_WHOLE_AT_1_BPM / frames)), unit


def _gen_strum(rng, n, unit):
    """A progression: each voicing strummed 1..4 times, each strum held 1..8 units."""
    notes, v = [], None
    while len(notes) < n:
        v = draw_voicing(rng, v.position if v else None)
        notes += [Note(unit * _pick(rng, HELD_MULTIPLES), v.frets) for _ in range(int(rng.integers(1, 5)))]
    return notes, "strum"


def _gen_fingerstyle(rng, n, unit):
    """Fingerpicking a held chord: every note a random part of it (1 string .. all, size uniform): bass notes,
    pinches of bass and treble, double stops, partial strums."""
    notes, v = [], None
    while len(notes) < n:
        v = draw_voicing(rng, v.position if v else None)
        for _ in range(int(rng.integers(4, 9))):
            size = int(rng.integers(1, len(v.strings) + 1))
            strings = [v.strings[i] for i in rng.choice(len(v.strings), size, replace=False)]
            notes.append(Note(unit * _pick(rng, STEADY_MULTIPLES), _part(v, strings)))
    return notes, "fingerstyle"


def _gen_arpeggio(rng, n, unit):
    """A held chord picked string by string, the chord as hint on every note (paper Fig. 13)."""
    notes, v = [], None
    while len(notes) < n:
        v = draw_voicing(rng, v.position if v else None)
        low_to_high = list(v.strings[::-1])
        pattern = _pick(rng, ("up", "down", "up-down", "random"))
        seq = {"up": low_to_high, "down": low_to_high[::-1], "up-down": low_to_high + low_to_high[-2:0:-1],
               "random": [low_to_high[i] for i in rng.permutation(len(low_to_high))]}[pattern]
        notes += [Note(unit * _pick(rng, STEADY_MULTIPLES), _part(v, [s]), chord=v.frets) for s in seq]
    return notes, "arpeggio"


def _gen_let_ring(rng, n, unit):
    """Fingerpicking with the strings left ringing: each note picks one more string of the chord while the ones
    picked before keep sounding (tied), so the hand holds a growing part of the chord and keeps its open strings
    free."""
    notes, v = [], None
    while len(notes) < n:
        v = draw_voicing(rng, v.position if v else None)
        order = [v.strings[i] for i in rng.permutation(len(v.strings))] if rng.random() < 0.5 else v.strings[::-1]
        for k in range(len(order)):
            ties = tuple(Effect.TIE if s in order[:k] else Effect.NONE for s in range(1, N_STRINGS + 1))
            notes.append(Note(unit * _pick(rng, STEADY_MULTIPLES), _part(v, order[:k + 1]), ties))
    return notes, "let ring"


def _gen_double_stops(rng, n, unit):
    """Two strings of a chord at once (thirds, fourths, sixths, octaves: neighbours or one string apart),
    2..4 per chord, moving in mostly small steps."""
    notes, v = [], None
    while len(notes) < n:
        v = draw_voicing(rng, v.position if v else None)
        pairs = [(a, b) for a in v.strings for b in v.strings if 1 <= b - a <= 2]
        for _ in range(int(rng.integers(2, 5))):
            notes.append(Note(unit * _pick(rng, STEADY_MULTIPLES), _part(v, _pick(rng, pairs))))
    return notes, "double stops"


def _gen_pedal(rng, n, unit):
    """A pedal point: an open bass string (6, 5 or 4) under a figure played on the strings above it; each note
    is the pedal alone, the figure (1..3 strings of a chord), or both."""
    pedal = int(rng.integers(4, N_STRINGS + 1))
    notes, v = [], None
    while len(notes) < n:
        v = draw_voicing(rng, v.position if v else None, below=pedal)
        for _ in range(int(rng.integers(3, 7))):
            size = int(rng.integers(1, min(3, len(v.strings)) + 1))
            figure = [v.strings[i] for i in rng.choice(len(v.strings), size, replace=False)]
            what = _pick(rng, ("pedal", "figure", "both"))
            frets = {"pedal": _single(pedal, OPEN), "figure": _part(v, figure),
                     "both": _part(v, figure, {pedal: OPEN})}[what]
            notes.append(Note(unit * _pick(rng, STEADY_MULTIPLES), frets))
    return notes, f"pedal {pedal}"


LINE_STEPS = (-4, -3, -2, -1, 1, 2, 3, 4)   # scale steps of a melody: mostly seconds, some skips
LINE_STEP_WEIGHTS = (1, 1, 2, 4, 4, 2, 1, 1)


def _move_box(rng, start: int) -> int:
    """The next 4-fret box of a line: with chance P_NEAR 1..NEAR+2 frets away, else anywhere (0 = open position)."""
    if rng.random() < P_NEAR:
        return int(np.clip(start + _pick(rng, (-1, 1)) * int(rng.integers(1, NEAR + 3)), 0, N_FRETS - MAX_SPAN))
    return int(rng.integers(0, N_FRETS - MAX_SPAN + 1))


def _gen_line(rng, n, unit):
    """A single-note melody in a scale: phrases of 4..12 notes, each a run or a walk in a 4-fret box, the box
    moving between phrases, near (1..NEAR+2 frets) or anywhere from the open position to fret 19."""
    scale = _pick(rng, list(LINE_SCALES))
    root = int(rng.integers(12))
    start = int(rng.integers(0, N_FRETS - MAX_SPAN + 1))
    notes: list[Note] = []
    while len(notes) < n:
        box = scale_box(start, root, scale)
        length = int(rng.integers(4, 13))
        if rng.random() < 0.5:
            first = int(rng.integers(0, max(len(box) - length, 0) + 1))
            seq = box[first:first + length]
            seq = seq if rng.random() < 0.5 else seq[::-1]
        else:
            i, seq = int(rng.integers(len(box))), []
            for _ in range(length):
                seq.append(box[i])
                i = int(np.clip(i + _pick(rng, LINE_STEPS, LINE_STEP_WEIGHTS), 0, len(box) - 1))
        notes += [Note(unit * _pick(rng, STEADY_MULTIPLES), _single(s, f)) for s, f in seq]
        start = _move_box(rng, start)
    return notes, f"line {_NOTE_NAMES[root]} {scale}"


def _gen_voices(rng, n, unit):
    """Classical two- and three-voice writing in one position: a bass note (strings 4-6) under one or two melody
    notes (strings 1-3), any tones of one scale in the 4-fret box, not only chord tones (passing notes,
    suspensions); every third note or so the melody sounds alone. The box moves every 4..8 notes."""
    scale = _pick(rng, [s for s in LINE_SCALES if s != "chromatic"])
    root = int(rng.integers(12))
    start = int(rng.integers(0, N_FRETS - MAX_SPAN + 1))
    notes: list[Note] = []
    while len(notes) < n:
        frets_on = {s: [f for t, f in scale_box(start, root, scale) if t == s] for s in range(1, N_STRINGS + 1)}
        basses = [s for s in (4, 5, 6) if frets_on[s]]
        for _ in range(int(rng.integers(4, 9))):
            strings = [int(s) for s in rng.choice((1, 2, 3), int(rng.integers(1, 3)), replace=False)]
            if rng.random() < 2 / 3:
                strings.append(_pick(rng, basses))
            frets = [MUTE] * N_STRINGS
            for s in strings:
                frets[s - 1] = _pick(rng, frets_on[s])
            notes.append(Note(unit * _pick(rng, STEADY_MULTIPLES), frets))
        start = _move_box(rng, start)
    return notes, f"voices {_NOTE_NAMES[root]} {scale}"


def _gen_jumps(rng, n, unit):
    """Chords and single notes, each at least FAR frets from the last: long shifts of the hand."""
    v = draw_voicing(rng)
    notes = [Note(unit * _pick(rng, HELD_MULTIPLES), v.frets)]
    prev = v.position
    while len(notes) < n:
        if rng.random() < 0.5:
            v = draw_voicing(rng, prev, far=True)
            frets, prev = v.frets, v.position
        else:
            prev = _pick(rng, [f for f in range(1, N_FRETS + 1) if abs(f - prev) >= FAR])
            frets = _single(int(rng.integers(1, N_STRINGS + 1)), prev)
        notes.append(Note(unit * _pick(rng, HELD_MULTIPLES), frets))
    return notes, "jumps"


GENERAL_KINDS = {"strum": _gen_strum, "fingerstyle": _gen_fingerstyle, "let ring": _gen_let_ring,
                 "arpeggio": _gen_arpeggio, "double stops": _gen_double_stops, "pedal": _gen_pedal,
                 "voices": _gen_voices, "line": _gen_line, "jumps": _gen_jumps}


def left_general(seed: int, n_songs: int, notes_per_song: int = 40) -> list[Song]:
    """General left-hand training songs, balanced: the kinds (`GENERAL_KINDS`) take turns, chords are drawn
    balanced over families and neck regions from `chord_voicings`, lines run in boxes from the open position
    to fret 19, and every song's shortest note lasts 5..15 frames at 50..225 BPM.

    Titles say the kind, e.g. "left-general-1 (fingerstyle)". Deterministic per seed; the first k songs of a
    call with n_songs >= k are the same.
    """
    if notes_per_song < 1:
        raise ValueError("notes_per_song must be >= 1")
    rng = np.random.default_rng(seed)
    kinds = list(GENERAL_KINDS)
    songs = []
    for i in range(n_songs):
        tempo, unit = _rhythm(rng)
        notes, label = GENERAL_KINDS[kinds[i % len(kinds)]](rng, notes_per_song, unit)
        songs.append(Song(tempo, _sprinkle(rng, notes, notes_per_song), f"left-general-{i} ({label})"))
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


# ----------------------------------------------------------------------------------------------- by name

STYLES = {  # (hand, style) -> (generator, default number of songs)
    ("left", "exercises"): (left_exercises, 64),
    ("left", "general"): (left_general, 2000),   # coverage keeps rising up to ~2000 songs (docs/results.md)
    ("right", "steady"): (right_patterns, 64),
    ("right", "paper"): (paper_right_patterns, 64),
}
DEFAULT_STYLE = {"left": "general", "right": "mixed"}


def material(hand: str, style: str | None, seed: int, n: int | None = None) -> list[Song]:
    """Procedural songs for a hand by style name: left "exercises" or "general" (the general-purpose left hand's
    balanced material); right "steady" (ours), "paper" (the authors' random patterns: a contiguous string set and
    5-44 frames per note) or "mixed" (half each). n None: the style's default number."""
    style = style or DEFAULT_STYLE.get(hand)
    if hand == "right" and style == "mixed":
        n = n or STYLES[("right", "steady")][1]
        return right_patterns(seed, n - n // 2) + paper_right_patterns(seed, n // 2)
    if (hand, style) not in STYLES:
        names = sorted({s for h, s in STYLES if h == hand} | ({"mixed"} if hand == "right" else set()))
        raise UserError(f"--style {style}: not a {hand}-hand style; expected one of {', '.join(names)}")
    generate, default = STYLES[(hand, style)]
    return generate(seed, n or default)
