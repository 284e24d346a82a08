import itertools
import random

import pytest

from dexguitar.music.fingering import (FingeringError, assign_positions, chord_positions, sequence_cost)
from dexguitar.world.guitar import OPEN_MIDI

E4, F4, G4, A4, E5 = 64, 65, 67, 69, 76


def sounding(frets):
    """Pitches of a 6-tuple of frets, computed independently from the guitar's open-string table."""
    return sorted(OPEN_MIDI[s] + f for s, f in enumerate(frets) if f >= 0)


def check_playable(chords, result, max_span=4):
    assert len(result) == len(chords)
    for chord, frets in zip(chords, result):
        assert len(frets) == 6
        assert sounding(frets) == sorted(chord)
        pressed = [f for f in frets if f > 0]
        if pressed:
            assert max(pressed) - min(pressed) <= max_span - 1
        assert all(-1 <= f <= 22 for f in frets)


def test_first_position_when_starting_on_open_e():
    chords = [[E4], [F4], [G4], [A4]]
    result = assign_positions(chords)
    check_playable(chords, result)
    # Open E, then frets 1, 3, 5 of the high E string: the hand never leaves the first position.
    assert result == [(0, -1, -1, -1, -1, -1), (1, -1, -1, -1, -1, -1),
                      (3, -1, -1, -1, -1, -1), (5, -1, -1, -1, -1, -1)]


def test_starting_high_stays_high():
    chords = [[E5], [F4], [G4], [A4]]
    result = assign_positions(chords)
    check_playable(chords, result)
    assert result[0] == (12, -1, -1, -1, -1, -1)  # E5 played low on the neck is impossible; fret 12 is lowest
    assert all(f >= 8 for frets in result for f in frets if f > 0), result


def test_chord_within_span_and_distinct_strings():
    triad = [60, 64, 67]  # C4 E4 G4
    (frets,) = assign_positions([triad])
    check_playable([triad], [frets])
    assert sum(f >= 0 for f in frets) == 3
    full = [40, 45, 50, 55, 59, 64]  # all open strings: the only way
    assert assign_positions([full]) == [(0, 0, 0, 0, 0, 0)]


def test_span_convention():
    # Pressed frets must satisfy max - min <= max_span - 1 (four frets under four fingers); open strings are free.
    positions = chord_positions([41, 50])  # F2 only on string 6 fret 1; D3 on string 5 fret 5 or string 4 open
    assert (-1, -1, -1, 0, -1, 1) in positions
    assert (-1, -1, -1, -1, 5, 1) not in positions  # 5 - 1 = 4 > 3
    assert (-1, -1, -1, -1, 4, 1) in chord_positions([41, 49])  # 4 - 1 = 3: fits under four fingers
    assert (-1, -1, -1, -1, 5, 1) in chord_positions([41, 50], max_span=5)


def test_rest_keeps_hand_and_gives_all_mute():
    result = assign_positions([[E5], [], [77]])
    assert result[1] == (-1,) * 6
    assert result[2] == (13, -1, -1, -1, -1, -1)


def test_dp_is_optimal_against_brute_force():
    rng = random.Random(0)
    for _ in range(15):
        chords = [[rng.randint(52, 76)] for _ in range(4)]
        if rng.random() < 0.5:
            chords[rng.randrange(4)].append(rng.randint(45, 51))
        result = assign_positions(chords)
        check_playable(chords, result)
        options = [chord_positions(c) for c in chords]
        best = min(sequence_cost(seq) for seq in itertools.product(*options))
        assert sequence_cost(result) == pytest.approx(best)


def test_errors_name_chord_and_pitches():
    with pytest.raises(FingeringError, match=r"chord 1 .*\(30\).*outside"):
        assign_positions([[E4], [30]])
    with pytest.raises(ValueError, match=r"chord 0 .*outside"):
        assign_positions([[87]])  # one above D6 = string 1 fret 22
    with pytest.raises(ValueError, match="7 notes"):
        assign_positions([[40, 45, 50, 55, 59, 64, 69]])
    with pytest.raises(FingeringError, match=r"chord 2 .*no assignment") as info:
        assign_positions([[E4], [E4], [40, 41, 42]])  # three pitches only the low E string can play
    assert info.value.index == 2 and info.value.pitches == (40, 41, 42)
    assert assign_positions([]) == []
