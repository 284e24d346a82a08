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
`MotionError`s (an `InputError`) whose message names the file and, where it applies, the position: the frame and
joint, the array of a .npz, the line and column of bad JSON. A missing, empty, truncated or foreign file is such an
error too, never a traceback.
"""
from __future__ import annotations

import dataclasses
import io
import json
from pathlib import Path

import numpy as np

from dexguitar.errors import InputError, read_input
from dexguitar.world import hands as H

FORMAT_VERSION = 1
HANDS = ("left", "right")
# Joint values may leave their range by this much (m for slides, rad for hinges): the PD-driven simulation overshoots
# limits slightly, and recorded motions keep that.
RANGE_TOL = 0.02
# Frame rates a motion may have: captures run at 60..480 fps; outside this range the number is a mistake, and resampling
# two frames at 1e-6 fps to 60 fps would allocate 60 million frames.
FPS_RANGE = (1.0, 1000.0)


class MotionError(InputError):
    """A motion file or array that does not fit the format; the message names the source and the position."""


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
    if motion.hand not in HANDS:
        raise MotionError(source, None, f"hand must be 'left' or 'right', got {motion.hand!r}")
    if not FPS_RANGE[0] <= motion.fps <= FPS_RANGE[1]:
        raise MotionError(source, None, f"fps must lie in {FPS_RANGE[0]:g}..{FPS_RANGE[1]:g}, got {motion.fps}")
    q = motion.qpos
    if q.ndim != 2 or q.shape[1] != H.N_DOF:
        raise MotionError(source, None, f"qpos must have shape (frames, {H.N_DOF}), got {q.shape}")
    if q.shape[0] < 1:
        raise MotionError(source, None, "the motion has no frames")
    if not np.issubdtype(q.dtype, np.floating):
        raise MotionError(source, None, f"qpos must be floating point, got {q.dtype}")
    bad = ~np.isfinite(q)
    if bad.any():
        t, j = np.argwhere(bad)[0]
        raise MotionError(source, f"frame {t}, joint {joint_names(motion.hand)[j]}",
                          f"non-finite value ({int(bad.sum())} in all)")
    rng = joint_ranges(motion.hand)
    excess = np.maximum(rng[:, 0] - tol - q, q - rng[:, 1] - tol)
    if (excess > 0).any():
        t, j = np.unravel_index(np.argmax(excess), excess.shape)
        name = joint_names(motion.hand)[j]
        raise MotionError(source, f"frame {t}, joint {name}",
                          f"{q[t, j]:.4f} is outside the joint's range [{rng[j, 0]:.4f}, {rng[j, 1]:.4f}] (tolerance "
                          f"{tol}; {int((excess > 0).sum())} values out of range). Is this a {motion.hand}-hand "
                          f"motion?")
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
        raise MotionError(path, None, f"unknown motion file type {path.suffix!r} (expected .npz or .json)")
    return path


def read_bytes(path: Path) -> bytes:
    """A motion file's bytes; `MotionError` if it is missing, unreadable or empty."""
    return read_input(path, "a motion file", MotionError)


def read_json(path: Path):
    """The JSON document of a motion file (a UTF-8 byte-order mark is allowed); `MotionError` if it is not JSON."""
    try:
        return json.loads(read_bytes(path).decode("utf-8-sig"))
    except UnicodeDecodeError as e:
        raise MotionError(path, f"byte {e.start}", "not UTF-8 text, so not a JSON motion (a .npz renamed?)") from None
    except json.JSONDecodeError as e:
        raise MotionError(path, f"line {e.lineno}, column {e.colno}", f"not valid JSON: {e.msg}") from None
    except RecursionError:
        raise MotionError(path, None, "not a motion: JSON nested too deeply") from None
    except ValueError as e:      # e.g. an integer of more than 4300 digits
        raise MotionError(path, None, f"not valid JSON: {e}") from None


def _npz_arrays(path: Path) -> dict[str, np.ndarray]:
    data = read_bytes(path)
    if not data.startswith(b"PK"):
        raise MotionError(path, "byte 0", "not a .npz file (a .npz is a zip archive, which starts with 'PK')")
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except Exception as e:  # a truncated or corrupt archive: zipfile, zlib and numpy raise many kinds
        raise MotionError(path, None, f"not a readable .npz file ({type(e).__name__}: {e}); truncated?") from None


def _scalar(path: Path, arrays: dict, key: str):
    """The single value of a 0-d array of a .npz."""
    a = arrays[key]
    if a.shape != () or a.dtype.kind not in "biufU":
        raise MotionError(path, f"array '{key}'", f"expected a single number or string, got {a.dtype} {a.shape}")
    return a.item()


def load(path: str | Path) -> Motion:
    """Read a `.npz` or `.json` motion written by `save` (or by hand) and validate it."""
    path = Path(path)
    if path.suffix == ".json":
        doc = read_json(path)
        if not isinstance(doc, dict) or "qpos" not in doc:
            hint = (" (this looks like the authors' format: use dexguitar.motion.official.read_official_json)"
                    if isinstance(doc, dict) and "frames" in doc else "")
            raise MotionError(path, None, f"expected an object with 'hand', 'fps' and 'qpos'{hint}")
        joints = doc.get("joints")
        if joints is not None and not (isinstance(joints, list) and all(isinstance(n, str) for n in joints)):
            raise MotionError(path, "key 'joints'", f"expected a list of {H.N_DOF} joint names")
        fields = {"hand": doc.get("hand"), "fps": doc.get("fps"), "joints": joints,
                  "name": doc.get("name", path.stem)}
        try:
            qpos = np.asarray(doc["qpos"], dtype=np.float64)
        except (TypeError, ValueError):
            raise MotionError(path, "key 'qpos'", f"expected a list of frames of {H.N_DOF} numbers") from None
    elif path.suffix == ".npz":
        arrays = _npz_arrays(path)
        missing = [k for k in ("qpos", "hand", "fps") if k not in arrays]
        if missing:
            raise MotionError(path, None, f"missing array(s) {', '.join(missing)}: not a motion file?")
        qpos = arrays["qpos"]
        if "joints" in arrays and arrays["joints"].ndim != 1:
            raise MotionError(path, "array 'joints'", f"expected {H.N_DOF} joint names, got shape "
                                                      f"{arrays['joints'].shape}")
        fields = {"hand": _scalar(path, arrays, "hand"), "fps": _scalar(path, arrays, "fps"),
                  "joints": [str(x) for x in arrays["joints"]] if "joints" in arrays else None,
                  "name": _scalar(path, arrays, "name") if "name" in arrays else path.stem}
        version = _scalar(path, arrays, "format") if "format" in arrays else FORMAT_VERSION
        if not isinstance(version, int) or version > FORMAT_VERSION:
            raise MotionError(path, "array 'format'", f"motion format {version!r} is not one this reader knows "
                                                      f"(1..{FORMAT_VERSION})")
    else:
        raise MotionError(path, None, f"unknown motion file type {path.suffix!r} (expected .npz or .json)")
    hand = fields["hand"]
    if hand not in HANDS:
        raise MotionError(path, None, f"hand must be 'left' or 'right', got {hand!r}")
    if fields["joints"] is not None and list(fields["joints"]) != list(joint_names(hand)):
        names = list(fields["joints"])
        if len(names) != H.N_DOF:
            raise MotionError(path, None, f"{len(names)} joint names, expected {H.N_DOF}")
        j = next(i for i, (a, b) in enumerate(zip(names, joint_names(hand))) if a != b)
        raise MotionError(path, f"joint {j}", f"{names[j]!r}, expected {joint_names(hand)[j]!r} "
                                              f"(joints must be in dexguitar.world.hands.joints order)")
    try:
        fps = float(fields["fps"])
    except (TypeError, ValueError):
        raise MotionError(path, None, f"fps must be a number, got {fields['fps']!r}") from None
    if qpos.ndim != 2 or qpos.shape[-1] != H.N_DOF:
        raise MotionError(path, None, f"qpos has shape {qpos.shape}, expected (frames, {H.N_DOF})")
    return validate(Motion(hand, fps, qpos, str(fields["name"])), path)


# ----------------------------------------------------------------------------------------------------- time

def resample(motion: Motion, fps: float) -> Motion:
    """The motion at another frame rate, by linear interpolation of every joint (slides and hinges alike: hinge
    values are unwrapped angles, so linear interpolation is exact for constant joint speed). The new frames span the
    same time, 0 .. floor(seconds * fps) / fps; the last original frame is kept when it falls on the new grid."""
    fps = float(fps)
    if not fps > 0:
        raise MotionError(None, None, f"fps must be positive, got {fps}")
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
