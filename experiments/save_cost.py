"""Seconds of the two saves that follow every training chunk (the whole state, then the compact one) for a left-hand
state of N envs, on this machine's disk (issue 12). On the 2-core VM, 4,096 envs (262 MiB): 0.44-0.48 s whole
(0.76 s the first time) and 0.11-0.16 s compact.

    JAX_PLATFORMS=cpu python experiments/save_cost.py 4096
"""
import sys
import tempfile
import time
from pathlib import Path

import jax

from dexguitar.learn import checkpoint as C
from dexguitar.learn.run import compact
from dexguitar.learn.trainer import Trainer, TrainConfig
from dexguitar.music import library
from dexguitar.music import timeline as TL


def main(n: int) -> None:
    cfg = TrainConfig(hand="left", num_envs=n, horizon=8, minibatch=n, iterations_per_call=1)
    state = Trainer(cfg, [TL.from_song(library.load("ode_to_joy"))], None).init()
    print(f"{n} envs: state {sum(x.nbytes for x in jax.tree.leaves(state)) / 2**20:.0f} MiB")
    folder = Path(tempfile.mkdtemp())
    for step in (1, 2, 3):
        t0 = time.perf_counter()
        C.save(folder / "ckpt", step, state)
        t1 = time.perf_counter()
        C.save(folder / "resume", step, state, keep=1, only=compact)
        print(f"save {step}: whole {t1 - t0:.2f} s, compact {time.perf_counter() - t1:.2f} s")


if __name__ == "__main__":
    main(int(sys.argv[1]))
