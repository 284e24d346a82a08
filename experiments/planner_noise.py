"""How exact the left hand's actions must be: the IK planner's own plans (`learn.windows`), rolled out with Gaussian
noise added to every action, on training windows of the general material (EnvConfig defaults), and with the noise on
the wrist's 6 DoFs or on the other 21 alone. Mean per-note precision, recall and F1 over the windows' notes.

    XLA_FLAGS="--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1" JAX_PLATFORMS=cpu \\
      .venv/bin/python experiments/planner_noise.py          # 16 windows, about 4 minutes on 2 cores
    ... experiments/planner_noise.py 0 0.001 0.002 0.005 0.01 0.02   # only these stds, on every DoF
"""
import sys

import jax
import jax.numpy as jnp
import numpy as np

from dexguitar import envs
from dexguitar.learn import windows as D
from dexguitar.learn import policy as PO
from dexguitar.music import procedural
from dexguitar.music import timeline as TL

WINDOWS = 16


def main():
    songs = procedural.material("left", "general", 0, 2000)
    env = envs.ENVS["left"](TL.stack([TL.from_song(s) for s in songs]), envs.EnvConfig())
    keys = D.window_keys(jax.random.PRNGKey(0), WINDOWS)
    acts, valid = D.pad_plans(D.plan_windows(env, keys, workers=1), env.config.episode_frames)
    spec = PO.PolicySpec("policy", "left", env.action_size, env.layout)
    rollout = D.rollout_fn(env, spec)

    def run(actions):          # the plans as given: no noise of the rollout's own
        _, _, scores, closed = D.chunked(rollout, PO.template(spec), keys, jnp.asarray(actions), False,
                                         jnp.float32(0.0), jax.random.PRNGKey(0))
        return D.window_scores(scores, closed, valid)

    noise = np.random.default_rng(0).normal(size=acts.shape).astype(np.float32)
    wrist = np.r_[np.ones(6), np.zeros(21)].astype(np.float32)
    print("| noise std (half ranges) | on | precision | recall | F1 |\n|---:|---|---:|---:|---:|")
    rows = [(0.0, "-", 1.0), (0.01, "all", 1.0), (0.02, "all", 1.0), (0.05, "all", 1.0),
            (0.02, "wrist (6)", wrist), (0.02, "thumb and fingers (21)", 1.0 - wrist)]
    if len(sys.argv) > 1:
        rows = [(float(v), "all" if float(v) else "-", 1.0) for v in sys.argv[1:]]
    for std, part, mask in rows:
        p, r, f = run(acts + std * noise * mask)
        print(f"| {std:g} | {part} | {p:.3f} | {r:.3f} | {f:.3f} |", flush=True)


if __name__ == "__main__":
    main()
