"""How a played left hand moves, beside how the human guitarist moved: one line per performance.

    quality(qpos, human, fps=60)   {"jerk", "energy", "human_distance"} of a (T, 27) left-hand recording
    human_poses(sources)           (M, 21) finger joint angles of the capture: retargeted marker CSVs (cached) or
                                   left-hand motion files

F1 says whether the notes sounded, not whether the fingers moved like a hand: a policy can press every fret with
twitching fingers or in poses no guitarist takes. Three numbers, over the 21 finger joints only (qpos[6:27]: thumb,
then index..pinky; the 6 wrist DoF are left out, since the human's wrist sits where the player's guitar was):

- jerk: mean over frames and finger joints of |third finite difference| * fps^3, rad/s^3 (twitching);
- energy: mean over frames of the sum over finger joints of the squared joint velocity (first finite difference
  * fps), (rad/s)^2: a kinetic-energy-like effort with unit inertia per joint;
- human_distance: per played frame, the RMS over the 21 finger joints of the difference to the nearest human frame,
  then the median over played frames, rad (a pose no human frame comes near is far; the median is not swayed by a
  few odd frames).

The human's poses come from `motion.retarget` (marker IK onto our left-hand model), so both sides are joint
angles of the same model. Retargeting a whole capture clip takes tens of seconds on a CPU, so its result is kept in
`~/.cache/dexguitar/human` (`DEXGUITAR_HUMAN` moves it), keyed by the CSV's bytes and the IK settings: outside the
repository, since the capture is CC BY-NC-ND.
"""
from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numpy as np

from dexguitar.errors import UserError
from dexguitar.world import hands as H

FINGER_JOINTS = slice(H.WRIST_DOF, H.N_DOF)       # the 21 finger joints in qpos order (`hands.joints`)
N_FINGER = H.N_DOF - H.WRIST_DOF
CACHE_VERSION = "1"                             # bump when what the cache holds changes meaning
KEYS = ("jerk", "energy", "human_distance")


def finger_joints(qpos) -> np.ndarray:
    """(T, 21) finger joint angles of a (T, 27) left-hand qpos; a (T, 21) array is taken as it is."""
    q = np.asarray(qpos, np.float64)
    if q.ndim != 2 or q.shape[1] not in (H.N_DOF, N_FINGER):
        raise ValueError(f"expected (frames, {H.N_DOF}) or (frames, {N_FINGER}) joint values, got {q.shape}")
    return q[:, FINGER_JOINTS] if q.shape[1] == H.N_DOF else q


def jerk(fingers: np.ndarray, fps: float = 60.0) -> float:
    """Mean |third finite difference| * fps^3 over frames and joints, rad/s^3; NaN under 4 frames. Exact for a
    cubic in time (its third difference is the constant 6 a / fps^3)."""
    if len(fingers) < 4:
        return float("nan")
    return float(np.mean(np.abs(np.diff(fingers, n=3, axis=0))) * fps ** 3)


def energy(fingers: np.ndarray, fps: float = 60.0) -> float:
    """Mean over frames of the sum over joints of the squared velocity (forward difference * fps), (rad/s)^2; NaN
    under 2 frames."""
    if len(fingers) < 2:
        return float("nan")
    v = np.diff(fingers, axis=0) * fps
    return float(np.mean(np.sum(v ** 2, axis=1)))


def nearest(played: np.ndarray, human: np.ndarray, cells: int = 4_000_000) -> tuple[np.ndarray, np.ndarray]:
    """For each played frame (T, J): the index of the nearest human frame (M, J) and the RMS over the J joints of
    their difference, (T,) each. Chunks of played frames keep the (chunk, M) distance table under `cells` numbers
    (32 MB), so T and M of 10^4 and more fit; the distance is recomputed exactly for the chosen frame (the
    |p|^2 + |h|^2 - 2 p.h expansion only ranks)."""
    played, human = np.asarray(played, np.float64), np.asarray(human, np.float64)
    if not len(human):
        raise ValueError("no human frames to compare with")
    step = max(1, cells // len(human))
    hh = np.sum(human ** 2, axis=1)
    index = np.empty(len(played), np.int64)
    for a in range(0, len(played), step):
        p = played[a:a + step]
        d2 = hh[None, :] - 2.0 * p @ human.T            # + |p|^2, the same for every human frame
        index[a:a + step] = np.argmin(d2, axis=1)
    rms = np.sqrt(np.mean((played - human[index]) ** 2, axis=1))
    return index, rms


def quality(qpos, human, fps: float = 60.0) -> dict:
    """{"jerk" (rad/s^3), "energy" ((rad/s)^2), "human_distance" (rad)} of a played left hand's (T, 27) qpos at
    `fps` against the human's (M, 21) finger joint angles (or (M, 27) qpos); see the module docstring."""
    q, h = finger_joints(qpos), finger_joints(human)
    dist = float(np.median(nearest(q, h)[1])) if len(q) else float("nan")
    return {"jerk": jerk(q, fps), "energy": energy(q, fps), "human_distance": dist}


def mean_quality(lines) -> dict:
    """The plain mean over performances of each number (NaN where every one is NaN)."""
    lines = list(lines)
    out = {}
    for k in KEYS:
        v = np.array([x[k] for x in lines], np.float64)
        v = v[np.isfinite(v)]
        out[k] = float(v.mean()) if v.size else float("nan")
    return out


def add_to_results(results: dict, human: np.ndarray, fps: float = 60.0) -> dict:
    """Take each song's recorded "qpos" out of `evaluate(..., record=True)` results and put its line in the song's
    summary as "motion"; returns the mean line over the songs."""
    lines = []
    for res in results.values():
        res["summary"]["motion"] = quality(res.pop("qpos"), human, fps)
        lines.append(res["summary"]["motion"])
    return mean_quality(lines)


# ---------------------------------------------------------------------------------------------------- human side

def cache_dir() -> Path:
    return Path(os.environ.get("DEXGUITAR_HUMAN", Path.home() / ".cache" / "dexguitar" / "human"))


def retargeted_left(csv, cache: Path | None = None) -> np.ndarray:
    """(M, 27) left-hand qpos of a marker CSV at the capture rate, retargeted as `dexguitar motion retarget CSV
    --hand left` does (the whole clip, default settings), or read from the cache of an earlier run."""
    from dexguitar.motion import load, save
    from dexguitar.motion.retarget import IKConfig, Registration, read_markers, retarget, to_motion
    csv = Path(csv)
    try:
        raw = csv.read_bytes()
    except OSError as err:
        raise UserError(f"{csv}: cannot read the capture ({err.strerror or err})") from None
    digest = hashlib.sha256(raw + repr((CACHE_VERSION, IKConfig(), Registration())).encode()).hexdigest()[:16]
    cache = cache_dir() if cache is None else Path(cache)
    path = cache / f"{csv.stem}-{digest}-left.npz"
    if path.is_file():
        try:
            return np.asarray(load(path).qpos, np.float64)
        except Exception:               # a damaged cache file: retarget again
            pass
    markers = read_markers(csv)
    fit = retarget(markers, ("left",))["left"]
    motion = to_motion(fit, markers.fps, f"{csv.stem} (left hand, retargeted)")
    try:
        cache.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.stem + f".{os.getpid()}.tmp.npz")
        save(motion, tmp)
        os.replace(tmp, path)
    except OSError:                     # no cache is no error
        pass
    return np.asarray(motion.qpos, np.float64)


def human_poses(sources, cache: Path | None = None) -> np.ndarray:
    """(M, 21) finger joint angles of the human, all `sources` together: a marker CSV of the capture (its left hand
    retargeted, `retargeted_left`) or a left-hand motion file (`motion.load_motion`: .npz / .json)."""
    from dexguitar.motion import load_motion
    parts = []
    for s in [sources] if isinstance(sources, (str, Path)) else sources:
        if str(s).lower().endswith(".csv"):
            q = retargeted_left(s, cache)
        else:
            motion = load_motion(s)
            if motion.hand != "left":
                raise UserError(f"{s}: a {motion.hand}-hand motion; the motion line compares left (fretting) hands")
            q = motion.qpos
        parts.append(finger_joints(q))
    if not parts or not sum(len(p) for p in parts):
        raise UserError("no human frames: give a capture CSV or a left-hand motion file")
    return np.concatenate(parts)
