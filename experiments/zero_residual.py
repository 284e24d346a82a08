"""A residual left hand whose residual is zero (`EnvConfig(feedforward=v)`: it plays exactly as the IK planner v), as
an exported policy: the start of every residual left hand, and the yardstick of a general one (issue 11), since the
planner has seen no song.

    .venv/bin/python experiments/zero_residual.py /tmp/zero_residual [VERSION, default the latest planner] [LOG_STD]
    .venv/bin/python experiments/general_left.py --left /tmp/zero_residual --notes ../shared/data/official/notes \
        --out experiments/results/general_left/zero_residual
"""
import sys

import numpy as np

from dexguitar.envs import EnvConfig, make
from dexguitar.learn import policy as PO
from dexguitar.learn.distill import with_log_std
from dexguitar.motion import feedforward as FF
from dexguitar.music import library

LOG_STD = -6.2        # std 0.002 of a half range: free for the planner (results/planner_noise.md), unlike 0.02


def main(out: str, version: int = FF.LATEST, log_std: float = LOG_STD) -> None:
    env = make("left", [library.load("ode_to_joy")], EnvConfig()).env.env    # for its layout and action size only
    spec = PO.PolicySpec("policy", "left", env.action_size, env.layout, feedforward=version)
    params = PO.template(spec)                                                # every weight zero: mu = 0
    params["obs_norm"]["var"] = np.ones_like(params["obs_norm"]["var"])
    # A zero log-std head would give std 1: sampled actions, as a synchronizer trains on, would flail.
    params = with_log_std(params, log_std)
    PO.export(out, params, dict(spec.to_meta(), iteration=0, samples=0))
    print(f"wrote {out}: a zero residual on the planner, version {version}, sampling std {np.exp(log_std):.2g}")


if __name__ == "__main__":
    main(sys.argv[1], *(int(v) for v in sys.argv[2:3]), *(float(v) for v in sys.argv[3:4]))
