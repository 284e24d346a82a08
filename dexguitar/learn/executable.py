"""The training chunk's compiled programs, ready sooner.

- A first run compiles the chunk's programs (`learn.stages`) in threads, one each, while the main thread makes the
  first state. The chunk needs only the state's shapes (`jax.eval_shape`), and XLA compiles outside Python's lock, so
  the compiles overlap. On one H100, a GSync chunk as one program was compiled 66 s after the trainer was built
  instead of 92 s (docs/benchmarks.md, "Compilation").
- The compiled chunk is kept on disk beside JAX's persistent cache (`<cache>/chunks/`). A later run of the same code,
  package versions, devices, XLA flags, config and shapes loads it without tracing or lowering it: ready 10.1 s after
  the trainer was built instead of 24.3 s (docs/benchmarks.md, "Compilation"). A later run in the same process
  reuses it. Under Warp (`EnvConfig.physics`) the file also keeps the Warp calls the program names
  (`world.warp_calls`), described again before it loads (on an H200 a later run's chunk was ready in 4.5-7.0 s:
  docs/benchmarks.md, "A first and a later run under Warp"); where this process cannot serve them, the chunk is
  traced and JAX's persistent cache spares its compile.

The file's key hashes everything the program is made of except the values of its arguments (songs, reference
motion, frozen policies): the package's files, the versions, the devices, the trainer's config (but the seed and
the run's length, which the chunk does not read), its policy spec and those of the frozen policies it plays, and the
arguments' shapes. The chunk closes over nothing else (`trainer.Data`).
"""
from __future__ import annotations

import collections
import concurrent.futures
import dataclasses
import functools
import hashlib
import importlib.metadata
import json
import os
import pickle
import re
import sys
import threading
import time
from pathlib import Path

import jax
from jax.experimental import serialize_executable

from dexguitar.learn.policy import PolicySpec
from dexguitar.learn.stages import Chain
from dexguitar.learn.tracing import fresh_trace
from dexguitar.world import warp_calls

# TrainConfig fields that the chunk does not read: the first state's key, the run's length. A second seed or a longer
# run loads the chunk file of the first.
OUTSIDE_THE_CHUNK = ("seed", "iterations")
PACKAGES = ("jax", "jaxlib", "jax-cuda12-plugin", "jax-cuda13-plugin", "mujoco", "mujoco-mjx", "warp-lang", "flax",
            "optax", "numpy")
KEEP = 4            # chunk files kept in the cache directory, the newest first
NO_RESAVE = ("cpu",)    # backends whose executables loaded from JAX's persistent cache are not kept (`_HITS`)
LOAD_EVENT = "/dexguitar/chunk/load_duration"     # beside JAX's compile events, for those who count them
# The chunks this process compiled or loaded, by key: a second run of a key in one process (`dexguitar songs`, the
# next song of a capacity) takes its chunk from here.
_LIVE: dict = {}
# Persistent-cache hits per thread. An XLA:CPU executable that JAX loaded from its persistent cache serializes
# without its machine code (18.5 MB instead of 22.5 MB for the tiny CPU chunk), and what loads from that file fails
# at its first call ("Function iota_convert_fusion not found"): such a chunk is not kept.
_HITS: collections.Counter = collections.Counter()
jax.monitoring.register_event_listener(
    lambda name, **kw: _HITS.update([threading.get_ident()]) if name == "/jax/compilation_cache/cache_hits" else None)
# The chunks being compiled or loaded in a thread now (`in_flight`).
_PENDING: set = set()


def in_flight() -> bool:
    """Is a chunk still being compiled or loaded? Python waits for such a thread at exit (a minute for a first GPU
    compile) and a daemon thread inside XLA aborts the process at exit, so `cli.main` leaves at once with `os._exit`
    when a command fails or is interrupted meanwhile."""
    return any(not f.done() for f in list(_PENDING))     # a snapshot: the worker threads discard theirs


def _submit(pool, fn, *args):
    future = pool.submit(fn, *args)
    _PENDING.add(future)
    future.add_done_callback(_PENDING.discard)
    return future


@functools.cache
def source_digest() -> str:
    """A digest of every file of the installed `dexguitar` package (its code makes the program), read once per
    process: a chunk this process compiles comes from the code it imported."""
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for path in sorted(root.rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts:
            h.update(str(path.relative_to(root)).encode() + b"\0" + path.read_bytes())
    return h.hexdigest()


def _versions() -> dict:
    out = {}
    for name in PACKAGES:
        try:
            out[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            pass
    return out


def key(trainer, where, n: int, args) -> str:
    """The chunk file's name for `trainer.make_train_chunk(n, where)` lowered with `args` (state, data)."""
    leaves = [(tuple(x.shape), str(x.dtype), str(getattr(x, "sharding", None))) for x in jax.tree.leaves(args)]
    parts = {
        "source": source_digest(), "versions": _versions(), "python": sys.version.split()[0],
        "devices": [str(d.device_kind) for d in where.mesh.devices.flat], "backend": jax.default_backend(),
        "xla_flags": os.environ.get("XLA_FLAGS", ""), "x64": bool(jax.config.jax_enable_x64),
        "trainer": type(trainer).__qualname__,
        "train": {k: v for k, v in dataclasses.asdict(trainer.config).items() if k not in OUTSIDE_THE_CHUNK},
        "env": dataclasses.asdict(trainer.env.config), "spec": repr(trainer.spec), "iterations": n,
        "sources": {k: repr(PolicySpec.from_meta(meta)) for k, meta in getattr(trainer, "sources", {}).items()},
        "tree": re.sub(r" at 0x[0-9a-f]+", "", str(jax.tree.structure(args))),    # MJX's static arrays' wrappers
        "leaves": leaves,
    }
    return hashlib.sha256(json.dumps(parts, sort_keys=True, default=str).encode()).hexdigest()[:40]


def directory() -> Path | None:
    """Where chunk files live: `chunks/` in JAX's persistent cache directory (none without one)."""
    cache = jax.config.jax_compilation_cache_dir
    return Path(cache) / "chunks" if cache else None


class ChunkBuild:
    """The compiled chunk of a run (`stages.Chain`), started now and ready at `result()`: loaded from its file, or
    traced and lowered here (on the calling thread: tracing is Python) and its programs compiled in threads, then
    saved. Start it before `trainer.init()`, so that the first state's compile runs beside the chunk's.

    `state` may be abstract (`jax.ShapeDtypeStruct` with shardings); `data` is the placed `trainer.data`."""

    def __init__(self, trainer, where, n: int, state, data, log=lambda msg: None):
        self.start = time.perf_counter()
        self.log = log
        self._stages = lambda: trainer.make_train_chunk(n, where)
        self._args = (state, data)
        self._devices = list(where.mesh.devices.flat)
        self.key = key(trainer, where, n, (state, data))
        # a program that calls Warp is kept only where its Warp calls can be described again (`warp_calls`)
        keep = jax.process_count() == 1 and (trainer.env.physics != "warp" or warp_calls.AVAILABLE)
        folder = directory() if keep else None
        self.path = folder / f"chunk-{self.key}.exe" if folder else None
        self._pool = concurrent.futures.ThreadPoolExecutor(1)
        saved = self._read() if self.key not in _LIVE and self.path is not None and self.path.exists() else None
        if self.key in _LIVE:
            self.how = "reused"
            self._future = _submit(self._pool, _LIVE.get, self.key)
        elif saved is not None and warp_calls.restore(saved["warp"],
                                                      lambda: _env_step_shapes(trainer, where, state)):
            if saved["warp"]:
                # as the chunk's own trace started in the process that compiled it: the first state, traced next,
                # then lowers to the program that process compiled (its Warp call ids included), which JAX's
                # persistent cache holds
                fresh_trace()
            self.how = "loaded"
            self._future = _submit(self._pool, self._load, saved)
        else:
            if saved is not None:
                self.log(f"{self.path} calls Warp's targets otherwise than this process registered them; compiling "
                         "the chunk")
            self.how = "compiled"
            self._future = _submit(self._pool, self._compile, *self._trace())

    def _trace(self):
        """(the chunk's programs lowered here, how many times they run per call, the Warp calls their traces added:
        `warp_calls.taken`)."""
        before = warp_calls.counts()
        stages = self._stages()
        lowered = stages.lower(*self._args)
        return lowered, stages.repeat, warp_calls.taken(before)

    def _read(self) -> dict | None:
        try:
            with open(self.path, "rb") as f:
                saved = pickle.load(f)
            if not isinstance(saved, dict) or set(saved) != {"executables", "repeat", "warp"}:
                raise ValueError("not a chunk file")
            return saved
        except Exception as err:        # noqa: BLE001 - a stale or broken file: compile instead
            self.log(f"could not load {self.path} ({type(err).__name__}: {err}); compiling the chunk")
            return None

    def _load(self, saved):
        try:
            t = time.perf_counter()
            # onto the run's devices: by default JAX loads onto all of them, and XLA aborts the process where the
            # program was compiled for fewer (a 2-GPU run on a 4-GPU machine)
            programs = [serialize_executable.deserialize_and_load(*executable, execution_devices=self._devices)
                        for executable in saved["executables"]]
            os.utime(self.path)                     # recently used: kept by `_prune`
            jax.monitoring.record_event_duration_secs(LOAD_EVENT, time.perf_counter() - t)
            return Chain(programs, saved["repeat"])
        except Exception as err:        # noqa: BLE001 - a stale or broken file: compile instead (in `result`)
            self.log(f"could not load {self.path} ({type(err).__name__}: {err}); compiling the chunk")
            return None

    def _compile(self, lowered: list, repeat: int, warp: dict):
        with concurrent.futures.ThreadPoolExecutor(len(lowered)) as pool:
            compiled = list(pool.map(_compile_one, lowered))
        chain = Chain([c for c, _ in compiled], repeat)
        if any(hit for _, hit in compiled) and jax.default_backend() in NO_RESAVE:
            return chain
        if self.path is not None:
            try:
                self.path.parent.mkdir(parents=True, exist_ok=True)
                tmp = self.path.with_suffix(f".{os.getpid()}.tmp")
                with open(tmp, "wb") as f:
                    pickle.dump({"executables": [serialize_executable.serialize(c) for c, _ in compiled],
                                 "repeat": repeat, "warp": warp}, f)
                os.replace(tmp, self.path)
                _prune(self.path.parent)
            except Exception as err:    # noqa: BLE001 - a cache that cannot be written only costs the next run time
                self.log(f"could not keep the compiled chunk in {self.path.parent} ({type(err).__name__}: {err})")
        return chain

    def result(self):
        """(compiled chunk, seconds since the start, how: "compiled", "loaded" from its file, or "reused" from
        earlier in this process)."""
        compiled = self._future.result()
        self._pool.shutdown()
        if compiled is None:                        # the file did not load
            compiled, self.how = self._compile(*self._trace()), "compiled"
        _LIVE[self.key] = compiled
        return compiled, time.perf_counter() - self.start, self.how


def _compile_one(lowered):
    """(the program compiled in this thread, whether JAX took it from its persistent cache)."""
    hits = _HITS[threading.get_ident()]
    compiled = lowered.compile()
    return compiled, _HITS[threading.get_ident()] > hits


def _env_step_shapes(trainer, where, state):
    """One batched env step traced (shapes only), as the chunk's rollout makes it (each device its own envs): it
    registers the Warp targets the chunk calls, in the order the chunk's trace first meets them."""
    action = jax.ShapeDtypeStruct((state.env.obs.shape[0], trainer.env.action_size), "float32")
    return jax.eval_shape(where.each(jax.vmap(trainer.env.step)), state.env, action)


def _prune(folder: Path) -> None:
    files = sorted(folder.glob("chunk-*.exe"), key=lambda p: p.stat().st_mtime, reverse=True)
    for old in files[KEEP:]:
        old.unlink(missing_ok=True)
