"""Automatic string/fret assignment ("fingering") for pitches without a tab, e.g. from a MIDI file.

`assign_positions` takes a sequence of chords (each a list of MIDI pitches; a single note is a chord of one, an
empty chord is a rest) and returns, per chord, a 6-tuple of frets (index 0 = string 1, high E; MUTE where unused).

Constraints on every chord:
  * each pitch is played on its own string, at fret `pitch - OPEN_MIDI[string]` in 0..max_fret;
  * span convention: the *pressed* frets (fret >= 1; open strings need no finger) satisfy
    `max - min <= max_span - 1`, i.e. with the default `max_span=4` they lie within four consecutive frets, one
    finger per fret (e.g. frets 2..5 are fine, 2..6 are not).

Among all playable positions of every chord the search picks the sequence of minimal total cost (exact dynamic
programming / Viterbi over the hand position):
  * hand position of a chord = mean of its pressed frets; a chord of open strings only (or a rest) leaves the hand
    where it was, so open strings are free;
  * moving cost = |hand position after - hand position before| summed over the song (the first pressed chord
    costs no movement: the hand starts wherever it is needed);
  * plus, per chord, `SPAN_WEIGHT * (max - min pressed fret)` (prefer compact shapes) and
    `HEIGHT_WEIGHT * hand position` (prefer lower positions when otherwise equal).
Ties are broken deterministically: the positions of a chord are tried in sorted order and the first minimum wins.
"""
from __future__ import annotations

from typing import Sequence

from dexguitar.world.guitar import N_FRETS, N_STRINGS, OPEN_MIDI

MUTE = -1  # same value as dexguitar.music.song.MUTE (not imported to keep this module dependency-free)
SPAN_WEIGHT = 0.1     # cost per fret of stretch inside one chord
HEIGHT_WEIGHT = 0.01  # cost per fret of hand height, per chord

_NAMES = ("C", "C#", "D", "D#", "E", "F", "F#", "G", "G#", "A", "A#", "B")


def pitch_name(pitch: int) -> str:
    """MIDI number -> scientific pitch name, e.g. 64 -> 'E4'."""
    return f"{_NAMES[pitch % 12]}{pitch // 12 - 1}"


class FingeringError(ValueError):
    """A chord cannot be played; `index` is its position in the input sequence, `pitches` its pitches."""

    def __init__(self, index: int, pitches: Sequence[int], message: str):
        self.index, self.pitches, self.detail = index, tuple(pitches), message
        names = ", ".join(f"{pitch_name(p)} ({p})" for p in pitches)
        super().__init__(f"chord {index} [{names}]: {message}")


def chord_positions(pitches: Sequence[int], *, max_span: int = 4, max_fret: int = N_FRETS
                    ) -> list[tuple[int, ...]]:
    """All playable 6-tuples of frets for one chord (distinct strings, pressed span <= max_span - 1)."""
    pitches = list(pitches)
    options = [[(s, p - OPEN_MIDI[s]) for s in range(N_STRINGS) if 0 <= p - OPEN_MIDI[s] <= max_fret]
               for p in pitches]
    # Most constrained pitch first keeps the backtracking small.
    order = sorted(range(len(pitches)), key=lambda i: len(options[i]))
    found: list[tuple[int, ...]] = []
    frets = [MUTE] * N_STRINGS

    def place(k: int, lo: int, hi: int) -> None:
        if k == len(order):
            found.append(tuple(frets))
            return
        for s, f in options[order[k]]:
            if frets[s] != MUTE:
                continue
            nlo, nhi = (min(lo, f), max(hi, f)) if f > 0 else (lo, hi)
            if f > 0 and nhi - nlo > max_span - 1:
                continue
            frets[s] = f
            place(k + 1, nlo, nhi)
            frets[s] = MUTE

    place(0, N_FRETS + 1, -1)
    return sorted(set(found))


def hand_position(frets: Sequence[int]) -> float | None:
    """Mean pressed fret, or None when no fret is pressed (open strings / rest)."""
    pressed = [f for f in frets if f > 0]
    return sum(pressed) / len(pressed) if pressed else None


def static_cost(frets: Sequence[int]) -> float:
    """Per-chord cost independent of the neighbours: stretch and height penalties."""
    pressed = [f for f in frets if f > 0]
    if not pressed:
        return 0.0
    return SPAN_WEIGHT * (max(pressed) - min(pressed)) + HEIGHT_WEIGHT * sum(pressed) / len(pressed)


def sequence_cost(positions: Sequence[Sequence[int]]) -> float:
    """Total cost of a fingering under the model documented above (what `assign_positions` minimizes)."""
    total, hand = 0.0, None
    for frets in positions:
        total += static_cost(frets)
        h = hand_position(frets)
        if h is not None:
            if hand is not None:
                total += abs(h - hand)
            hand = h
    return total


def _check_pitches(index: int, chord: Sequence[int], max_fret: int) -> None:
    if len(chord) > N_STRINGS:
        raise FingeringError(index, chord, f"{len(chord)} notes do not fit on {N_STRINGS} strings")
    lo, hi = min(OPEN_MIDI), max(OPEN_MIDI) + max_fret
    for p in chord:
        if not lo <= p <= hi:
            raise FingeringError(index, chord, f"pitch {pitch_name(p)} ({p}) is outside the guitar's range "
                                               f"{pitch_name(lo)} ({lo}) .. {pitch_name(hi)} ({hi})")


def assign_positions(chords: Sequence[Sequence[int]], *, max_span: int = 4, max_fret: int = N_FRETS
                     ) -> list[tuple[int, ...]]:
    """Choose a string and fret for every pitch with minimal total hand travel (see the module docstring).

    Raises `FingeringError` (a ValueError) naming the chord index and pitches when a pitch is out of range, a
    chord has more than six notes, or no assignment to distinct strings fits within the span.
    """
    if max_span < 1:
        raise ValueError(f"max_span must be >= 1, got {max_span}")
    if not 0 <= max_fret <= N_FRETS:
        raise ValueError(f"max_fret must be in 0..{N_FRETS}, got {max_fret}")
    candidates: list[list[tuple[int, ...]]] = []
    for i, chord in enumerate(chords):
        chord = [int(p) for p in chord]
        _check_pitches(i, chord, max_fret)
        if not chord:
            candidates.append([(MUTE,) * N_STRINGS])
            continue
        options = chord_positions(chord, max_span=max_span, max_fret=max_fret)
        if not options:
            raise FingeringError(i, chord, f"no assignment to distinct strings with pressed frets within "
                                           f"{max_span} frets (max - min <= {max_span - 1})")
        candidates.append(options)

    # Viterbi over the hand position: state = hand position after the chord (None before the first pressed chord).
    # best[state] = (cost, backpointer index into `trail`); trail entries are (previous trail index, frets).
    trail: list[tuple[int, tuple[int, ...]]] = []
    best: dict[float | None, tuple[float, int]] = {None: (0.0, -1)}
    for options in candidates:
        nxt: dict[float | None, tuple[float, int]] = {}
        for state, (cost, back) in best.items():
            for frets in options:
                h = hand_position(frets)
                new_state = state if h is None else h
                c = cost + static_cost(frets)
                if h is not None and state is not None:
                    c += abs(h - state)
                old = nxt.get(new_state)
                if old is None or c < old[0] - 1e-12:
                    trail.append((back, frets))
                    nxt[new_state] = (c, len(trail) - 1)
        best = nxt
    if not candidates:
        return []
    _, back = min(best.values(), key=lambda v: v[0])
    result: list[tuple[int, ...]] = []
    while back >= 0:
        back, frets = trail[back]
        result.append(frets)
    result.reverse()
    return result
