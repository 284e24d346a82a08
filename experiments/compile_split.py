"""Where a GSync run's compile seconds go (issue 10, "compile once"): building the trainer (planning included), its
first state, then the training chunk's trace, lowering and XLA compile (or load from the persistent cache), each
timed apart. Run it twice with the same DEXGUITAR_CACHE: the first process compiles, the second loads.

    DEXGUITAR_CACHE=/tmp/xla python experiments/compile_split.py SONG.json [ENVS]     # ENVS >= 512 (minibatch 4096)

Prints one JSON line (seconds). `device/compile_split.sh` ran it three times on an H100 (`results/general_left/
session24/compile_split/`).
"""
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


def main(song_file: str, envs: int = 0) -> dict:
    compilation_cache(os.environ.get("DEXGUITAR_CACHE"))
    cfg, env_cfg = load_config("experiments/sync_hold.py", hand="duet", num_envs=envs or None)
    if envs:
        cfg = dataclasses.replace(cfg, minibatch=min(cfg.minibatch, envs * cfg.horizon))
    pair = PO.load_pair("models/policies/left_general", "models/policies/right_mixed")
    out = {}
    t = time.perf_counter()
    trainer = SyncTrainer(cfg, [TL.from_song(load_song(song_file))], reference_frames(load_motion("left")), *pair,
                          env_cfg)
    out["build_s"] = time.perf_counter() - t
    t = time.perf_counter()
    state = jax.block_until_ready(trainer.init())
    out["init_s"] = time.perf_counter() - t
    chunk = trainer.make_train_chunk(cfg.iterations_per_call, Placement())
    t = time.perf_counter()
    traced = chunk.trace(state, trainer.data)
    out["trace_s"] = time.perf_counter() - t
    t = time.perf_counter()
    lowered = traced.lower()
    out["lower_s"] = time.perf_counter() - t
    t = time.perf_counter()
    lowered.compile()
    out["compile_or_load_s"] = time.perf_counter() - t
    return {"device": jax.devices()[0].device_kind, "envs": cfg.num_envs,
            **{k: round(v, 1) for k, v in out.items()}}


if __name__ == "__main__":          # planning spawns worker processes: they import this module
    print(json.dumps(main(sys.argv[1], *(int(v) for v in sys.argv[2:3]))))
