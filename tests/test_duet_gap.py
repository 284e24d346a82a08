"""experiments/duet_gap.py's count of why notes are lost for both hands: a hand-made report with one note of each
kind, so the counts are known without playing."""
import runpy
from pathlib import Path

G = runpy.run_path(str(Path(__file__).resolve().parents[1] / "experiments" / "duet_gap.py"))


def note(left, right, both, verdict, why="", targets=1, rest=False):
    f1 = lambda x: {"f1": x, "targets": targets}   # noqa: E731
    return {"left": f1(left), "right": f1(right), "both": f1(both), "verdict": verdict, "why": why, "rest": rest}


def test_lost_notes_are_counted_by_reason_and_by_each_hand_alone():
    report = {"title": "t", "summary": {h: {"f1": 0.5} for h in ("left", "right", "both")}, "notes": [
        note(1, 1, 1, "right"),
        note(1, 1, 0, "wrong", "picked before the press"),                 # each hand right: lost to timing
        note(1, 1, 0, "late", "picked at frame 9 of 12"),                  # each hand right: lost to timing
        note(0, 1, 0, "wrong", "wrong fret"),                              # the left hand's own fault
        note(1, 1, 0, "late", "picked at frame 5 of 6"),
        note(1, 1, 1, "rest", rest=True, targets=0),                      # not a note
    ]}
    t = G["tally"](report)
    assert (t["notes"], t["lost"], t["lost_with_each_hand_right"]) == (5, 4, 3)
    assert t["reasons"] == {"wrong: picked before the press": 1, "late: picked": 2, "wrong: wrong fret": 1}
    assert t["reasons_with_each_hand_right"] == {"wrong: picked before the press": 1, "late: picked": 2}
