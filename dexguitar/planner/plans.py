"""Plans: the planners' motion of whole songs, as feedforwards that a residual policy corrects, cached on disk.

With `EnvConfig(feedforward=True)` the env adds the left planner's action of the current song frame to the left
hand's action, so a policy whose output starts at zero starts as the planner and PPO only learns the corrections
(residual RL); training windows start in the planned state of their first frame and end with their last note, so the
feedforward always belongs to the notes being played. `EnvConfig(right_feedforward=True)` does the same for the right
hand, whose plan, in the duet, waits note by note for the left hand's plan to hold the note (`left_plans`).

A `Plan` lives in `Timeline.plan` / `Timeline.plan_right` (song-frame indexed: frame 0 is the grace rest before the
first note, as in a sequential window), so it travels with the songs into every jitted program as an argument.
`envs.make` attaches the plans its config asks for (`prepare`). Planning takes seconds per song on one CPU core;
`attach` plans in parallel processes and keeps each plan in a disk cache keyed by the song's notes and timing and by
the planners' code and constants (`constants`), so that a plan made by other code is made again.
"""
from __future__ import annotations

import concurrent.futures as futures
import functools
import hashlib
import inspect
import multiprocessing
import os
import sys
import threading
import time
import warnings
from pathlib import Path

import jax
import mujoco
import numpy as np
from flax import struct

from dexguitar.music import timeline as TL
from dexguitar.planner import left as L
from dexguitar.planner.left import ScriptedLeft
from dexguitar.planner.right import ScriptedRight
from dexguitar.planner.tracking import Notes, Tracker
from dexguitar.world import hands as H
from dexguitar.world import scene

MIN_FRAMES = 1024                 # frame capacities are powers of two of at least this (few compiled shapes)


@struct.dataclass
class Plan:
    """Per song (leading axis in a batch): the left hand's planned env action and state at every song frame."""

    action: jax.Array      # float32 (F, 27) env action (a half-range units offset from the home pose)
    qpos: jax.Array        # float32 (F, 27) joint positions at the start of each frame
    qvel: jax.Array        # float32 (F, 27) joint velocities at the start of each frame
    frames: jax.Array      # int32 () planned frames (rows beyond repeat the last one)


def cache_dir() -> Path:
    return Path(os.environ.get("DEXGUITAR_PLANS", Path.home() / ".cache" / "dexguitar" / "plans"))


def _job_key(left, onset, hand: str = "left", pick=None, after: bool = False) -> str:
    """A plan's cache key: the left hand's plan depends on the left goals and onsets, the right hand's on the picked
    strings and onsets, and where it waits for the left hand's plan (`after`), on that plan too; each on its planner's
    constants (`constants`), so that a plan made with other constants is made again."""
    tag = "left" if hand == "left" else "right-after-left" if after else "right"
    h = hashlib.sha256(tag.encode())
    h.update(constants(hand).encode())
    if hand == "right" and after:
        h.update(constants("left").encode())
    if hand == "right":
        h.update(np.ascontiguousarray(pick, np.int32).tobytes())
    if hand == "left" or after:
        h.update(np.ascontiguousarray(left, np.int32).tobytes())
    h.update(np.ascontiguousarray(onset, np.int64).tobytes())
    return h.hexdigest()[:24]


def constants(hand: str) -> str:
    """What plans of `hand` ("left" or "right") are made with, as text: the source of the planner package and of the
    world it plans in, its planner's class constants, the left planner's module constants, the scene's control timing
    and the tracker's defaults, and the MuJoCo version. The plan cache's keys hash it (`_job_key`)."""
    cls = ScriptedLeft if hand == "left" else ScriptedRight
    own = {k: v for k, v in sorted(vars(cls).items()) if not k.startswith("_") and isinstance(v, (int, float))}
    tracker = {k: p.default for k, p in inspect.signature(Tracker.__init__).parameters.items()
               if p.default is not p.empty}
    common = {"control_hz": scene.CONTROL_HZ, "substeps": scene.SUBSTEPS, "home_position": L.HOME_POSITION,
              "posture": L.POSTURE.tolist(), "pair": L.PAIR, "barre": L.BARRE, "barre_positions": L.BARRE_POSITIONS}
    return repr((_source_digest(), mujoco.__version__, cls.__name__, own, tracker, common))


@functools.cache
def _source_digest() -> str:
    """sha256 of the planner package's sources and of the world modules it reads."""
    here = Path(__file__).parent
    world = ("scene", "hands", "guitar", "geometry", "kinematics", "detect", "scoring")
    files = sorted(here.glob("*.py")) + [here.parent / "world" / f"{m}.py" for m in world]
    return hashlib.sha256(b"".join(f.read_bytes() for f in files)).hexdigest()


_PLANNERS: dict = {}


def plan_notes(job) -> tuple[np.ndarray, np.ndarray]:
    """(action (T, 27), qpos (T + 1, 27)) of a hand's planner for one `Notes` (left, pick, onset[, hand: "left"
    (default) or "right"[, the tracked left plan's qpos that the right hand waits for]]), from the home pose. Runs
    in a worker process, which keeps its planner and IK caches between songs."""
    left, pick, onset, *rest = job
    role = rest[0] if rest else "left"
    after = rest[1] if len(rest) > 1 else None       # the right hand waits for this tracked left plan (qpos)
    hand, tracker = _planner(role)
    notes = Notes(left, pick, onset)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if role == "left":
            desired = hand.desired(notes)
        else:
            earliest = None if after is None else _planner("left")[0].timing(notes, after)
            desired = hand.desired(notes, earliest)
        ctrl, q = tracker.track(desired)
    return np.clip(tracker.to_action(ctrl), -1.0, 1.0).astype(np.float32), q.astype(np.float32)


def _planner(role: str):
    """(planner, tracker) of a hand, made once per process."""
    if role not in _PLANNERS:
        _PLANNERS[role] = (ScriptedLeft() if role == "left" else ScriptedRight(), Tracker(role))
    return _PLANNERS[role]


# Planning pools kept for the next call (`in_processes(keep=True)`), by worker count: spawning a worker and importing
# the package in it takes ~2.5 s on a CPU core, and its first plan ~3 s more to build the planner; a warm worker plans
# the next song in what that plan takes (ode_to_joy: 8 s in a fresh pool, 3 s more in a warm one). A pool idle for
# IDLE_S is shut down, so that a long training run does not hold idle workers (~320 MB each, one per core).
_KEPT: dict = {}
_KEPT_LOCK = threading.Lock()
IDLE_S = 120.0


def _blas_one_thread():
    """The environment a planning worker is spawned with: one BLAS thread, JAX on the CPU (see `in_processes`)."""
    saved = {k: os.environ.get(k) for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                                             "JAX_PLATFORMS")}
    os.environ.update({k: "1" for k in saved} | {"JAX_PLATFORMS": "cpu"})   # the planner's JAX bits: CPU, not the GPU
    return saved


def _restore(saved: dict) -> None:
    for k, v in saved.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


def _follow_parent(parent: int) -> None:
    """A worker leaves when the process that spawned it is gone: one that ends with `os._exit` (`cli`, Ctrl-C during
    a compile) or is killed does not shut its pools down, and their workers would wait on them for ever."""
    def watch():
        while os.getppid() == parent:
            time.sleep(1.0)
        os._exit(0)
    threading.Thread(target=watch, daemon=True).start()


def _new_pool(workers: int):
    return futures.ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"),  # never fork JAX
                                       initializer=_follow_parent, initargs=(os.getpid(),))


def _kept_pool(workers: int):
    """The kept pool of `workers` processes (made now if there is none), its idle timer stopped while it works."""
    with _KEPT_LOCK:
        pool, timer = _KEPT.pop(workers, (None, None))
        if timer is not None:
            timer.cancel()
    if pool is not None and getattr(pool, "_broken", False):    # a worker died while it waited (killed, out of memory)
        pool.shutdown(wait=False)
        pool = None
    return pool or _new_pool(workers)


def _keep(workers: int, pool) -> None:
    """Keep `pool` for the next call of its size, for IDLE_S (one pool a size: another call's, made meanwhile, ends)."""
    def idle():
        with _KEPT_LOCK:
            if _KEPT.get(workers, (None, None))[1] is timer:
                _KEPT.pop(workers)
                pool.shutdown(wait=False)
    timer = threading.Timer(IDLE_S, idle)
    timer.daemon = True
    with _KEPT_LOCK:
        if workers in _KEPT:
            pool.shutdown(wait=False)
            return
        _KEPT[workers] = pool, timer
    timer.start()


def in_processes(fn, jobs, workers: int = 0, keep: bool = False) -> tuple[list, int]:
    """([fn(job) for job in jobs], processes used): on `workers` processes (0: one per CPU) with one BLAS thread
    each, never in this process, even for one job: one process per core does the work, and 16 processes of 16 BLAS
    threads each ran at a load of 150 on a GPU host. `fn` must be a module-level function.
    keep: the processes stay for the next call with `keep` (`_KEPT`); only for work whose result does not depend on
    what a worker did before (a plan does not: `ScriptedLeft.position`)."""
    workers = max(1, min(workers or os.cpu_count() or 1, len(jobs)))
    saved = _blas_one_thread()           # workers are spawned as jobs arrive, so for the whole call
    try:
        pool = _kept_pool(workers) if keep else _new_pool(workers)
        try:
            out = list(pool.map(fn, jobs, chunksize=max(1, len(jobs) // (8 * workers))))
        except BaseException:
            pool.shutdown(wait=False, cancel_futures=True)
            raise
        if keep:
            _keep(workers, pool)
        else:
            pool.shutdown()
        return out, workers
    finally:
        _restore(saved)


def _progress(message: str) -> None:
    """Planning progress goes to stderr, so that `dexguitar eval --json` prints only JSON on stdout."""
    print(message, file=sys.stderr, flush=True)


def plan_all(jobs, workers: int = 0, log=None) -> list[tuple[np.ndarray, np.ndarray]]:
    """`plan_notes` of every job, in parallel processes."""
    log = log or _progress
    t0 = time.time()
    out, used = in_processes(plan_notes, jobs, workers, keep=True)
    hands = " and ".join(sorted({job[3] if len(job) > 3 else "left" for job in jobs}))
    songs = f"{len(jobs)} song{'s' * (len(jobs) != 1)}"
    log(f"planned the {hands} hand for {songs} ({sum(len(a) for a, _ in out):,} frames) in {time.time() - t0:.0f} s "
        f"on {used} process{'es' * (used != 1)}")
    return out


def song_notes(songs, i: int, rest_frames: int):
    """The planner's `Notes` of song i of a batch played whole: the grace rest, then every note at its written
    tempo (the rows and frames of a sequential window)."""
    n = int(songs.n_notes[i])
    onset = np.asarray(songs.onset[i][:n + 1], np.int64) + rest_frames
    left = np.concatenate([np.zeros((1, 6), np.int32), np.asarray(songs.left[i][:n], np.int32)])
    pick = np.concatenate([np.zeros((1, 6), bool), np.asarray(songs.pick[i][:n], bool)])
    return Notes(left, pick, np.concatenate([[0], onset]))


def plan_songs(songs, rest_frames: int = 5, workers: int = 0, log=None, hand: str = "left", after: list | None = None):
    """(keys, {key: (action, qpos)}): the plan of each song of a batch by `hand`'s planner (key None: an empty song),
    from the disk cache where it was made before, else made now (all in one pool) and cached.
    after: per song its tracked left plan's qpos: the right hand crosses each note's strings only once that left hand
    holds the note (`left_plans`)."""
    S = int(np.shape(songs.n_notes)[0])
    notes = [song_notes(songs, i, rest_frames) if int(songs.n_notes[i]) > 0 else None for i in range(S)]
    left_q = after if after is not None else [None] * S
    keys = [_job_key(n.left, n.onset, hand, n.pick, after is not None) if n is not None else None for n in notes]
    cache = cache_dir()
    found = {}
    for k in set(filter(None, keys)):
        f = cache / f"{k}.npz"
        if f.exists():
            with np.load(f) as z:
                found[k] = (z["action"], z["qpos"])
    todo = sorted({k for k in keys if k is not None and k not in found})
    if todo:
        jobs = {k: keys.index(k) for k in todo}
        made = plan_all([(notes[i].left, notes[i].pick, notes[i].onset, hand, left_q[i])
                         for i in jobs.values()], workers, log)
        cache.mkdir(parents=True, exist_ok=True)
        for k, (a, q) in zip(todo, made):
            found[k] = (a, q)
            tmp = cache / f"{k}.tmp.npz"
            np.savez(tmp, action=a, qpos=q)
            tmp.replace(cache / f"{k}.npz")
    return keys, found


def attach(songs, rest_frames: int = 5, mirror: bool = False, workers: int = 0, log=None, hand: str = "left",
           after: list | None = None):
    """The song batch (`timeline.batch`/`stack`) with a `Plan` per song by `hand`'s planner (`plan_songs`), as `plan`
    (left) or `plan_right`; empty songs get a plan of the home pose."""
    keys, found = plan_songs(songs, rest_frames, workers, log, hand, after)
    F = TL.capacity(max((len(found[k][0]) for k in found), default=1), MIN_FRAMES)
    flip = H.mirror_qpos(np.ones(H.N_DOF), hand) if mirror else np.ones(H.N_DOF, np.float32)
    act, qpos, qvel, frames = [], [], [], []
    for k in keys:
        if k is None:
            a, q = np.zeros((1, H.N_DOF), np.float32), _home_qpos(hand)[None]
            q = np.concatenate([q, q])
        else:
            a, q = found[k]
        v = np.diff(q, axis=0) * scene.CONTROL_HZ        # velocity over the frame before
        v = np.concatenate([np.zeros((1, H.N_DOF)), v[:-1]])
        q = q[:-1]
        T = len(a)
        frames.append(T)
        act.append(_extend(a, F) * flip)
        qpos.append(_extend(q, F) * flip)
        qvel.append(_extend(v, F) * flip)
    plan = Plan(action=jax.device_put(np.stack(act).astype(np.float32)),
                qpos=jax.device_put(np.stack(qpos).astype(np.float32)),
                qvel=jax.device_put(np.stack(qvel).astype(np.float32)),
                frames=jax.device_put(np.asarray(frames, np.int32)))
    return songs.replace(plan=plan) if hand == "left" else songs.replace(plan_right=plan)


def prepare(songs, config, hand: str):
    """Songs (a list of `Song`s or timelines, or a batch) as the `hand` env of `config` (an `EnvConfig` or None)
    reads them: stacked, with the plans attached where `config.feedforward` or `config.right_feedforward` asks for
    them, and the plan of a one-hand env's own hand where `config.teacher` labels it."""
    songs = TL.as_batch(songs)
    if config is None:
        return songs
    if (config.feedforward or (config.teacher and hand == "left")) and songs.plan is None:
        songs = attach(songs, config.rest_frames, config.mirror)
    if (config.right_feedforward or (config.teacher and hand == "right")) and songs.plan_right is None:
        songs = attach(songs, config.rest_frames, config.mirror, hand="right", after=left_plans(songs, config))
    return songs


def left_plans(songs, config) -> list | None:
    """Where both hands play on their planners (the duet): per song the tracked left plan's qpos, which the right
    hand's plan waits for, note by note, as the paper's strict gate asks (a string picked before the left hand holds
    the note is wrong); else None. The left plans come from the disk cache."""
    if not (config.feedforward and config.right_feedforward):
        return None
    keys, found = plan_songs(songs, config.rest_frames)
    return [found[k][1] if k is not None else None for k in keys]


def _extend(x: np.ndarray, frames: int) -> np.ndarray:
    """Rows to `frames`: cut, or padded with the last row (the hand holds its last pose after the song)."""
    x = np.asarray(x)[:frames]
    return np.concatenate([x, np.repeat(x[-1:], frames - len(x), 0)])


def _home_qpos(hand: str = "left") -> np.ndarray:
    return np.asarray(scene.home_qpos(hand), np.float32)
