"""A residual hand whose residual is zero (`EnvConfig(feedforward=v)` for the left hand, `right_feedforward=v` for the
right: it plays exactly as the IK planner v), as an exported policy: the start of every residual hand, and the
yardstick of a general one (issue 11), since the planner has seen no song. `models/policies/left_general` and
`right_general` are such policies.

    .venv/bin/python experiments/zero_residual.py /tmp/zero_residual [VERSION] [LOG_STD] [--hand right]
    .venv/bin/python experiments/general_left.py --left /tmp/zero_residual --notes ../shared/data/official/notes \
        --out experiments/results/general_left/zero_residual
"""
import argparse

import numpy as np

from dexguitar.envs import EnvConfig, make
from dexguitar.learn import policy as PO
from dexguitar.motion import planner
from dexguitar.music import library

LOG_STD = -6.2        # std 0.002 of a half range: free for the planner (results/planner_noise.md), unlike 0.02


def main(out: str, hand: str = "left", version: int = 0, log_std: float = LOG_STD) -> None:
    version = version or (planner.LATEST if hand == "left" else planner.RIGHT_LATEST)
    env = make(hand, [library.load("ode_to_joy")], EnvConfig()).env.env    # for its layout and action size only
    spec = PO.PolicySpec("policy", hand, env.action_size, env.layout, feedforward=version if hand == "left" else 0,
                         right_feedforward=version if hand == "right" else 0)
    params = PO.template(spec)                                                # every weight zero: mu = 0
    params["obs_norm"]["var"] = np.ones_like(params["obs_norm"]["var"])
    # A zero log-std head would give std 1: sampled actions, as a synchronizer trains on, would flail.
    params = PO.with_log_std(params, log_std)
    PO.export(out, params, dict(spec.to_meta(), iteration=0, samples=0))
    print(f"wrote {out}: a zero residual on the {hand} planner, version {version}, sampling std {np.exp(log_std):.2g}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out")
    ap.add_argument("--hand", choices=("left", "right"), default="left")
    ap.add_argument("version", type=int, nargs="?", default=0, help="the planner's version (default: the latest)")
    ap.add_argument("log_std", type=float, nargs="?", default=LOG_STD)
    a = ap.parse_args()
    main(a.out, a.hand, a.version, a.log_std)
