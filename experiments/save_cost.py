"""Seconds that the two saves after every training chunk (the whole state, then the compact one) hold the run up,
for a left-hand state of N envs on this machine's disk: written at once (`checkpoint.save`), and in the background
as training saves them (`checkpoint.Saver`, here with a chunk of `--chunk` seconds between saves, time.sleep standing
in for the device's work). Issue 12's 4-H100 runs lost 1.35 s a chunk on one GPU and 3.8 s on four to saving whole.

    JAX_PLATFORMS=cpu python experiments/save_cost.py 4096 --chunk 3
"""
import argparse
import tempfile
import time
from pathlib import Path

import jax

from dexguitar.learn import checkpoint as C
from dexguitar.learn.run import compact
from dexguitar.learn.trainer import Trainer, TrainConfig
from dexguitar.music import library
from dexguitar.music import timeline as TL


def main(n: int, chunk: float) -> None:
    cfg = TrainConfig(hand="left", num_envs=n, horizon=8, minibatch=n, iterations_per_call=1)
    state = Trainer(cfg, [TL.from_song(library.load("ode_to_joy"))], None).init()
    print(f"{n} envs: state {sum(x.nbytes for x in jax.tree.leaves(state)) / 2**20:.0f} MiB")
    folder = Path(tempfile.mkdtemp())
    for step in (1, 2, 3):
        t0 = time.perf_counter()
        C.save(folder / "ckpt", step, state)
        t1 = time.perf_counter()
        C.save(folder / "resume", step, state, keep=1, only=compact)
        print(f"at once, save {step}: whole {t1 - t0:.2f} s, compact {time.perf_counter() - t1:.2f} s")
    with C.Saver(folder / "bg") as whole, C.Saver(folder / "bg_resume", keep=1, only=compact) as part:
        for step in (1, 2, 3, 4):
            t0 = time.perf_counter()
            whole.save(step, state)
            t1 = time.perf_counter()
            part.save(step, state)
            print(f"background, save {step}: whole {t1 - t0:.2f} s, compact {time.perf_counter() - t1:.2f} s")
            time.sleep(chunk)
        t0 = time.perf_counter()
    print(f"background: the last writes finished {time.perf_counter() - t0:.2f} s after the last chunk")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("envs", type=int)
    ap.add_argument("--chunk", type=float, default=3.0, help="seconds between saves (a chunk's work)")
    a = ap.parse_args()
    main(a.envs, a.chunk)
