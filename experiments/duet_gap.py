"""Why two hands that each play a song well play it worse together.

Reads the per-note reports that `dexguitar play` writes (`<out>-report.json`) and counts, over the notes where the
both-hands F1 is below 1, the verdict and its reason (`perform/play.py`: "picked before the press", "late",
"wrong fret", "released early", "missed", "extra pick", ...), split by whether each hand, judged alone on the same
rollout, played that note right. A note that both hands play right alone but not together was lost to timing
between them: what a synchronizer is for.

    dexguitar play --left models/policies/left_general --right models/policies/right_mixed --song S.json \
        --frames-only --out /tmp/S
    python experiments/duet_gap.py /tmp/*-report.json
"""
import argparse
import json
from collections import Counter


def tally(report: dict) -> dict:
    notes = [n for n in report["notes"] if not n["rest"] and n["both"]["targets"] > 0]
    lost = [n for n in notes if n["both"]["f1"] < 1.0]
    alone_ok = [n for n in lost if n["left"]["f1"] >= 1.0 and n["right"]["f1"] >= 1.0]
    return {"song": report["title"], "notes": len(notes), "both_f1": report["summary"]["both"]["f1"],
            "left_f1": report["summary"]["left"]["f1"], "right_f1": report["summary"]["right"]["f1"],
            "lost": len(lost), "lost_with_each_hand_right": len(alone_ok),
            "reasons": Counter(map(reason, lost)), "reasons_with_each_hand_right": Counter(map(reason, alone_ok))}


def reason(note: dict) -> str:
    """The verdict and its reason without the frame numbers ("late: picked at frame 7 of 12" -> "late: picked")."""
    return f"{note['verdict']}: {note['why'].split(' at frame')[0]}" if note["why"] else note["verdict"]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("reports", nargs="+")
    args = p.parse_args()
    for path in args.reports:
        t = tally(json.load(open(path)))
        print(f"{t['song']}: {t['notes']} notes, F1 left {t['left_f1']:.3f} right {t['right_f1']:.3f} both "
              f"{t['both_f1']:.3f}; {t['lost']} notes not right for both, {t['lost_with_each_hand_right']} of them "
              "right for each hand alone")
        for reason, k in t["reasons"].most_common():
            print(f"    {k:4d}  {reason}")
        for reason, k in t["reasons_with_each_hand_right"].most_common():
            print(f"    {k:4d}  (each hand right alone) {reason}")


if __name__ == "__main__":
    main()
