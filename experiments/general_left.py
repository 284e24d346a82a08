"""Zero-shot evaluation of a general left hand on songs it never trained on: the authors' official songs. Writes,
into --out:

- `general_left.json`: one object per song (`song`, `left`, `chords_above_0.8`, `chords`, `right`, ...) and a last
  one with `song: "overall"`; `left` there is the mean over songs, `left_notes` the mean over all notes;
  `chords_above_0.8` counts every distinct chord of every song once (strictly above 0.8);
- `general_left.md`: the same table, and the left hand's F1 split by where on the neck, how many strings, how long
  and how far from the last position each note is (what to train more of);
- `general_left_chords_left.png`, `general_left_chords_right.png`: the per-chord F1 histograms (the paper's Fig. 5).

  .venv/bin/python experiments/general_left.py --left runs/left-general/policy \
      --notes ../shared/data/official/notes --out out/general_left
"""
import argparse
import json
from pathlib import Path

import numpy as np

from dexguitar.learn import policy as PO
from dexguitar.learn.run import compilation_cache
from dexguitar.music import load_songs
from dexguitar.perform import plots
from dexguitar.perform.evaluate import evaluate

SPLITS = {   # note features and their buckets (inclusive) for the breakdown
    "lowest pressed fret": ("pos", ((0, 0), (1, 3), (4, 6), (7, 10), (11, 15), (16, 22))),
    "pressed strings": ("pressed", ((0, 0), (1, 1), (2, 2), (3, 3), (4, 6))),
    "note length (frames)": ("frames", ((0, 7), (8, 11), (12, 15), (16, 23), (24, 47), (48, 10**6))),
    "frets from the last position": ("jump", ((0, 0), (1, 2), (3, 6), (7, 30))),
}


def features(rows) -> list[dict]:
    """Per sounding note: its left F1 and the features of SPLITS."""
    out, last_pos, last_frame = [], None, 0
    for r in rows:
        frames, last_frame = r["frame"] - last_frame, r["frame"]
        if r["note"] < 0 or r["rest"]:
            continue
        pressed = [f for f in r["frets"] if f > 0]
        pos = min(pressed) if pressed else 0
        jump = abs(pos - last_pos) if pressed and last_pos else 0
        last_pos = pos if pressed else last_pos
        out.append({"f1": r["left"]["f1"], "pos": pos, "pressed": len(pressed), "frames": frames, "jump": jump})
    return out


def breakdown(notes) -> dict:
    f1 = np.array([n["f1"] for n in notes])
    table = {}
    for title, (key, buckets) in SPLITS.items():
        v = np.array([n[key] for n in notes])
        table[title] = [{"range": [lo, hi], "notes": int(((v >= lo) & (v <= hi)).sum()),
                         "f1": float(f1[(v >= lo) & (v <= hi)].mean()) if ((v >= lo) & (v <= hi)).any() else None}
                        for lo, hi in buckets]
    return table


def name(directory) -> str:
    """A policy's name: its folder, or its run's for a run's `policy/` export."""
    d = Path(directory)
    return d.parent.name if d.name == "policy" else d.name


def above(f1s) -> float | None:
    """The fraction of chord F1s strictly above the paper's 0.8 (None for no chords)."""
    f1s = list(f1s)
    return float(np.mean([v > plots.GOOD_F1 for v in f1s])) if f1s else None


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--left", required=True, help="the general left hand: an exported policy or a run directory")
    p.add_argument("--right", default="models/policies/right_mixed", help="the general right hand")
    p.add_argument("--notes", required=True, help="a folder of tabs the hands never trained on")
    p.add_argument("--out", default="out/general_left")
    args = p.parse_args()
    compilation_cache()
    paths = sorted(Path(args.notes).glob("*.json"))
    songs = load_songs(paths)
    res = {}
    for hand, directory in (("left", args.left), ("right", args.right)):
        params, meta = PO.load(directory)
        res[hand] = dict(zip([q.stem for q in paths], evaluate(params, PO.PolicySpec.from_meta(meta), songs).values()))
        res[hand + "_meta"] = {k: meta.get(k) for k in ("iteration", "samples")}
    rows, notes, all_chords = [], [], {"left": [], "right": []}
    for q in paths:
        left, right = res["left"][q.stem]["summary"], res["right"][q.stem]["summary"]
        notes += features(res["left"][q.stem]["notes"])
        for h, s in (("left", left), ("right", right)):
            all_chords[h] += list(s["chords"].values())
        rows.append({"song": q.stem, "left": left["left"]["f1"], "chords_above_0.8": above(left["chords"].values()),
                     "chords": len(left["chords"]), "left_notes": left["left"]["notes"],
                     "right": right["right"]["f1"], "right_chords_above_0.8": above(right["chords"].values())})
    overall = {"song": "overall", "left": float(np.mean([r["left"] for r in rows])),
               "left_notes": float(np.mean([n["f1"] for n in notes])),
               "chords_above_0.8": above(all_chords["left"]),
               "chords": len(all_chords["left"]), "right": float(np.mean([r["right"] for r in rows])),
               "right_chords_above_0.8": above(all_chords["right"]),
               "left_policy": str(args.left), "right_policy": str(args.right), **{
                   f"{h}_{k}": v for h in ("left", "right") for k, v in res[h + "_meta"].items()},
               "breakdown_left": breakdown(notes)}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "general_left.json").write_text(json.dumps(rows + [overall], indent=1))
    for h in ("left", "right"):
        plots.plot_chord_histogram(all_chords[h], out / f"general_left_chords_{h}.png",
                                   f"{h} hand ({name(getattr(args, h))}), per chord, official songs, zero-shot")
    fmt = lambda v: "–" if v is None else f"{v:.3f}"                      # noqa: E731
    pct = lambda v: "–" if v is None else f"{v:.0%}"                      # noqa: E731
    md = ["# The general pair on songs it never trained on", "",
          "```bash", f".venv/bin/python experiments/general_left.py --left {args.left} --right {args.right} "
          f"--notes {args.notes} --out {args.out}", "```", "",
          f"left: `{args.left}` ({overall['left_samples'] or 0:,} samples); right: `{args.right}`", "",
          "| song | left | chords > 0.8 (of) | right | right chords > 0.8 |", "|---|---:|---:|---:|---:|"]
    md += [f"| {r['song']} | {fmt(r['left'])} | {pct(r['chords_above_0.8'])} ({r['chords']}) | {fmt(r['right'])} | "
           f"{pct(r['right_chords_above_0.8'])} |" for r in rows + [overall]]
    md += ["", f"Left F1 over all {len(notes)} sounding notes: {overall['left_notes']:.3f} (open-string notes played "
           "cleanly included; the per-song F1 leaves them out). By note:", ""]
    for title, buckets in overall["breakdown_left"].items():
        ranges = (f"{lo}–{hi}" if hi < 1000 else f"{lo}+" for lo, hi in (b["range"] for b in buckets))
        md += [f"| {title} | " + " | ".join(ranges) + " |",
               "|---|" + "---:|" * len(buckets),
               "| notes | " + " | ".join(str(b["notes"]) for b in buckets) + " |",
               "| left F1 | " + " | ".join(fmt(b["f1"]) for b in buckets) + " |", ""]
    (out / "general_left.md").write_text("\n".join(md))
    print("\n".join(md))


if __name__ == "__main__":
    main()
