"""Reader for the authors' motion clips (JSON), converted to our joint values.

Their format: `{"fps": 120, "frames": [{body: value, ...}, ...]}` with body names prefixed "RH:" or "LH:":

* `wrist_dx`, `wrist_dy`, `wrist_dz`: 3-lists, the local translations [x, 0, 0], [0, y, 0], [0, 0, z] of the wrist
  slides in the guitar frame -> our `wrist_tx/ty/tz`.
* `wrist`, `thumb1..3`, `index1..3`, `middle1..3`, `ring1..3`, `pinky1..3`: 4-lists, each body's local rotation
  relative to its parent's rest frame as a quaternion in **xyzw** order.

Their hand has our joint structure and axis conventions (bodies axis-aligned at zero angles; wrist hinges x, y, z;
thumb1 x, y, z; thumb2 z; thumb3 z; finger1 x, z; finger2 x; finger3 x), so each body's rotation converts to our
joint angles:

* one hinge about axis a: the rotation is about a, angle = 2 atan2(q_a, w) (exact);
* three hinges x, y, z in one body: MuJoCo composes a body's joints in order, R = Rx(a) Ry(b) Rz(c) (intrinsic
  x -> y -> z Euler angles), decomposed exactly as b = asin(R02), a = atan2(-R12, R22), c = atan2(-R01, R00)
  (b is kept in [-pi/2, pi/2]; at b = +-pi/2 only a + c or a - c is defined, and c = 0 is taken);
* two hinges x, z (finger MCP): R = Rx(a) Rz(c) cannot express every rotation (the quaternion of Rx(a) Rz(c) has
  y = -sin(a/2) sin(c/2)); their clips store finger1 rotations with y = 0, i.e. a single rotation about an axis in
  the x-z plane. We take the (a, c) whose quaternion is nearest (largest |<q, q(a, c)>|), in closed form: with
  M = [[w^2 + x^2, wz - xy], [wz - xy, y^2 + z^2]], c/2 is the angle of M's leading eigenvector and
  a/2 = atan2(x cos(c/2) - y sin(c/2), w cos(c/2) + z sin(c/2)). On the authors' strum clip the rotation left over
  is at most 0.5 deg for index..ring and 3 deg for the pinky (its MCP bends most in both axes).

The frame rate is kept (resample with `format.resample`). Values outside our joint ranges are clipped, with one
warning giving the count. Errors are `MotionError`s naming the file and the frame (and body) where they apply.
"""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from dexguitar.motion.format import Motion, MotionError, clip_to_ranges, joint_names, read_json, validate
from dexguitar.world import hands as H

PREFIXES = {"LH": "left", "RH": "right"}
_AXIS = {"x": 0, "y": 1, "z": 2}


# ----------------------------------------------------------------------------------------------------- rotations

def hinge_angle(q_xyzw, axis: str) -> np.ndarray:
    """Angle of a rotation about one axis from its xyzw quaternion (..., 4)."""
    q = np.asarray(q_xyzw, dtype=np.float64)
    return 2.0 * np.arctan2(q[..., _AXIS[axis]], q[..., 3])


def quat_to_matrix(q_xyzw) -> np.ndarray:
    """(..., 3, 3) rotation matrix of a (normalised here) xyzw quaternion."""
    q = np.asarray(q_xyzw, dtype=np.float64)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    x, y, z, w = np.moveaxis(q, -1, 0)
    return np.stack([np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
                     np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
                     np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], -2)


def euler_xyz(q_xyzw) -> np.ndarray:
    """(..., 3) intrinsic x -> y -> z angles (a, b, c) with R = Rx(a) Ry(b) Rz(c), MuJoCo's order for three hinges
    x, y, z in one body."""
    R = quat_to_matrix(q_xyzw)
    b = np.arcsin(np.clip(R[..., 0, 2], -1.0, 1.0))
    lock = np.abs(R[..., 0, 2]) > 1 - 1e-9
    a = np.where(lock, np.arctan2(R[..., 2, 1], R[..., 1, 1]), np.arctan2(-R[..., 1, 2], R[..., 2, 2]))
    c = np.where(lock, 0.0, np.arctan2(-R[..., 0, 1], R[..., 0, 0]))
    return np.stack([a, b, c], axis=-1)


def euler_xz(q_xyzw) -> np.ndarray:
    """(..., 2) angles (a, c) of the rotation Rx(a) Rz(c) nearest to the quaternion (see the module docstring)."""
    q = np.asarray(q_xyzw, dtype=np.float64)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    x, y, z, w = np.moveaxis(q, -1, 0)
    m00, m11, m01 = w * w + x * x, y * y + z * z, w * z - x * y
    g = 0.5 * np.arctan2(2 * m01, m00 - m11)          # leading eigenvector angle of the 2x2 form
    a2 = np.arctan2(x * np.cos(g) - y * np.sin(g), w * np.cos(g) + z * np.sin(g))
    return np.stack([2 * a2, 2 * g], axis=-1)


def quat_from_euler_xyz(a, b, c) -> np.ndarray:
    """xyzw quaternion of Rx(a) Ry(b) Rz(c) (for tests and round trips)."""
    def axis_quat(angle, i):
        q = np.zeros(np.shape(angle) + (4,))
        q[..., i] = np.sin(np.asarray(angle) / 2)
        q[..., 3] = np.cos(np.asarray(angle) / 2)
        return q
    return _mul_xyzw(_mul_xyzw(axis_quat(a, 0), axis_quat(b, 1)), axis_quat(c, 2))


def _mul_xyzw(p, q):
    x1, y1, z1, w1 = np.moveaxis(p, -1, 0)
    x2, y2, z2, w2 = np.moveaxis(q, -1, 0)
    return np.stack([w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2, w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                     w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2, w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2], axis=-1)


# ----------------------------------------------------------------------------------------------------- reader

# Their body -> (kind, our joint names): "slide" takes component i of the 3-list.
def _layout():
    out = [("wrist_dx", "slide", ("wrist_tx",)), ("wrist_dy", "slide", ("wrist_ty",)),
           ("wrist_dz", "slide", ("wrist_tz",)), ("wrist", "xyz", ("wrist_rx", "wrist_ry", "wrist_rz")),
           ("thumb1", "xyz", ("thumb1_x", "thumb1_y", "thumb1_z")), ("thumb2", "z", ("thumb2",)),
           ("thumb3", "z", ("thumb3",))]
    for f in H.FINGERS:
        out += [(f"{f}1", "xz", (f"{f}1_x", f"{f}1_z")), (f"{f}2", "x", (f"{f}2",)), (f"{f}3", "x", (f"{f}3",))]
    return tuple(out)


LAYOUT = _layout()


def _infer_hand(path, frame0) -> str:
    if not isinstance(frame0, dict):
        raise MotionError(path, "frame 0", f"a frame must be an object of body values, got {type(frame0).__name__}")
    prefixes = {k.split(":", 1)[0] for k in frame0 if ":" in k}
    hands = {PREFIXES[p] for p in prefixes if p in PREFIXES}
    if len(hands) != 1:
        raise MotionError(path, "frame 0", f"cannot tell the hand from body names (prefixes {sorted(prefixes)}; "
                                           f"expected LH: or RH:)")
    return hands.pop()


def read_official_json(path: str | Path, hand: str | None = None) -> Motion:
    """The authors' JSON motion clip as a `Motion` of our joints at the clip's frame rate. `hand` ("left" /
    "right") picks one hand where a clip holds both; by default it is inferred from the LH: / RH: prefix."""
    path = Path(path)
    doc = read_json(path)
    if not isinstance(doc, dict) or not isinstance(doc.get("frames"), list) or "fps" not in doc:
        raise MotionError(path, None, "expected an object with 'fps' and a list 'frames'")
    frames = doc["frames"]
    if not frames:
        raise MotionError(path, None, "no frames")
    try:
        fps = float(doc["fps"])
    except (TypeError, ValueError):
        raise MotionError(path, None, f"fps must be a number, got {doc['fps']!r}") from None
    if hand is None:
        hand = _infer_hand(path, frames[0])
    if hand not in PREFIXES.values():
        raise MotionError(path, None, f"hand must be 'left' or 'right', got {hand!r}")
    prefix = next(p for p, h in PREFIXES.items() if h == hand) + ":"

    # Gather every body's values into arrays, checking shapes frame by frame.
    values = {}
    for body, kind, _ in LAYOUT:
        key = prefix + body
        size = 3 if kind == "slide" else 4
        rows = np.empty((len(frames), size))
        for t, fr in enumerate(frames):
            if not isinstance(fr, dict) or key not in fr:
                raise MotionError(path, f"frame {t}", f"missing body {key!r}")
            v = fr[key]
            try:
                rows[t] = v
            except (TypeError, ValueError):
                raise MotionError(path, f"frame {t}", f"{key} must be {size} numbers, got {v!r}") from None
            if not np.all(np.isfinite(rows[t])):
                raise MotionError(path, f"frame {t}", f"{key} has a non-finite value {v!r}")
            if size == 4 and np.linalg.norm(rows[t]) < 1e-6:
                raise MotionError(path, f"frame {t}", f"{key} is not a rotation (zero quaternion)")
        values[body] = rows

    names = joint_names(hand)
    col = {n: i for i, n in enumerate(names)}
    qpos = np.zeros((len(frames), H.N_DOF))
    for body, kind, ours in LAYOUT:
        v = values[body]
        if kind == "slide":
            qpos[:, col[ours[0]]] = v[:, "xyz".index(ours[0][-1])]
        elif kind == "xyz":
            qpos[:, [col[n] for n in ours]] = euler_xyz(v)
        elif kind == "xz":
            qpos[:, [col[n] for n in ours]] = euler_xz(v)
        else:
            qpos[:, col[ours[0]]] = hinge_angle(v / np.linalg.norm(v, axis=-1, keepdims=True), kind)
    clipped, n_clipped = clip_to_ranges(qpos, hand)
    if n_clipped:
        moved = [n for j, n in enumerate(names) if np.any(clipped[:, j] != qpos[:, j])]
        worst = np.abs(clipped - qpos).max()
        warnings.warn(f"{path}: {n_clipped} joint values clipped to our joint ranges, at most by {worst:.3f} "
                      f"({', '.join(moved)})", stacklevel=2)
    return validate(Motion(hand, fps, clipped, name=path.stem), path)


def is_official_json(path: str | Path) -> bool:
    """Cheap test: a .json file whose start mentions "frames" (ours has "qpos"). Any file that is not, or cannot be
    read, goes to `format.load`, which says what is wrong with it."""
    path = Path(path)
    if path.suffix != ".json" or not path.is_file():
        return False
    try:
        with open(path, "rb") as f:
            head = f.read(4096)
    except OSError:
        return False
    return b'"frames"' in head and b'"qpos"' not in head
