"""How much margin the planner's plans of whole songs have: left F1 of a planner version (a zero residual) on each
song, with Gaussian noise of each std added to every action at every step (fresh draws per seed). A plan that loses
much to a noise far below the frozen left hand's sampling std (0.002 in `left_general`) also loses to the float
differences between a GPU and a CPU program.

    JAX_PLATFORMS=cpu .venv/bin/python experiments/planner_noise_songs.py ../shared/data/official/notes/snow.json \\
        --stds 0 0.0003 0.001 --seeds 2          # about a minute a song on 2 cores
"""
import argparse
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from dexguitar import envs
from dexguitar.motion import feedforward as FF
from dexguitar.music import load_songs
from dexguitar.music import timeline as TL
from dexguitar.perform.evaluate import note_scores, rollout_song


def song_f1(tab: str, version: int, stds, seeds: int) -> dict:
    """{std: [left F1 per seed]} of one song (one draw for std 0)."""
    config = envs.EnvConfig(feedforward=version).evaluation()
    songs = load_songs([tab])
    batch = FF.prepare(TL.batch([TL.from_song(s) for s in songs]), config)
    env = envs.make("left", batch, config)
    frames = int(batch.plan.frames[0]) + config.rest_frames

    @jax.jit
    def play(key, std):
        return rollout_song(env, lambda obs, k: std * jax.random.normal(k, (env.action_size,)), 0, frames,
                            xs=jax.random.split(key, frames))

    out = {}
    for std in stds:
        out[std] = []
        for seed in range(seeds if std > 0 else 1):
            info, alive = jax.tree.map(np.asarray, play(jax.random.PRNGKey(seed), jnp.float32(std)))
            n = int(alive.sum())
            rows = note_scores({k: v[:n] for k, v in info.items()}, songs[0], ("left",))
            out[std].append(float(np.mean([r["left"]["f1"] for r in rows
                                           if r["left"]["targets"] + r["left"]["predicted"] > 0])))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("tabs", nargs="+", help="tab files")
    ap.add_argument("--version", type=int, default=FF.LATEST, help="planner version")
    ap.add_argument("--stds", type=float, nargs="+", default=[0.0, 0.0003, 0.001])
    ap.add_argument("--seeds", type=int, default=2)
    args = ap.parse_args()
    print("| song | " + " | ".join(f"std {s:g}" for s in args.stds) + " |\n|---|" + "---:|" * len(args.stds))
    for tab in args.tabs:
        f1 = song_f1(tab, args.version, args.stds, args.seeds)
        cells = [" / ".join(f"{v:.3f}" for v in f1[s]) for s in args.stds]
        print(f"| {Path(tab).stem} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
