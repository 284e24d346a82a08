"""How much of a left hand's F1 belongs to one exact trajectory? Each policy is played as it is, and again with a
constant offset drawn once per draw (Gaussian, `--rms` of a half range per action) added to its mean action, on
held-out procedural songs of the general material and on any tab files given: left F1 per song, per draw.

An offset of 4e-5 of a half range moves a fingertip by a few micrometres, far below anything a hand could mean. If
such offsets cost F1 on average, the unperturbed score was selected on its exact trajectory (the planner searches its
fingerings in MuJoCo trials of the exact plan), and a trained residual, itself one such perturbation of the planner,
must be compared with the perturbed draws, not with the one exact rollout.

    python experiments/perturbed_eval.py models/policies/left_general runs/anchored/policy --out OUT.json \\
        --procedural 48 --seed 2 --song ../shared/data/official/notes/*.json --rms 4e-5 --draws 4
"""
import argparse
import json
import statistics

import numpy as np

from dexguitar.learn import policy as PO
from dexguitar.music import library, procedural
from dexguitar.perform.evaluate import evaluate


def offset(params: dict, shift: np.ndarray) -> dict:
    """The policy with `shift` (half ranges, after its action scale) added to its mean action's bias."""
    mu = params["policy"]["params"]["mu"]
    return {**params, "policy": {**params["policy"], "params": {**params["policy"]["params"],
                                                                "mu": dict(mu, bias=np.asarray(mu["bias"]) + shift)}}}


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("policies", nargs="+")
    ap.add_argument("--out", required=True)
    ap.add_argument("--procedural", type=int, default=48)
    ap.add_argument("--seed", type=int, default=2, help="of the procedural songs (training uses 0)")
    ap.add_argument("--pick", help="comma-separated indices of the procedural songs to play (default: all)")
    ap.add_argument("--song", nargs="*", default=[])
    ap.add_argument("--rms", type=float, default=4e-5)
    ap.add_argument("--draws", type=int, default=4)
    a = ap.parse_args()
    songs = procedural.material("left", "general", a.seed, a.procedural)
    if a.pick:
        songs = [songs[int(i)] for i in a.pick.split(",")]
    songs += library.load_songs(a.song)
    out = {}
    for path in a.policies:
        params, meta = PO.load(path)
        spec = PO.PolicySpec.from_meta(meta)
        size = np.asarray(params["policy"]["params"]["mu"]["bias"]).shape
        for draw in range(a.draws + 1):                     # draw 0: the policy as it is
            shift = np.random.default_rng(draw).normal(size=size) * a.rms / spec.scale if draw else 0.0
            res = evaluate(offset(params, shift), spec, songs)
            f1 = {k: v["summary"]["left"]["f1"] for k, v in res.items()}
            out[f"{path} draw {draw}"] = f1
            proc = [v for k, v in f1.items() if k.startswith("left-general")]
            other = [v for k, v in f1.items() if not k.startswith("left-general")]
            print(f"{path} draw {draw}: procedural {statistics.mean(proc):.4f}"
                  + (f", tabs {statistics.mean(other):.4f}" if other else ""), flush=True)
            json.dump(out, open(a.out, "w"), indent=1)
