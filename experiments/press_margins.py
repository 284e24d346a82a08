"""How much room the planner's presses leave (`rewards.press_margins`): the left hand played with a zero residual from a
song's start (evaluation config), and at every control step where a note has been held for 3 steps, each pressed
string's margin to the 6 mm press distance and its fret wires, and each open string's clearance. A margin under
1 mm is where a few micrometres of fingertip flip a note (results/general_left/session30/).

    JAX_PLATFORMS=cpu .venv/bin/python experiments/press_margins.py --procedural 8 --song ../shared/data/official/notes/snow.json
"""
import argparse

import jax
import jax.numpy as jnp
import numpy as np

from dexguitar import envs
from dexguitar.envs import rewards as R
from dexguitar.motion import feedforward as FF
from dexguitar.music import cursor as CU
from dexguitar.music import library, procedural
from dexguitar.music import timeline as TL


def margins(song, version: int):
    """(goals (T, 6), margins (T, 6) in m) of the steps after which a note has been under the cursor for 3 steps."""
    config = envs.EnvConfig(feedforward=version).evaluation()
    env = envs.make("left", FF.prepare([TL.from_song(song)], config), config)

    @jax.jit
    def step(state):
        goal = CU.current(state.cursor)[0]
        state = env.step(state, jnp.zeros(env.action_size))
        return state, goal, R.press_margins(env.segments(state.body.data, env.hands[0]), goal, env.guitar)

    state, goals, out = env.reset(jax.random.PRNGKey(0)), [], []
    while not (bool(state.done) or bool(state.cursor.over)):
        state, goal, m = step(state)
        goals.append(np.asarray(goal))
        out.append(np.asarray(m))
    g, m = np.stack(goals), np.stack(out)
    held = np.zeros(len(g), bool)
    held[3:] = np.all([(g[3:] == g[3 - i:len(g) - i]).all(1) for i in (1, 2, 3)], axis=0)
    return g[held], m[held]


def row(name, g, m):
    cells = []
    for sel in (g > 0, g < 0):
        mm = m[sel] * 1000
        cells += [f"{len(mm)}"] + ([f"{np.mean(mm < 0):.2f}", f"{np.mean((mm >= 0) & (mm < 1)):.2f}",
                                    f"{np.median(mm):.2f}"] if len(mm) else ["", "", ""])
    return f"| {name} | " + " | ".join(cells) + " |"


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--procedural", type=int, default=0, help="held-out songs of the general material (seed 2)")
    ap.add_argument("--song", nargs="*", default=[])
    ap.add_argument("--version", type=int, default=FF.LATEST, help="planner version")
    a = ap.parse_args()
    songs = procedural.material("left", "general", 2, a.procedural) if a.procedural else []
    songs += library.load_songs(a.song)
    print("| song | pressed: string-steps | below 0 | 0-1 mm | median (mm) | open: string-steps | below 0 | 0-1 mm "
          "| median (mm) |\n|---|" + "---:|" * 8, flush=True)
    for s in songs:
        print(row(s.title, *margins(s, a.version)), flush=True)
