"""Where a GSync run's compile seconds go (issue 10, "compile once"): building the trainer (planning included), its
first state, then the training chunk's trace, lowering and XLA compile (or load from the persistent cache), each
timed apart. Run it twice with the same DEXGUITAR_CACHE: the first process compiles, the second loads.

    DEXGUITAR_CACHE=/tmp/xla python experiments/compile_split.py SONG.json [ENVS [RUNS]]

ENVS >= 512 (minibatch 4096), 0 for the config's. RUNS > 0 also times that many calls of the compiled chunk after one
warm-up call (samples/s), to weigh XLA flags that compile faster against the speed of what they compile.
RESET_STUB=1 replaces the auto-reset by one that computes no MJX kinematics (a new window's cursor on the finished
body): what the reset's second kinematics inside every step costs in compile seconds and samples/s, not a way to
train. Prints one JSON line (seconds). `device/compile_split.sh` ran it three times on an H100
(`results/general_left/session24/compile_split/`), `device/compile_flags.sh` once per XLA flag set,
`device/reset_cost.sh` with and without the stub, each with an empty cache.
"""
import contextlib
import dataclasses
import json
import os
import sys
import time

import jax

from dexguitar.cli import load_config, load_motion, load_song, reference_frames
from dexguitar.learn import policy as PO
from dexguitar.learn.devices import Placement
from dexguitar.learn.run import compilation_cache
from dexguitar.learn.sync import SyncTrainer
from dexguitar.music import timeline as TL


@contextlib.contextmanager
def timed(out: dict, stage: str):
    """Time the block as `out[stage]` (seconds) and print the stages so far to stderr."""
    t = time.perf_counter()
    yield
    out[stage] = time.perf_counter() - t
    print(json.dumps({k: round(v, 1) for k, v in out.items()}), file=sys.stderr, flush=True)


def stub_reset() -> None:
    """AutoReset without the fresh state's kinematics: the finished episode's body goes on under a new window."""
    import jax.numpy as jnp

    from dexguitar.envs import wrappers as W
    from dexguitar.music import cursor as CU

    def step(self, state, action):
        s = self.env.step(state, action)
        done = s.done | (s.lifetime >= self.env.config.episode_frames)
        key, k_win = jax.random.split(s.key)
        cursor = W.tree_where(done, CU.start(self.env.sample_window(k_win)), s.cursor)
        return s.replace(cursor=cursor, lifetime=jnp.where(done, 0, s.lifetime), done=done, key=key)
    W.AutoReset.step = step


def main(song_file: str, envs: int = 0, runs: int = 0) -> dict:
    compilation_cache(os.environ.get("DEXGUITAR_CACHE"))
    if os.environ.get("RESET_STUB"):
        stub_reset()
    cfg, env_cfg = load_config("sync_hold", hand="duet", num_envs=envs or None)
    if envs:
        cfg = dataclasses.replace(cfg, minibatch=min(cfg.minibatch, envs * cfg.horizon))
    pair = PO.load_pair("models/policies/left_general", "models/policies/right_mixed")
    out = {}
    with timed(out, "build_s"):
        trainer = SyncTrainer(cfg, [TL.from_song(load_song(song_file))], reference_frames(load_motion("left")),
                              *pair, env_cfg)
    with timed(out, "init_s"):
        state = jax.block_until_ready(trainer.init())
    chunk = trainer.make_train_chunk(cfg.iterations_per_call, Placement())
    with timed(out, "trace_s"):
        traced = chunk.trace(state, trainer.data)
    with timed(out, "lower_s"):
        lowered = traced.lower()
    with timed(out, "compile_or_load_s"):
        compiled = lowered.compile()
    speed = {}
    if runs:                       # the compiled chunk's speed: one warm-up call, then `runs` timed calls
        data = trainer.data
        state, _ = compiled(state, data)
        jax.block_until_ready(state)
        t = time.perf_counter()
        for _ in range(runs):
            state, _ = compiled(state, data)
        jax.block_until_ready(state)
        dt = (time.perf_counter() - t) / runs
        speed = {"chunk_s": round(dt, 3),
                 "samples_per_s": round(cfg.num_envs * cfg.horizon * cfg.iterations_per_call / dt)}
    return {"device": jax.devices()[0].device_kind, "envs": cfg.num_envs,
            "xla_flags": os.environ.get("XLA_FLAGS", ""),
            "reset": "stub" if os.environ.get("RESET_STUB") else "kinematics",
            **{k: round(v, 1) for k, v in out.items()}, **speed}


if __name__ == "__main__":          # planning spawns worker processes: they import this module
    print(json.dumps(main(sys.argv[1], *(int(v) for v in sys.argv[2:4]))))
