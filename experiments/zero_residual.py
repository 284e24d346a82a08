"""A residual hand whose residual is zero (`EnvConfig(feedforward=True)` for the left hand, `right_feedforward=True`
for the right: it plays exactly as the IK planner, `dexguitar/planner/`), as an exported policy: the start
of every residual hand, and the yardstick of a general one, since the planner has seen no song.
`models/policies/left_general` and `right_general` are such policies (docs/planner.md):

    .venv/bin/python experiments/zero_residual.py models/policies/left_general
    .venv/bin/python experiments/zero_residual.py models/policies/right_general --hand right
"""
import argparse

import numpy as np

from dexguitar.envs import EnvConfig, make
from dexguitar.learn import policy as PO
from dexguitar.music import library

LOG_STD = -6.2        # std 0.002 of a half range: free for the planner (docs/results.md), unlike 0.02


def main(out: str, hand: str = "left", log_std: float = LOG_STD) -> None:
    env = make(hand, [library.load("ode_to_joy")], EnvConfig()).env.env    # for its layout and action size only
    spec = PO.PolicySpec("policy", hand, env.action_size, env.layout, feedforward=hand == "left",
                         right_feedforward=hand == "right")
    params = PO.template(spec)                                                # every weight zero: mu = 0
    params["obs_norm"]["var"] = np.ones_like(params["obs_norm"]["var"])
    # A zero log-std head would give std 1: sampled actions, as a synchronizer trains on, would flail.
    params = PO.with_log_std(params, log_std)
    PO.export(out, params, dict(spec.to_meta(), iteration=0, samples=0))
    print(f"wrote {out}: a zero residual on the {hand} planner, sampling std {np.exp(log_std):.2g}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out")
    ap.add_argument("--hand", choices=("left", "right"), default="left")
    ap.add_argument("--log-std", type=float, default=LOG_STD, help="the sampling std's log (default: std 0.002)")
    a = ap.parse_args()
    main(a.out, a.hand, a.log_std)
