"""The reference-motion format: one hand's 27 joint values per frame, at a given frame rate.

Why joint values (and not link states): they are what our own tools produce and what the MuJoCo model consumes, they
are small, and every other representation (link states for the discriminator, renders) follows from them by forward
kinematics (`dexguitar.motion.kinematics`). A `Motion` is

    hand   "left" or "right": the hand *model* whose joints `qpos` holds ("left" frets for a right-handed player)
    fps    frames per second (float)
    qpos   (T, 27) float array in `hands.joints(hand)` order: wrist slides x/y/z in the guitar frame (m), wrist hinges
           x/y/z, thumb1 x/y/z, thumb2, thumb3, then index/middle/ring/pinky 1_x, 1_z, 2, 3 (rad)
    name   a label

On disk (`save` / `load`):

* `.npz` (the normal form): arrays `qpos` (float32 unless saved otherwise) and `joints` (the 27 names, checked on
  load), scalars `hand`, `fps`, `name`, `format` (= FORMAT_VERSION).
* `.json` for humans: `{"hand": "left", "fps": 60, "joints": [27 names], "qpos": [[27 numbers], ...], "name": ""}`;
  `joints` is optional, and when given it must match our order.

Loading validates: 27 joints, finite values, every joint inside its range up to `RANGE_TOL`. Errors are
`MotionError`s whose message names the file (and the frame / joint where it applies).
"""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np

from dexguitar.world import hands as H

FORMAT_VERSION = 1
HANDS = ("left", "right")
# Joint values may leave their range by this much (m for slides, rad for hinges): the PD-driven simulation overshoots
# limits slightly, and recorded motions keep that.
RANGE_TOL = 0.02


class MotionError(ValueError):
    """A motion file or array that does not fit the format; the message names the source."""


@dataclasses.dataclass(frozen=True, eq=False)
class Motion:
    hand: str
    fps: float
    qpos: np.ndarray
    name: str = ""

    def __post_init__(self):
        object.__setattr__(self, "qpos", np.asarray(self.qpos))
        object.__setattr__(self, "fps", float(self.fps))

    @property
    def n_frames(self) -> int:
        return int(self.qpos.shape[0])

    @property
    def seconds(self) -> float:
        """Duration from the first to the last frame."""
        return max(self.n_frames - 1, 0) / self.fps

    @property
    def times(self) -> np.ndarray:
        return np.arange(self.n_frames) / self.fps

    def replace(self, **changes) -> "Motion":
        return dataclasses.replace(self, **changes)


def joint_names(hand: str) -> tuple[str, ...]:
    return tuple(j.name for j in H.joints(hand))


def joint_ranges(hand: str) -> np.ndarray:
    """(27, 2) lower / upper limit of every joint of that hand model."""
    return np.array([j.range for j in H.joints(hand)], dtype=np.float64)


def validate(motion: Motion, source: str | Path | None = None, tol: float = RANGE_TOL) -> Motion:
    """Raise `MotionError` (naming `source`) unless the motion fits the format; returns it unchanged."""
    where = f"{source}: " if source is not None else ""
    if motion.hand not in HANDS:
        raise MotionError(f"{where}hand must be 'left' or 'right', got {motion.hand!r}")
    if not (np.isfinite(motion.fps) and motion.fps > 0):
        raise MotionError(f"{where}fps must be a positive number, got {motion.fps}")
    q = motion.qpos
    if q.ndim != 2 or q.shape[1] != H.N_DOF:
        raise MotionError(f"{where}qpos must have shape (frames, {H.N_DOF}), got {q.shape}")
    if q.shape[0] < 1:
        raise MotionError(f"{where}the motion has no frames")
    if not np.issubdtype(q.dtype, np.floating):
        raise MotionError(f"{where}qpos must be floating point, got {q.dtype}")
    bad = ~np.isfinite(q)
    if bad.any():
        t, j = np.argwhere(bad)[0]
        raise MotionError(f"{where}non-finite value at frame {t}, joint {joint_names(motion.hand)[j]} "
                          f"({int(bad.sum())} in all)")
    rng = joint_ranges(motion.hand)
    excess = np.maximum(rng[:, 0] - tol - q, q - rng[:, 1] - tol)
    if (excess > 0).any():
        t, j = np.unravel_index(np.argmax(excess), excess.shape)
        name = joint_names(motion.hand)[j]
        raise MotionError(f"{where}joint {name} = {q[t, j]:.4f} at frame {t} is outside its range "
                          f"[{rng[j, 0]:.4f}, {rng[j, 1]:.4f}] (tolerance {tol}; {int((excess > 0).sum())} values out "
                          f"of range). Is this a {motion.hand}-hand motion?")
    return motion


def clip_to_ranges(qpos: np.ndarray, hand: str) -> tuple[np.ndarray, int]:
    """Joint values clipped into their ranges, and how many values moved."""
    rng = joint_ranges(hand)
    out = np.clip(qpos, rng[:, 0], rng[:, 1])
    return out, int(np.sum(out != qpos))


# ----------------------------------------------------------------------------------------------------- files

def save(motion: Motion, path: str | Path, dtype=np.float32) -> Path:
    """Write `.npz` (compressed, qpos as `dtype`) or `.json` by the suffix of `path`."""
    path = Path(path)
    validate(motion, path)
    if path.suffix == ".json":
        doc = {"hand": motion.hand, "fps": motion.fps, "name": motion.name, "format": FORMAT_VERSION,
               "joints": list(joint_names(motion.hand)),
               "qpos": [[round(float(x), 6) for x in row] for row in motion.qpos]}
        path.write_text(json.dumps(doc, separators=(",", ":")))
    elif path.suffix == ".npz":
        with open(path, "wb") as f:      # a file object: numpy would otherwise append ".npz" to odd names
            np.savez_compressed(f, qpos=motion.qpos.astype(dtype), joints=np.array(joint_names(motion.hand)),
                                hand=np.array(motion.hand), fps=np.array(motion.fps), name=np.array(motion.name),
                                format=np.array(FORMAT_VERSION))
    else:
        raise MotionError(f"{path}: unknown motion file type {path.suffix!r} (expected .npz or .json)")
    return path


def load(path: str | Path) -> Motion:
    """Read a `.npz` or `.json` motion written by `save` (or by hand) and validate it."""
    path = Path(path)
    if not path.exists():
        raise MotionError(f"{path}: no such file")
    if path.suffix == ".json":
        try:
            doc = json.loads(path.read_text())
        except json.JSONDecodeError as e:
            raise MotionError(f"{path}: not valid JSON ({e})") from None
        if not isinstance(doc, dict) or "qpos" not in doc:
            hint = (" (this looks like the authors' format: use dexguitar.motion.official.read_official_json)"
                    if isinstance(doc, dict) and "frames" in doc else "")
            raise MotionError(f"{path}: expected an object with 'hand', 'fps' and 'qpos'{hint}")
        fields = {"hand": doc.get("hand"), "fps": doc.get("fps"), "joints": doc.get("joints"),
                  "name": doc.get("name", path.stem)}
        try:
            qpos = np.asarray(doc["qpos"], dtype=np.float64)
        except (TypeError, ValueError):
            raise MotionError(f"{path}: 'qpos' must be a list of frames of {H.N_DOF} numbers") from None
    elif path.suffix == ".npz":
        try:
            with np.load(path, allow_pickle=False) as z:
                arrays = {k: z[k] for k in z.files}
        except (OSError, ValueError) as e:
            raise MotionError(f"{path}: not a readable .npz file ({e})") from None
        missing = [k for k in ("qpos", "hand", "fps") if k not in arrays]
        if missing:
            raise MotionError(f"{path}: missing array(s) {', '.join(missing)}")
        qpos = arrays["qpos"]
        fields = {"hand": str(arrays["hand"]), "fps": float(arrays["fps"]),
                  "joints": [str(x) for x in arrays["joints"]] if "joints" in arrays else None,
                  "name": str(arrays["name"]) if "name" in arrays else path.stem}
        version = int(arrays["format"]) if "format" in arrays else FORMAT_VERSION
        if version > FORMAT_VERSION:
            raise MotionError(f"{path}: motion format {version} is newer than this reader ({FORMAT_VERSION})")
    else:
        raise MotionError(f"{path}: unknown motion file type {path.suffix!r} (expected .npz or .json)")
    hand = fields["hand"]
    if hand not in HANDS:
        raise MotionError(f"{path}: hand must be 'left' or 'right', got {hand!r}")
    if fields["joints"] is not None and list(fields["joints"]) != list(joint_names(hand)):
        names = list(fields["joints"])
        if len(names) != H.N_DOF:
            raise MotionError(f"{path}: {len(names)} joint names, expected {H.N_DOF}")
        j = next(i for i, (a, b) in enumerate(zip(names, joint_names(hand))) if a != b)
        raise MotionError(f"{path}: joint {j} is {names[j]!r}, expected {joint_names(hand)[j]!r} "
                          f"(joints must be in dexguitar.world.hands.joints order)")
    try:
        fps = float(fields["fps"])
    except (TypeError, ValueError):
        raise MotionError(f"{path}: fps must be a number, got {fields['fps']!r}") from None
    if qpos.ndim != 2 or qpos.shape[-1] != H.N_DOF:
        raise MotionError(f"{path}: qpos has shape {qpos.shape}, expected (frames, {H.N_DOF})")
    return validate(Motion(hand, fps, qpos, str(fields["name"])), path)


# ----------------------------------------------------------------------------------------------------- time

def resample(motion: Motion, fps: float) -> Motion:
    """The motion at another frame rate, by linear interpolation of every joint (slides and hinges alike: hinge
    values are unwrapped angles, so linear interpolation is exact for constant joint speed). The new frames span the
    same time, 0 .. floor(seconds * fps) / fps; the last original frame is kept when it falls on the new grid."""
    fps = float(fps)
    if not fps > 0:
        raise MotionError(f"fps must be positive, got {fps}")
    if fps == motion.fps:
        return motion
    n = int(np.floor(motion.seconds * fps + 1e-9)) + 1
    t_new = np.arange(n) / fps
    t_old = motion.times
    q = motion.qpos
    out = np.empty((n, q.shape[1]), dtype=np.result_type(q.dtype, np.float32))
    for j in range(q.shape[1]):
        out[:, j] = np.interp(t_new, t_old, q[:, j])
    return motion.replace(fps=fps, qpos=out)
