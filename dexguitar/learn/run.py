"""The host side of training: a run directory, resume, chunks of iterations, progress, metrics and checkpoints. The host
only logs and saves; all learning happens inside the jitted chunk.

A run directory holds `config.json` (how the run was made: compared on --resume), `ckpt/` (the last few whole train
states), `resume/` (the last compact state: what a run cannot rebuild, to carry a long run from machine to machine),
`metrics.jsonl` (one row per host call: --resume drops the rows past the checkpoint it restores, all of them where
there is none) and `policy/` (the export, after every host call). The checkpoints are written at most every
`SAVE_EVERY_S` seconds and when the run stops, in the background while training goes on. A lock file keeps a
second process out of a directory in use. Non-finite parameters are never saved: the run rolls back to its last good
checkpoint with a new random key and stops after repeated failures. A full disk ends the run with one error naming
the run and its newest complete checkpoint, from which --resume continues.
"""
from __future__ import annotations

import contextlib
import dataclasses
import fcntl
import hashlib
import json
import os
import signal
import sys
import threading
import time
from pathlib import Path

import jax
import numpy as np
import optax

from dexguitar.errors import RunError, TrainingDiverged, UserError
from dexguitar.learn import checkpoint as C
from dexguitar.learn import policy as PO
from dexguitar.learn.devices import Placement
from dexguitar.learn.executable import ChunkBuild
from dexguitar.learn.trainer import Trainer, TrainConfig

SUMMED = ("episodes", "terminations")      # counts (and notes/*, nonfinite/*); f1/* are sums over notes
MAX_ROLLBACKS = 3                          # non-finite states in a row before giving up
CPU_ENVS = 512                             # envs from which `train` warns of XLA:CPU's LAPACK deadlock
SAVE_EVERY_S = 60.0                        # the whole and the compact state are saved at most this often, and at a stop
RESUME_FREE = ("iterations", "iterations_per_call")   # may change on --resume; nothing else may
TRAIN_DEFAULTS = {f.name: f.default for f in dataclasses.fields(TrainConfig)}
# EnvConfig fields newer than the runs that lack them, with the value those runs had (their envs ran MJX's JAX physics)
ENV_ADDED = {"physics": "auto", "warp_envs": 4096, "teacher": False, "teacher_gain": 1.0, "teacher_damping": 0.0,
             "teacher_finger_damping": 0.0, "plan_wrist_reward": 0.0}
KEPT = ("params", "obs_norm", "disc_norm", "popart", "key", "iteration")


def compact(path, leaf) -> bool:
    """What `resume/` keeps of a train state: the networks, normalizers, random key and iteration, and the
    optimizers' scalars (the adaptive actor rate, the warm-up schedule's count). The envs start afresh, the
    discriminators' replay buffers refill, and Adam restarts (`restart_adam`). The general left hand's state (4096
    envs) is 280 MiB; this part of it 20 MiB (19.5 MB on disk, 19.4 MB as a .tgz: docs/benchmarks.md, "Checkpoints")."""
    name = getattr(path[0], "name", None)
    return name in KEPT or (name == "opt" and np.size(leaf) == 1)


def restart_adam(opt, fresh):
    """`opt` with every Adam state taken from `fresh`: moments and step count together, since Adam's bias correction
    for a late count would read zero moments as a tiny second moment and take steps several times too long."""
    adam = lambda x: isinstance(x, optax.ScaleByAdamState)   # noqa: E731
    return jax.tree.map(lambda kept, new: new if adam(kept) else kept, opt, fresh, is_leaf=adam)


def compilation_cache(directory=None) -> Path:
    """Turn on JAX's persistent compilation cache (`$DEXGUITAR_CACHE`, default ~/.cache/dexguitar/xla), so a
    second process loads the programs the first one compiled."""
    directory = Path(directory or os.environ.get("DEXGUITAR_CACHE") or Path.home() / ".cache" / "dexguitar" / "xla")
    jax.config.update("jax_compilation_cache_dir", str(directory))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 1.0)
    return directory


# On an H100 the GSync training chunk compiled in 113 s with XLA's Triton GEMMs and in 63-73 s without them (their
# autotuning), running 3.5 % slower (docs/benchmarks.md, "Compilation").
FAST_COMPILE = "--xla_gpu_enable_triton_gemm=false"


def xla_flags(current: str, flags=(FAST_COMPILE,)) -> str:
    """`XLA_FLAGS` for the commands that compile: the user's own, plus each of `flags` whose name they did not set."""
    for flag in flags:
        if flag.split("=")[0] not in current:
            current = f"{current} {flag}".strip()
    return current


def chunk_summary(metrics: dict, n_iter: int) -> dict:
    m = {k: float(v) for k, v in metrics.items()}
    out = {k: m[k] for k in m if k in SUMMED or k.startswith(("notes/", "nonfinite/"))}
    for k, v in m.items():
        if k.startswith("f1/"):
            notes = m.get("notes/" + k[3:], 0.0)
            out[k] = v / notes if notes > 0 else float("nan")
        elif k not in out:
            out[k] = v / n_iter
    return out


def songs_digest(songs) -> str:
    """A fingerprint of the songs a run trains on (their padded arrays)."""
    h = hashlib.sha1()
    for leaf in jax.tree.leaves(songs):
        h.update(np.asarray(leaf).tobytes())
    return h.hexdigest()[:16]


def check_out(path, resume: bool) -> None:
    """The cheap checks of a run directory, before anything is built: --out names no file, --resume finds a run,
    and a new run does not write over an old one."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise RunError(f"--out {path}: a file, not a directory")
    if resume and not (path / "config.json").exists():
        raise RunError(f"{path}: no run to resume here (no config.json); leave out --resume to start one")
    if not resume and any(C.latest_step(path / d) is not None for d in ("ckpt", "resume")):
        raise RunError(f"{path} already holds a run: pass --resume to continue it, or choose another --out")


class RunDir:
    """A run directory held by this process (a lock file; released when the process ends, even by kill -9).
    Processes other than the first of a multi-host run only read it."""

    def __init__(self, path, main: bool = True):
        self.path = Path(path)
        self._lock = None
        if not main:
            return
        if self.path.exists() and not self.path.is_dir():
            raise RunError(f"--out {self.path}: a file, not a directory")
        try:
            self.path.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise RunError(f"--out {self.path}: cannot create it ({err.strerror})") from None
        self._lock = open(self.path / ".lock", "a+")
        try:
            fcntl.flock(self._lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            self._lock.seek(0)
            holder = self._lock.read().strip() or "another process"
            self._lock.close()
            raise RunError(f"{self.path} is in use by {holder}: wait for it, or choose another --out") from None
        self._lock.seek(0)
        self._lock.truncate()
        self._lock.write(f"process {os.getpid()}")
        self._lock.flush()

    ckpt = property(lambda self: self.path / "ckpt")
    compact = property(lambda self: self.path / "resume")
    metrics = property(lambda self: self.path / "metrics.jsonl")
    config = property(lambda self: self.path / "config.json")

    def check_resume(self, record: dict) -> None:
        """Refuse to resume a run made with another config, hand, songs or policies, naming what differs."""
        if not self.config.exists():
            raise RunError(f"{self.path}: no run to resume here (no config.json); leave out --resume to start one")
        old = json.loads(self.config.read_text())
        if old.get("env"):
            old["env"] = planner_flags(old["env"], self.config)
        diffs = []
        for key in sorted(set(old) | set(record)):
            a, b = old.get(key), record.get(key)
            if key == "train":   # a field newer than the run counts as its default
                a, b = ({k: v for k, v in {**TRAIN_DEFAULTS, **(x or {})}.items() if k not in RESUME_FREE}
                        for x in (a, b))
                diffs += [f"train.{k}: {a.get(k)!r} -> {b.get(k)!r}" for k in sorted(set(a) | set(b))
                          if a.get(k) != b.get(k)]
            elif key == "env" and a != b:
                a, b = ({**ENV_ADDED, **x} if x is not None else None for x in (a, b))
                diffs += [f"env.{k}: {a.get(k)!r} -> {b.get(k)!r}" for k in sorted(set(a or {}) | set(b or {}))
                          if (a or {}).get(k) != (b or {}).get(k)]
            elif key not in ("env", "train") and a != b and key in old:   # a key newer than the run: not compared
                diffs.append(f"{key}: {json.dumps(a)[:80]} -> {json.dumps(b)[:80]}")
        if diffs:
            raise RunError(f"{self.path} was made with another setup; --resume continues a run as it was made. "
                           f"Differences: " + "; ".join(diffs))

    def truncate_metrics(self, iteration: int) -> None:
        """Drop metric rows past `iteration` (written by a process killed before its next checkpoint)."""
        if not self.metrics.exists():
            return
        rows = [r for r in self.metrics.read_text().splitlines() if r.strip()]
        keep = []
        for r in rows:
            try:
                if json.loads(r).get("iteration", 0) <= iteration:
                    keep.append(r)
            except json.JSONDecodeError:        # a row cut by a kill
                pass
        if len(keep) != len(rows):
            self.metrics.write_text("".join(k + "\n" for k in keep))

    def close(self):
        if self._lock is not None:
            self._lock.close()


def export(trainer: Trainer, state, directory, saver: C.Saver | None = None) -> None:
    """What eval and play need: the policy (or the synchronizer, naming its two frozen policies), its observation
    normalizer and its spec (the weights through `saver`, in the background, where given)."""
    meta = {**trainer.spec.to_meta(), "iteration": int(state.iteration),
            "samples": int(state.iteration) * trainer.config.batch, "columns": list(trainer.columns)}
    if trainer.spec.kind == "synchronizer":
        meta["sources"] = {side: {"path": PO.source_path(directory, m["path"]),
                                  **{k: m.get(k) for k in ("samples", "iteration")}}
                           for side, m in trainer.sources.items()}
    PO.export(directory, trainer.actor_params(state.params, state.obs_norm), meta, saver)


def check_init(init_from, hand: str, feedforward: bool, scale: float = 1.0) -> dict:
    """The meta of the exported policy that a run of `hand` starts from, if it can: a policy of that hand, a
    residual on the planner exactly when the run trains one (`EnvConfig.feedforward`), and of the run's action scale
    (`TrainConfig.action_scale`). Reads no weights."""
    meta = PO.read_meta(init_from)
    if meta.get("hand") != hand or meta.get("kind", "policy") != "policy":
        raise UserError(f"--init-from {init_from}: a {meta.get('hand')} hand {meta.get('kind', 'policy')}, not a "
                        f"{hand} hand policy")
    spec = PO.PolicySpec.from_meta(meta)
    residual, feedforward = bool(spec.feedforward or spec.right_feedforward), bool(feedforward)
    if residual != feedforward:
        what = {True: "a residual on the IK planner", False: "a plain policy"}
        raise UserError(f"--init-from {init_from}: {what[residual]}, but this run's ENV trains {what[feedforward]} "
                        "(EnvConfig.feedforward)")
    theirs = spec.scale
    if theirs != scale:
        raise UserError(f"--init-from {init_from}: its actions are scaled by {theirs}, but this run's "
                        f"TrainConfig.action_scale is {scale}")
    return meta


def train(trainer: Trainer, out_dir, *, iterations: int, resume: bool = False, progress: bool = True,
          meta: dict | None = None, stop_after_calls: int | None = None, max_minutes: float | None = None,
          init_from=None, on_call=None, devices: int | None = None, log=None, save_every: float = SAVE_EVERY_S) -> dict:
    """Run until `iterations` iterations are done (counting those of a resumed run), `max_minutes` have passed,
    `on_call(iteration)`, called after each host call's export, returns True (the pipeline judges the export there), or
    a SIGINT or SIGTERM asks it to stop (`stop_requests`; then KeyboardInterrupt, once saved). Returns the last
    summary, with `compile_s` (the first call's compilation) and `calls`. `devices`: how many devices share the envs
    (default: the trainer's). The metrics and the policy export are written after every host call, the checkpoints
    when `save_every` seconds have passed since the last (0: after every call; a run of several processes saves after
    every call) and when the run stops."""
    cfg = trainer.config
    where = Placement(devices or trainer.devices)
    if where.n != trainer.devices:     # its envs are reset in groups, one per device, with Warp's buffers sized so
        raise ValueError(f"a trainer made for {trainer.devices} devices cannot run on {where.n}: give both the "
                         "same devices")
    log = (log or (lambda msg: print(msg, file=sys.stderr))) if where.main else (lambda msg: None)
    if jax.default_backend() == "cpu" and cfg.num_envs >= CPU_ENVS:
        log(f"warning: {cfg.num_envs} envs on a CPU: XLA:CPU's batched Cholesky factorizations (MJX) can wait on "
            "each other forever at this size (seen with 512 envs on 2 cores; docs/training.md); the "
            "CPU config uses 4 (--config cpu_smoke)")
    run = RunDir(out_dir, where.main)
    try:
        record = json.loads(json.dumps({  # as config.json holds it (tuples become lists)
            "train": dataclasses.asdict(cfg), "env": dataclasses.asdict(trainer.env.config),
            "columns": list(trainer.columns), "songs_digest": songs_digest(trainer.data.songs), **(meta or {})}))
        ckpt_step, compact_step = C.latest_step(run.ckpt), C.latest_step(run.compact)
        has_ckpt, has_compact = ckpt_step is not None, compact_step is not None
        if resume:
            run.check_resume(record)
        else:
            check_out(run.path, resume=False)         # for callers that did not check (the pipeline, tests)
        if init_from and not (resume and (has_ckpt or has_compact)):     # checked before anything compiles
            meta_init = check_init(init_from, cfg.hand, trainer.env.config.feedforward
                                   or trainer.env.config.right_feedforward, cfg.action_scale)
        done = resume and (ckpt_step if has_ckpt else compact_step or 0) >= iterations     # as restored below
        data = where.put(trainer.data, where.replicated(trainer.data))
        build = None if done else chunk_build(trainer, where, data, log)    # compiles beside `init` below
        state = trainer.init()
        shardings = where.shardings(state)
        if resume and has_ckpt:            # restored straight into this run's placement, whatever the saved one
            state, step = C.restore(run.ckpt, where.put(state, shardings), set_damaged_aside=where.main)
            run.truncate_metrics(step)
            log(f"resumed {run.path} at iteration {int(state.iteration)}")
        elif resume and has_compact:       # carried from another machine: the whole state stayed there
            fresh = where.put(state, shardings)
            state, step = C.restore(run.compact, fresh, only=compact)
            state = state.replace(opt=restart_adam(state.opt, fresh.opt))
            run.truncate_metrics(step)
            log(f"resumed {run.path} at iteration {step} from its compact state (envs, replay buffers and Adam "
                "start afresh)")
        elif resume:                       # killed before its first checkpoint was complete
            run.truncate_metrics(0)
            log(f"{run.path} holds no checkpoint yet: the run starts again from iteration 0")
        if init_from and not (resume and (has_ckpt or has_compact)):
            params = PO.load(init_from)[0]
            state = state.replace(params=dict(state.params, policy=params["policy"]), obs_norm=params["obs_norm"])
            log(f"policy initialized from {init_from} ({meta_init.get('samples', 0):,} samples)")
        if build is None and int(state.iteration) < iterations:    # the newest step was damaged: an older one came
            build = chunk_build(trainer, where, data, log)
        if where.main and (not resume or not run.config.exists()):
            tmp = run.config.with_suffix(".tmp")
            tmp.write_text(json.dumps(record, indent=2))
            os.replace(tmp, run.config)
        if where.n > 1:
            log(f"{where.n} devices: {cfg.num_envs // where.n} envs and minibatches of {cfg.minibatch // where.n} "
                f"samples each")
        return _loop(trainer, run, where, where.put(state, shardings), data, build, iterations,
                     progress and where.main, stop_after_calls, max_minutes, on_call, log,
                     save_every if jax.process_count() == 1 else 0.0)
    except (OSError, C.DiskFull) as err:     # the saves are complete or abandoned by now: say which step is kept
        if isinstance(err, OSError) and not C.disk_full(err):
            raise
        raise RunError(C.full_message(run.path, C.latest_step(run.ckpt))) from None
    finally:
        run.close()


def chunk_build(trainer, where, data, log) -> ChunkBuild:
    """Start getting the compiled training chunk for the state `trainer.init()` will make, placed by `where`."""
    return ChunkBuild(trainer, where, trainer.config.iterations_per_call, where.placed_shapes(trainer.state_shapes),
                      data, log)


def _loop(trainer, run, where, state, data, build, iterations, progress, stop_after_calls, max_minutes, on_call,
          log, save_every) -> dict:
    cfg = trainer.config
    n = cfg.iterations_per_call
    if int(state.iteration) >= iterations:
        log(f"{run.path}: all {iterations} iterations are done")
        return {"iteration": int(state.iteration), "calls": 0, "compile_s": 0.0}
    t_start = build.start                         # `max_minutes` counts the compilation too
    chunk, compile_s, how = build.result()
    log(f"{how} the training chunk in {compile_s:.1f} s" + (f" from {build.path}" if how == "loaded" else ""))
    bar = None
    if progress:
        from tqdm import tqdm          # noqa: PLC0415 - only for a progress display
        bar = tqdm(total=iterations, initial=int(state.iteration), unit="it", dynamic_ncols=True, file=sys.stderr,
                   mininterval=0.1 if sys.stderr.isatty() else 30.0)     # a log file gets a line every 30 s
        say = log
        log = lambda msg: (bar.clear(), say(msg), bar.refresh())  # noqa: E731 - a line of its own, not the bar's
    summary, calls, rollbacks, saved_at, asked = {}, 0, 0, time.perf_counter(), None
    # the saves and the export of one chunk are written while the next one runs; leaving the block (the end, an
    # error, Ctrl-C) waits until they are complete on disk
    with C.Saver(run.ckpt) as ckpt, C.Saver(run.compact, keep=1, only=compact) as resume_state, \
            (C.Saver(run.path / "policy" / "params", keep=1) if where.main else contextlib.nullcontext()) as policy, \
            (bar if bar is not None else contextlib.nullcontext()), stop_requests(log) as requested:
        def save(it, state) -> dict:
            """The saves' blocking seconds (copying to the host, waiting for the writes before): saved after every
            chunk, they took about 0.7 s of each 3.6 s under Warp on one H200 (docs/benchmarks.md, "Several GPUs")."""
            t = time.perf_counter()
            ckpt.save(it, state)
            t2 = time.perf_counter()
            resume_state.save(it, state)
            return {"ckpt_s": t2 - t, "compact_s": time.perf_counter() - t2}

        while int(state.iteration) < iterations:
            t0 = time.perf_counter()
            new, metrics = chunk(state, data)
            metrics = jax.device_get(metrics)
            dt = time.perf_counter() - t0
            summary = chunk_summary(metrics, n)
            if summary.get("nonfinite/state", 0.0) > 0:
                rollbacks += 1
                if rollbacks > MAX_ROLLBACKS:
                    raise TrainingDiverged(f"{run.path}: the parameters became non-finite {rollbacks} times in a row, "
                                           "even after rolling back; lower the learning rates or check the songs")
                ckpt.wait()
                state = _rollback(trainer, run, where, rollbacks)
                log(f"warning: non-finite parameters after iteration {int(new.iteration)} "
                    f"({summary.get('nonfinite/env_steps', 0):.0f} env steps and "
                    f"{summary.get('nonfinite/ppo_updates', 0):.0f} PPO updates were non-finite); rolled back to "
                    f"iteration {int(state.iteration)} with a new random key")
                continue
            rollbacks = 0
            state = new
            if summary.get("nonfinite/env_steps", 0) > 0:
                log(f"warning: {summary['nonfinite/env_steps']:.0f} env steps went non-finite and were reset")
            it = int(state.iteration)
            t1 = time.perf_counter()
            summary.update(iteration=it, samples=it * cfg.batch, seconds=dt, samples_per_s=n * cfg.batch / dt,
                           wall=t1 - t_start, compile_s=compile_s)
            calls += 1
            asked = requested()
            quota = stop_after_calls is not None and calls >= stop_after_calls
            late = max_minutes is not None and t1 - t_start > 60 * max_minutes
            stop = it >= iterations or asked or quota or late
            saved = stop or t1 - saved_at >= save_every
            if saved:
                summary.update(save(it, state))
                saved_at = time.perf_counter()
            if where.main:
                with open(run.metrics, "a") as f:
                    f.write(json.dumps(summary) + "\n")
                export(trainer, state, run.path / "policy", policy)
            if bar is not None:
                hands = trainer.env.roles + (("both",) if len(trainer.env.roles) == 2 else ())
                reward = np.mean([v for k, v in summary.items() if k.startswith("reward/")])
                bar.set_postfix({"samples/s": f"{summary['samples_per_s']:,.0f}",
                                 **{f"F1 {h}": f"{summary.get('f1/' + h, float('nan')):.3f}" for h in hands},
                                 "reward": f"{reward:.3f}"})
                bar.update(n)
            if not (quota or asked) and on_call is not None and where.main:
                policy.wait()                                   # on_call judges the export: complete on disk
                if on_call(it):
                    if not saved:
                        save(it, state)
                    break
            if asked:
                log(f"{asked}: stopped at iteration {it}, saved (continue with --resume)")
            elif late:
                log(f"stopping after {max_minutes} minutes at iteration {it} (resume with --resume)")
            if stop:
                break
    if asked:
        raise KeyboardInterrupt
    return dict(summary, compile_s=compile_s, calls=calls)


@contextlib.contextmanager
def stop_requests(log):
    """Within the block, a first SIGINT (Ctrl-C) or SIGTERM asks the training loop to stop after the chunk that runs,
    with its checkpoints; a second SIGINT stops at once (KeyboardInterrupt), as without the block. Yields a function:
    the name of the first signal received, or None. Where Python takes no signals (a thread other than the main one)
    or the run has several processes (which would stop at different chunks), the signals stay as they were."""
    asked = []
    if threading.current_thread() is not threading.main_thread() or jax.process_count() > 1:
        yield lambda: None
        return

    def handler(signum, frame):
        if asked and signum == signal.SIGINT:
            raise KeyboardInterrupt
        if not asked:
            log(f"{signal.Signals(signum).name}: stopping after this chunk with a checkpoint (Ctrl-C again stops at "
                "once)")
        asked.append(signal.Signals(signum).name)
    before = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield lambda: asked[0] if asked else None
    finally:
        for s, h in before.items():
            signal.signal(s, h)


def _rollback(trainer, run, where, attempt: int):
    """The last good state (or a fresh one) with a new random key."""
    state = trainer.init()
    shardings = where.shardings(state)
    state = where.put(state, shardings)
    if C.latest_step(run.ckpt) is not None:
        state, _ = C.restore(run.ckpt, state)
    state = state.replace(key=jax.random.fold_in(state.key, 7919 * attempt))
    return where.put(state, shardings)


def planner_flags(env: dict, where="the run's config.json") -> dict:
    """A run's recorded EnvConfig fields (config.json's "env") with "feedforward" and "right_feedforward" as
    booleans: a run may have recorded the planner's version number there (`policy.PLANNER_KEYS`). A run on a planner
    version this release no longer has cannot go on (RunError)."""
    out = dict(env)
    for key, version in PO.PLANNER_KEYS.items():
        value = out.get(key)
        if type(value) is int and value not in (0, version):
            raise RunError(f"{where}: made on a planner version this release no longer has (env.{key}: {value}); "
                           f"only the left planner of version {PO.PLANNER_VERSION} and the right planner of version "
                           f"{PO.RIGHT_PLANNER_VERSION} are kept, so start a new run")
        if type(value) is int:
            out[key] = bool(value)
    return out


