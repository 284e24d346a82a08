"""experiments/general_left.py's breakdown of a hand's notes (where on the neck, how many strings, how long, how far
from the last position): hand-built note rows, features worked out by hand."""
import runpy
from pathlib import Path

G = runpy.run_path(str(Path(__file__).resolve().parents[1] / "experiments" / "general_left.py"))
M = -1


def row(note, frame, frets, f1, rest=False):
    return {"note": note, "frame": frame, "frets": frets, "chord": False, "rest": rest, "left": {"f1": f1}}


ROWS = [row(-1, 4, None, 1.0),                          # the grace rest: only its end frame counts
        row(0, 16, [M, M, 3, M, M, M], 1.0),            # fret 3, 12 frames, no earlier position
        row(1, 28, [M] * 6, 1.0, rest=True),            # a rest: left out, but the next note starts after it
        row(2, 40, [0, 5, 7, M, M, M], 0.5),            # lowest pressed fret 5, two strings, 2 frets from 3
        row(3, 45, [0, 0, M, M, M, M], 1.0),            # open strings only: position unchanged
        row(4, 60, [12, M, M, M, M, M], 0.0)]           # 7 frets from 5 (the open note kept 5)


def test_note_features():
    got = [(n["pos"], n["pressed"], n["frames"], n["jump"], n["f1"]) for n in G["features"](ROWS)]
    assert got == [(3, 1, 12, 0, 1.0), (5, 2, 12, 2, 0.5), (0, 0, 5, 0, 1.0), (12, 1, 15, 7, 0.0)]


def test_breakdown_by_neck_region():
    by_fret = G["breakdown"](G["features"](ROWS))["lowest pressed fret"]
    assert [(b["range"], b["notes"], b["f1"]) for b in by_fret] == [
        ([0, 0], 1, 1.0), ([1, 3], 1, 1.0), ([4, 6], 1, 0.5), ([7, 10], 0, None), ([11, 15], 1, 0.0),
        ([16, 22], 0, None)]


def test_chords_above_counts_strictly_above():
    assert G["above"]([0.8, 0.81, 1.0, 0.2]) == 0.5
    assert G["above"]([]) is None
