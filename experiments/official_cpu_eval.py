"""The official-songs table's CPU columns (issue 10): each hand alone and the pair unsynchronized, on every tab of a
folder, by the paper's rules. Writes JSON {"left"|"right"|"both_before": {song: summary}}.

  .venv/bin/python experiments/official_cpu_eval.py --notes ../shared/data/official/notes \
      --left models/policies/left_official15 --right models/policies/right_mixed --out /tmp/official.json
"""
import argparse
import json
from pathlib import Path

from dexguitar.learn import policy as PO
from dexguitar.learn.run import compilation_cache
from dexguitar.music import load_songs
from dexguitar.perform.evaluate import evaluate
from dexguitar.perform.play import pair

p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
p.add_argument("--notes", required=True, help="a folder of tabs (or tab files, with --songs)")
p.add_argument("--songs", nargs="*", help="only these song stems")
p.add_argument("--left", required=True)
p.add_argument("--right", required=True)
p.add_argument("--out", required=True)
args = p.parse_args()
compilation_cache()
paths = sorted(Path(args.notes).glob("*.json"))
paths = [q for q in paths if not args.songs or q.stem in args.songs]
songs = load_songs(paths)
out = {}
for name, directory in (("left", args.left), ("right", args.right)):
    params, meta = PO.load(directory)
    results = evaluate(params, PO.PolicySpec.from_meta(meta), songs)
    out[name] = {q.stem: r["summary"] for q, r in zip(paths, results.values())}
results = evaluate(*pair(args.left, args.right), songs)
out["both_before"] = {q.stem: r["summary"] for q, r in zip(paths, results.values())}
Path(args.out).write_text(json.dumps(out, indent=1))
for stem in out["left"]:
    b = out["both_before"][stem]
    print(f"{stem:30s} left {out['left'][stem]['left']['f1']:.3f}  right {out['right'][stem]['right']['f1']:.3f}  "
          f"both before {b['both']['f1']:.3f}")
