"""Does a trained residual play better, or only survive its own exploration noise better? Two left-hand residual
policies on the planner (e.g. the shipped zero residual and a PPO-trained one) on the same training windows of
held-out general material, each rolled out with its mean action plus Gaussian noise of several stds (half ranges):
mean per-note precision, recall and F1 over the windows' notes. PPO judges a policy by its noisy rollouts; the
official evaluation by its mean action.

    JAX_PLATFORMS=cpu .venv/bin/python experiments/residual_noise.py models/policies/left_general runs/scaled/policy
    ... --stds 0 0.002 0.005 --windows 32 --seed 1
"""
import argparse

import jax
import jax.numpy as jnp

from dexguitar import envs
from dexguitar.learn import windows as D
from dexguitar.learn import policy as PO
from dexguitar.motion import feedforward as FF
from dexguitar.music import procedural
from dexguitar.music import timeline as TL


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("policies", nargs="+", help="exported left-hand residual policies (same planner version)")
    ap.add_argument("--stds", type=float, nargs="+", default=[0.0, 0.002, 0.005])
    ap.add_argument("--windows", type=int, default=32)
    ap.add_argument("--songs", type=int, default=16, help="procedural general songs to draw the windows from")
    ap.add_argument("--seed", type=int, default=1, help="of the songs (training uses 0)")
    args = ap.parse_args()

    loaded = [PO.load(p) for p in args.policies]
    specs = [PO.PolicySpec.from_meta(m) for _, m in loaded]
    if len({s.feedforward for s in specs}) != 1 or not specs[0].feedforward:
        raise SystemExit("the policies must be residuals on one planner version (policy.json 'feedforward')")
    config = envs.EnvConfig(shift_prob=0.0, tempo_prob=0.0, feedforward=specs[0].feedforward)  # the residual recipe
    songs = procedural.material("left", "general", args.seed, args.songs)
    env = envs.make("left", FF.prepare([TL.from_song(s) for s in songs], config), config)
    keys = jax.random.split(jax.random.PRNGKey(0), args.windows)
    frames = env.config.episode_frames
    no_plan = jnp.zeros((args.windows, frames, env.action_size))
    valid = jnp.ones((args.windows, frames), bool)
    print("| policy | noise std | precision | recall | F1 |\n|---|---:|---:|---:|---:|")
    for path, (params, _), spec in zip(args.policies, loaded, specs):
        rollout = D.rollout_fn(env, spec)
        for std in args.stds:
            _, _, scores, closed = D.chunked(rollout, params, keys, no_plan, True, jnp.float32(std),
                                             jax.random.PRNGKey(1))
            p, r, f = D.window_scores(scores, closed, valid)
            print(f"| `{path}` | {std:g} | {p:.3f} | {r:.3f} | {f:.3f} |", flush=True)


if __name__ == "__main__":
    main()
