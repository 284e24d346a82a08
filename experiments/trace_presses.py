"""What the planner's left hand presses, step by step, against each note's goal: the env (evaluation config) played
with a zero residual on a planner version, from a song's start. Each row is one control step: the goal of the note
under the cursor, the frets detected after the step, and the note's left F1 where it ends.

    JAX_PLATFORMS=cpu .venv/bin/python experiments/trace_presses.py ../shared/data/official/notes/beethoven_virus.json \\
        --version 9 --steps 30
"""
import argparse

import jax
import jax.numpy as jnp
import numpy as np

from dexguitar import envs
from dexguitar.motion import feedforward as FF
from dexguitar.music import cursor as CU
from dexguitar.music import load_songs
from dexguitar.music import timeline as TL


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("song", help="a tab file")
    ap.add_argument("--version", type=int, default=FF.LATEST, help="planner version")
    ap.add_argument("--steps", type=int, default=30)
    ap.add_argument("--start", type=int, default=0, help="first step printed")
    args = ap.parse_args()
    config = envs.EnvConfig(feedforward=args.version).evaluation()
    env = envs.make("left", FF.prepare([TL.from_song(s) for s in load_songs([args.song])], config), config)
    step, state, zero = jax.jit(env.step), env.reset(jax.random.PRNGKey(0)), jnp.zeros(env.action_size)
    print("| step | goal | pressed | note F1 |\n|---:|---|---|---:|")
    for t in range(args.start + args.steps):
        goal = np.asarray(CU.current(state.cursor)[0]).tolist()
        state = step(state, zero)
        if t >= args.start:
            f1 = f"{float(state.info['left'][2]):.2f}" if bool(state.info["note_end"]) else ""
            print(f"| {t} | {goal} | {np.asarray(state.info['press']).tolist()} | {f1} |")


if __name__ == "__main__":
    main()
