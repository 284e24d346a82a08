from fractions import Fraction

import numpy as np
import pytest

from dexguitar.music import coverage as C
from dexguitar.music.song import Note, Song

X = -1
REST = (X,) * 6


def note(frets, duration=Fraction(1, 4), chord=None):
    return Note(Fraction(duration), frets, chord=chord)


# Training: G barre at fret 3, a single note (string 6, fret 5), a rest, open C.
TRAIN = Song(120, [note((3, 3, 4, 5, 5, 3)), note((X, X, X, X, X, 5), Fraction(1, 8)), note(REST),
                   note((0, 1, 0, 2, 3, X), Fraction(1, 2))], "train")
# Test: A barre (the G shape moved up), G barre (exact), a single note moved up, a C-like shape two strings off
# the open C, a rest, a dyad with a chord hint that fills strings 2 and 5, the A barre again.
TEST = Song(100, [note((5, 5, 6, 7, 7, 5)), note((3, 3, 4, 5, 5, 3)), note((X, X, X, X, X, 7)),
                  note((0, 2, 0, 2, 3, X)), note(REST), note((X, X, 2, 2, X, X), chord=(X, 3, 2, 2, 0, X)),
                  note((5, 5, 6, 7, 7, 5))], "test")


def test_goal_shape_position():
    assert C.goal(note((0, 1, 0, 2, 3, X))) == (-1, 1, -1, 2, 3, 0)          # open -> -1, mute -> don't care
    hinted = note((X, X, 2, 2, X, X), chord=(X, 3, 2, 2, 0, X))
    assert C.goal(hinted) == (0, 3, 2, 2, -1, 0)                               # the hint fills muted strings
    assert C.shape((5, 5, 6, 7, 7, 5)) == (1, 1, 2, 3, 3, 1) == C.shape((3, 3, 4, 5, 5, 3))
    assert C.shape((0, 3, 2, 2, -1, 0)) == (0, 2, 1, 1, -1, 0)
    assert C.shape((-1, 0, 0, 0, 0, 0)) == (-1, 0, 0, 0, 0, 0)                # nothing pressed: unchanged
    assert (C.position((0, 3, 2, 2, -1, 0)), C.span((0, 3, 2, 2, -1, 0))) == (2, 1)
    assert (C.position((-1, 0, 0, 0, 0, 0)), C.span((-1, 0, 0, 0, 0, 0))) == (0, 0)
    assert C.is_chord((0, 0, 2, 0, 0, 1)) and not C.is_chord((-1, -1, 0, 0, 0, 7))
    assert [C.bucket(f) for f in (0, 1, 5, 6, 15, 16, 22)] == ["open", "1-5", "1-5", "6-10", "11-15", "16-22",
                                                                "16-22"]
    assert C.jumps([(0, 0, 0, 0, 0, 5), (-1, 0, 0, 0, 0, 0), (0, 0, 0, 0, 8, 0), (0, 0, 0, 0, 0, 1)]) == [3, 7]


def test_distance():
    assert C.distance((-1, 1, -1, 1, 2, 0), (-1, 1, -1, 2, 3, 0)) == 2
    rows = np.array([(1, 1, 2, 3, 3, 1), (0, 0, 0, 0, 0, 1), (-1, 1, -1, 2, 3, 0)])
    assert C.nearest((-1, 1, -1, 1, 2, 0), rows) == 2
    assert C.nearest((0, 2, 1, 1, -1, 0), rows) == 5
    assert C.nearest((0, 2, 1, 1, -1, 0), rows[:0]) == 6


def test_distribution_of_the_training_song():
    d = C.distribution([TRAIN])
    assert (d["songs"], d["notes"], d["chords"]) == (1, 3, 2)
    assert (d["distinct_shapes"], d["distinct_chord_shapes"], d["distinct_chords"]) == (3, 2, 2)
    third = pytest.approx(1 / 3)
    assert d["pressed_strings"] == {"1": third, "3": third, "6": third}
    assert d["buckets"] == {"1-5": 1.0}
    assert d["positions"] == {"1": third, "3": third, "5": third}
    assert d["spans"] == {"0": third, "2": pytest.approx(2 / 3)}
    assert d["jumps"] == {"2": 0.5, "4": 0.5}                      # 3 -> 5 -> (rest) -> 1
    assert d["note_frames"] == {"15": third, "30": third, "60": third}  # 1/8, 1/4, 1/2 at 120 BPM
    assert d["shortest_frames"] == {"15": 1.0}


def test_coverage_worked_by_hand():
    c = C.coverage([TEST], [TRAIN])
    # 6 sounding notes: exact G barre; A barre twice and the moved single note only up to a shift; the C-like
    # shape is 2 strings off open C, the hinted dyad 5 strings off its nearest shape.
    assert c["notes"] == {"count": 6, "exact": pytest.approx(1 / 6), "shift": pytest.approx(4 / 6),
                          "nearest": {"2": pytest.approx(1 / 6), "5": pytest.approx(1 / 6)}}
    assert c["chords"] == {"count": 5, "exact": pytest.approx(1 / 5), "shift": pytest.approx(3 / 5),
                           "nearest": {"2": pytest.approx(1 / 5), "5": pytest.approx(1 / 5)}}
    assert c["distinct_chords"] == {"count": 4, "exact": 0.25, "shift": 0.5, "nearest": {"2": 0.25, "5": 0.25}}
    assert c["positions"] == 0.5                # 5, 3, 7, 2, 2, 5 against {3, 5, 1}
    assert c["spans"] == pytest.approx(4 / 6)   # 2, 2, 0, 1, 1, 2 against {2, 0}
    assert c["jumps"] == pytest.approx(2 / 5)   # 2, 4, 5, 0, 3 against {2, 4}
    assert c["per_song"] == {"test": {"count": 5, "exact": pytest.approx(1 / 5), "shift": pytest.approx(3 / 5)}}


def test_a_set_covers_itself():
    c = C.coverage([TEST], [TEST])
    assert c["notes"]["exact"] == c["chords"]["shift"] == 1.0 and c["notes"]["nearest"] == {}
    assert c["positions"] == c["spans"] == c["jumps"] == 1.0


def test_chord_f1_histogram_bins():
    from dexguitar.perform.plots import chord_f1_histogram
    f1 = [0.0, 0.05, 0.1, 0.3, 0.45, 0.5, 0.7, 0.79, 0.8, 0.95, 1.0, 1.0]
    # bins:  0     0    1    3    4     5    7    7     8    9     9    9
    assert chord_f1_histogram(f1) == pytest.approx([c / 12 for c in (2, 1, 0, 1, 1, 1, 0, 2, 1, 3)])
    assert chord_f1_histogram({"x x 0 2 3 2": 0.25, "3 2 0 0 0 3": 1.0}) == [0, 0, 0.5, 0, 0, 0, 0, 0, 0, 0.5]
    with pytest.raises(ValueError):
        chord_f1_histogram([0.5, 1.5])
    with pytest.raises(ValueError):
        chord_f1_histogram({})


def test_chord_histogram_plot(tmp_path):
    from dexguitar.perform.plots import plot_chord_histogram
    out = plot_chord_histogram({"x x 0 2 3 2": 0.25, "3 2 0 0 0 3": 1.0, "x 3 2 0 1 0": 0.85}, tmp_path / "f.png")
    assert out == tmp_path / "f.png"
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
