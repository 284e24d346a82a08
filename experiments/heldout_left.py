"""Left F1 of a left hand on held-out procedural songs of the general material (a seed that training never uses): what
a planner version or a trained general hand is judged by beside the official songs. On a CPU `evaluate` plays them 16
at a time (`perform.evaluate.CPU_HAND_SONGS`), about 40 s a chunk once planned.

    JAX_PLATFORMS=cpu .venv/bin/python experiments/heldout_left.py models/policies/left_general out.json --seed 2 --songs 48
"""
import argparse
import json
import statistics

from dexguitar.learn import policy as PO
from dexguitar.music import procedural
from dexguitar.perform.evaluate import evaluate

if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("ckpt")
    p.add_argument("out")
    p.add_argument("--seed", type=int, default=2)
    p.add_argument("--songs", type=int, default=48)
    args = p.parse_args()
    params, meta = PO.load(args.ckpt)
    spec = PO.PolicySpec.from_meta(meta)
    songs = procedural.material("left", "general", args.seed, args.songs)
    out = {k: v["summary"] for k, v in evaluate(params, spec, songs).items()}
    json.dump(out, open(args.out, "w"), indent=1)
    print(f"{len(out)} songs, mean left F1 {statistics.mean(v['left']['f1'] for v in out.values()):.4f}")
