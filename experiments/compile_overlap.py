"""Issue 10, "compile once": can a first run's start shrink by compiling the training chunk while the first state
compiles? The chunk needs only the state's shapes, so it can be traced and lowered from `jax.eval_shape`, and XLA
can compile it in a thread while the main thread compiles and runs `trainer.init()`.

    DEXGUITAR_CACHE=/tmp/xla python experiments/compile_overlap.py SONG.json MODE [ENVS]

MODE: `seq` (first state, then the chunk: what `train` does now), `overlap` (the chunk compiled in a thread beside the
first state), `save` (overlap, then the compiled chunk serialized to $EXE, default /tmp/chunk.exe), `load` (the first
state, and the chunk deserialized from $EXE: no trace, lower or compile). Prints one JSON line of seconds since the
start; each mode also runs the chunk once on the first state, to show that what it got plays. Measured on one H100
(`device/compile_overlap.sh`, `results/general_left/session26/compile_overlap/`): what `dexguitar/learn/executable.py`
does now. On a 2-core CPU the chunk's first call at 512 envs never returns (`cpu_lapack_hang.py`).
"""
import concurrent.futures
import dataclasses
import json
import os
import pickle
import sys
import time

import jax

from dexguitar.cli import load_config, load_motion, load_song, reference_frames
from dexguitar.learn import policy as PO
from dexguitar.learn.devices import Placement
from dexguitar.learn.run import compilation_cache
from dexguitar.learn.sync import SyncTrainer
from dexguitar.music import timeline as TL


def main(song_file: str, mode: str, envs: int = 0) -> dict:
    compilation_cache(os.environ.get("DEXGUITAR_CACHE"))
    exe = os.environ.get("EXE", "/tmp/chunk.exe")
    t0 = time.perf_counter()
    out = {}

    def mark(stage):
        out[stage] = round(time.perf_counter() - t0, 1)
        print(json.dumps(out), file=sys.stderr, flush=True)

    cfg, env_cfg = load_config("sync_hold", hand="duet", num_envs=envs or None)
    if envs:
        cfg = dataclasses.replace(cfg, minibatch=min(cfg.minibatch, envs * cfg.horizon))
    pair = PO.load_pair("models/policies/left_general", "models/policies/right_mixed")
    trainer = SyncTrainer(cfg, [TL.from_song(load_song(song_file))], reference_frames(load_motion("left")),
                          *pair, env_cfg)
    where = Placement()
    data = where.put(trainer.data, where.replicated(trainer.data))
    mark("built")
    chunk = trainer.make_train_chunk(cfg.iterations_per_call, where)
    abstract = where.placed_shapes(trainer.state_shapes)
    shardings = where.shardings(abstract)
    if mode == "load":
        from jax.experimental import serialize_executable as SE
        with open(exe, "rb") as f:
            payload, in_tree, out_tree = pickle.load(f)
        compiled = SE.deserialize_and_load(payload, in_tree, out_tree)
        mark("chunk_loaded")
        state = jax.block_until_ready(trainer.init())
        mark("first_state")
    elif mode == "seq":
        state = jax.block_until_ready(trainer.init())
        mark("first_state")
        compiled = chunk.lower(abstract, data).compile()
        mark("chunk_compiled")
    else:
        lowered = chunk.lower(abstract, data)
        mark("chunk_lowered")
        pool = concurrent.futures.ThreadPoolExecutor(1)
        future = pool.submit(lowered.compile)
        state = jax.block_until_ready(trainer.init())
        mark("first_state")
        compiled = future.result()
        mark("chunk_compiled")
        if mode == "save":
            from jax.experimental import serialize_executable as SE
            with open(exe, "wb") as f:
                pickle.dump(SE.serialize(compiled), f)
            mark("saved")
    state, _ = compiled(where.put(state, shardings), data)
    jax.block_until_ready(state)
    mark("first_call")
    return {"mode": mode, "device": jax.devices()[0].device_kind, "envs": cfg.num_envs,
            "xla_flags": os.environ.get("XLA_FLAGS", ""), **out}


if __name__ == "__main__":          # planning spawns worker processes: they import this module
    print(json.dumps(main(sys.argv[1], sys.argv[2], *(int(v) for v in sys.argv[3:4]))))
