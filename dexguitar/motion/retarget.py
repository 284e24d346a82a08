"""Human reference motions from the authors' guitarist motion capture: marker CSV -> our two 27-DoF hands.

`dexguitar motion retarget CSV --out MOTION [--hand left|right|both]`. The capture (CC BY-NC-ND: read from a path
given at run time; neither it nor anything retargeted from it goes into the repository) is a CSV of marker
positions, one row per frame at 120 fps, in millimetres, `nan` where a marker was occluded:

    Marker1..4-{X,Y,Z}                 the guitar: 1 (bass side) and 2 (treble side) on the pickguard beside the
                                       neck pickup, 3 (treble side) and 4 (bass side, by the low-E tuner) on the
                                       headstock
    {L,R}-{A..E}{1,2,3}-{X,Y,Z}        per hand, A thumb, B index, C middle, D ring, E pinky; 1 the nail, 2 the next
                                       joint (PIP; thumb IP), 3 the knuckle (MCP; thumb MCP)
    {L,R}-Wan-{nei,1,2,wai}-{X,Y,Z}    the wrist: radial styloid (thumb side), two on the back of the hand, ulnar
                                       styloid (pinky side)

Three steps, each a function here:

1. `read_markers`: the CSV -> `MarkerData` (metres). Errors name the file, the line and the column.
2. `register_guitar` / `to_guitar_frame`: every frame, the guitar's four markers give a rigid "marker frame"
   (origin midway between markers 1 and 2, y toward the midpoint of 3 and 4 = along the neck, z the normal of the
   marker plane = out of the fretboard, x = y x z toward the treble strings); a median template of the four markers
   is fitted to each frame by Kabsch, so frames with a marker missing still register and the guitar may move. The
   marker frame maps onto our guitar frame (`world.guitar`) by the documented assumptions of `Registration`: where
   the neck centreline, the nut and the fretboard are, and a uniform scale about the nut from 25.5" to our scale.
3. `retarget_targets`: inverse kinematics of one hand to its markers for all frames at once in JAX (`solve_ik`),
   with a per-clip calibration of where the markers sit on the hand links (`calibrate_offsets`), then the fit error
   per marker (mm, our guitar frame); `to_motion` makes the `Motion` (capture rate, joints clipped to range).

The marker model (`MARKERS`): every marker is a point fixed in one link of our hand. Our hand is larger than the
captured one in places (e.g. PIP marker to nail: 29-31 mm in the captures, 30-46 mm on our fingers), so no pose fits
every marker; we let the fingertips win: nail markers (A1..E1) sit at a fixed point 8 mm behind our fingertip site,
9 mm toward the back of the finger, with double weight, so our fingertips land where the player's did (on the
strings). Joint markers (2 and thumb 3) sit near their joint axes (their distance to the markers on both sides of the
joint hardly changes in the captures) and may slide along their link in the calibration (that absorbs bone-length
differences; a free 3-D offset would trade against the joint angle and drift); knuckles (B3..E3) and the four wrist
markers sit on the palm link and calibrate freely. The styloid markers ride on the forearm, which our hand lacks:
half weight. `IKConfig(free_nails=True)` (`--free-nails`) lets nails slide too: lower marker error, fingertips
overshoot the player's.
"""
from __future__ import annotations

import dataclasses
import functools
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from dexguitar.errors import InputError, UserError
from dexguitar.motion.format import Motion, clip_to_ranges, resample, save
from dexguitar.world import guitar as G
from dexguitar.world import hands as H
from dexguitar.world import scene as S

CAPTURE_FPS = 120.0
DUPLICATE_TOL = 0.004                  # two markers of one hand this close (m) in a frame: a labelling glitch
CAPTURE_SCALE_LENGTH = 0.6477          # Fender American Deluxe Stratocaster: 25.5 in
GUITAR_MARKERS = ("Marker1", "Marker2", "Marker3", "Marker4")
SIDES = {"left": "L", "right": "R"}


class RetargetError(UserError, ValueError):
    """A marker file or request that cannot be retargeted; the message names the file (and line / column)."""


class MarkerFileError(InputError, RetargetError):
    """A malformed marker CSV: the message names the file, the line and the column."""


# ----------------------------------------------------------------------------------------------------- CSV

@dataclasses.dataclass(frozen=True, eq=False)
class MarkerData:
    """Marker positions of one capture: `xyz` (T, N, 3) in metres (nan = occluded), `names` the N marker names."""

    path: str
    names: tuple[str, ...]
    xyz: np.ndarray
    fps: float = CAPTURE_FPS

    @property
    def n_frames(self) -> int:
        return int(self.xyz.shape[0])

    def index(self, name: str) -> int:
        return self.names.index(name)

    def get(self, name: str) -> np.ndarray:
        """(T, 3) positions of one marker; all nan when the file has no such marker."""
        if name not in self.names:
            return np.full((self.n_frames, 3), np.nan)
        return self.xyz[:, self.names.index(name)]

    def hands(self) -> tuple[str, ...]:
        """The hands ("left", "right") with at least one marker column in the file."""
        return tuple(h for h, p in SIDES.items() if any(n.startswith(p + "-") for n in self.names))

    def frames(self, start: int = 0, stop: int | None = None) -> "MarkerData":
        return dataclasses.replace(self, xyz=self.xyz[start:stop])


_NAN_WORDS = {"nan", "-nan", "+nan", "", "na", "n/a"}


def read_markers(path: str | Path, *, unit: float = 0.001) -> MarkerData:
    """Read a marker CSV (header `NAME-X,NAME-Y,NAME-Z,...`, one row per frame, values in mm, `nan` or an empty
    field for an occluded marker). The four guitar markers are required; hand markers may be absent (Pick1 has
    none of the left hand). Raises `MarkerFileError` naming the file, line and column of anything malformed."""
    path = Path(path)

    def text(raw: bytes, line_no: int) -> str:
        try:
            return raw.decode("utf-8-sig" if line_no == 1 else "utf-8")
        except UnicodeDecodeError as e:
            raise MarkerFileError(path, f"line {line_no}, column {e.start + 1}",
                                  "not UTF-8 text: expected a CSV of marker positions (is this a binary file?)"
                                  ) from None

    try:
        f = open(path, "rb")
    except FileNotFoundError:
        raise MarkerFileError(path, None, "no such file") from None
    except OSError as e:
        raise MarkerFileError(path, None, f"cannot read the file: {e.strerror or e}") from None
    with f:
        header = text(f.readline(), 1)
        if not header.strip():
            raise MarkerFileError(path, None, "empty file (expected a header row of marker columns NAME-X,NAME-Y,"
                                              "NAME-Z)")
        cols = [c.strip() for c in header.strip().split(",")]
        if len(cols) % 3:
            raise MarkerFileError(path, "line 1", f"{len(cols)} columns, expected X, Y, Z for every marker "
                                                  f"(a multiple of 3)")
        names = []
        for i in range(0, len(cols), 3):
            base = cols[i][:-2]
            for j, axis in enumerate("XYZ"):
                c = cols[i + j]
                if c[-2:].upper() != f"-{axis}" or c[:-2] != base or not base:
                    raise MarkerFileError(path, f"line 1, column {i + j + 1}",
                                          f"{c!r}; expected {base or 'NAME'}-{axis} (columns come as NAME-X, NAME-Y, "
                                          f"NAME-Z)")
            if base in names:
                raise MarkerFileError(path, "line 1", f"marker {base!r} appears twice")
            names.append(base)
        missing = [m for m in GUITAR_MARKERS if m not in names]
        if missing:
            raise MarkerFileError(path, "line 1", f"no column for the guitar marker(s) {', '.join(missing)} "
                                                  f"(needed to place the guitar)")
        rows = []
        for line_no, raw in enumerate(f, start=2):
            line = text(raw, line_no)
            if not line.strip():
                continue
            fields = line.rstrip("\r\n").split(",")
            if len(fields) != len(cols):
                raise MarkerFileError(path, f"line {line_no}", f"{len(fields)} fields, expected {len(cols)} (one per "
                                                               f"header column)")
            try:
                rows.append([float("nan") if v.strip().lower() in _NAN_WORDS else float(v) for v in fields])
            except ValueError:
                k = next(k for k, v in enumerate(fields) if not _is_number(v))
                raise MarkerFileError(path, f"line {line_no}, column {k + 1} ({cols[k]})",
                                      f"{fields[k].strip()!r} is not a number (use nan for a missing marker)"
                                      ) from None
    if not rows:
        raise MarkerFileError(path, None, "no frames after the header")
    xyz = np.asarray(rows, dtype=np.float64).reshape(len(rows), len(names), 3) * unit
    if np.isinf(xyz).any():
        t, k, a = np.argwhere(np.isinf(xyz))[0]
        raise MarkerFileError(path, f"line {t + 2}, column {3 * k + a + 1} ({names[k]}-{'XYZ'[a]})", "infinite value")
    return MarkerData(str(path), tuple(names), xyz)


def _is_number(field: str) -> bool:
    try:
        float(field)
    except ValueError:
        return field.strip().lower() in _NAN_WORDS
    return True


# ----------------------------------------------------------------------------------------------------- guitar

@dataclasses.dataclass(frozen=True)
class Registration:
    """How the guitar's marker frame maps onto our guitar frame. The marker positions on the real guitar are not
    documented; these constants come from the marker photo (`mocap/doc/marker_guitar.png`) and were checked against
    where the fretting fingertips land (docs/retarget.md):

    nut_along        nut, in capture metres along the marker frame's y from the midpoint of markers 1 and 2. In the
                     photo that midpoint lies one fret spacing (~11.5 mm) on the body side of fret 22 (at 466.1 mm
                     from the nut on a 25.5" scale); a projective fit to all 22 fret wires of the photo gives 478 mm.
    centre_x         marker-frame x of the neck centreline: both marker midpoints sit ~2 mm toward the treble side.
    fretboard_z      marker-frame z of the fretboard surface: the marker centres (on ~8 mm bases on the pickguard and
                     on the headstock face) are assumed level with the fretboard.
    scale            "uniform" (default): every coordinate scales by our / captured scale length about the nut on
                     the fretboard, so frets and strings land on ours and hands keep their shape (4% smaller);
                     "neck": only the along-neck coordinate scales (frets map, hands stretch 4% along the neck);
                     "none": capture metres.
    """

    nut_along: float = 0.478
    centre_x: float = -0.002
    fretboard_z: float = 0.0
    scale: str = "uniform"
    capture_scale_length: float = CAPTURE_SCALE_LENGTH

    @property
    def factor(self) -> float:
        return G.SCALE_LENGTH / self.capture_scale_length if self.scale != "none" else 1.0

    def __post_init__(self):
        if self.scale not in ("uniform", "neck", "none"):
            raise ValueError(f"scale must be 'uniform', 'neck' or 'none', got {self.scale!r}")


def marker_frame(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(R (..., 3, 3) with the frame axes as columns, origin (..., 3)) of the guitar marker frame from the four
    markers (..., 4, 3); nan where a marker is missing."""
    p = np.asarray(points, dtype=np.float64)
    o = 0.5 * (p[..., 0, :] + p[..., 1, :])
    y = 0.5 * (p[..., 2, :] + p[..., 3, :]) - o
    y = y / np.linalg.norm(y, axis=-1, keepdims=True)
    z = np.cross(p[..., 1, :] - p[..., 0, :], y)
    z = z / np.linalg.norm(z, axis=-1, keepdims=True)
    x = np.cross(y, z)
    return np.stack([x, y, z], axis=-1), o


def kabsch(src: np.ndarray, dst: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation R and translation t minimizing sum w |R src + t - dst|^2, batched: src/dst (..., N, 3), w (..., N)
    (zero weight = missing). Needs three non-collinear weighted points per batch entry."""
    w = w[..., None]
    sw = np.maximum(w.sum(-2), 1e-12)
    cs, cd = (w * src).sum(-2) / sw, (w * dst).sum(-2) / sw
    a, b = src - cs[..., None, :], dst - cd[..., None, :]
    cov = np.einsum("...ni,...nj->...ij", w * a, b)
    u, _, vt = np.linalg.svd(cov)
    d = np.sign(np.linalg.det(np.einsum("...ij,...jk->...ik", u, vt)))
    fix = np.ones(u.shape[:-2] + (3,))
    fix[..., 2] = d
    rot = np.einsum("...ji,...j,...kj->...ik", vt, fix, u)
    return rot, cd - np.einsum("...ij,...j->...i", rot, cs)


def _fill_nearest(valid: np.ndarray) -> np.ndarray:
    """For every frame the index of the nearest frame where `valid` holds."""
    idx = np.flatnonzero(valid)
    t = np.arange(len(valid))
    pos = np.clip(np.searchsorted(idx, t), 1, len(idx) - 1) if len(idx) > 1 else np.zeros_like(t)
    if len(idx) == 1:
        return np.full(len(valid), idx[0])
    left, right = idx[pos - 1], idx[pos]
    return np.where(np.abs(t - left) <= np.abs(right - t), left, right)


@dataclasses.dataclass(frozen=True, eq=False)
class GuitarTrack:
    """Per-frame pose of the guitar marker frame in capture coordinates, and the template it was fitted with."""

    rot: np.ndarray        # (T, 3, 3) marker-frame axes as columns
    origin: np.ndarray     # (T, 3)
    template: np.ndarray   # (4, 3) the guitar markers in the marker frame
    registered: np.ndarray  # (T,) bool: at least three guitar markers seen (else the nearest such frame's pose)
    fit_error: np.ndarray   # (T, 4) distance of each guitar marker from the fitted template (m; nan if missing)


def register_guitar(markers: MarkerData) -> GuitarTrack:
    """Fit the guitar marker template to every frame (Kabsch); raises if the four markers are never seen together."""
    pts = np.stack([markers.get(m) for m in GUITAR_MARKERS], axis=1)
    present = ~np.isnan(pts).any(-1)
    full = present.all(-1)
    if not full.any():
        raise RetargetError(f"{markers.path}: the four guitar markers are never all visible in one frame")
    rot, o = marker_frame(pts[full])
    template = np.median(np.einsum("tji,tnj->tni", rot, pts[full] - o[:, None]), axis=0)
    enough = present.sum(-1) >= 3
    src = np.broadcast_to(template, pts.shape)
    rot_all = np.tile(np.eye(3), (len(pts), 1, 1))
    org = np.zeros((len(pts), 3))
    r, t = kabsch(src[enough], np.nan_to_num(pts[enough]), present[enough].astype(float))
    rot_all[enough], org[enough] = r, t
    near = _fill_nearest(enough)
    rot_all, org = rot_all[near], org[near]
    fitted = np.einsum("tij,nj->tni", rot_all, template) + org[:, None]
    err = np.where(present, np.linalg.norm(fitted - pts, axis=-1), np.nan)
    return GuitarTrack(rot_all, org, template, enough, err)


def to_guitar_frame(points: np.ndarray, track: GuitarTrack, reg: Registration = Registration()) -> np.ndarray:
    """Capture points (T, ..., 3) -> our guitar frame (m), frame by frame; nan stays nan."""
    p = np.asarray(points, dtype=np.float64)
    extra = p.ndim - 2
    o = track.origin.reshape(track.origin.shape[:1] + (1,) * extra + (3,))
    local = np.einsum("tji,t...j->t...i", track.rot, p - o)
    u = local - np.array([reg.centre_x, reg.nut_along, reg.fretboard_z])
    s = reg.factor
    u = u * (np.array([1.0, s, 1.0]) if reg.scale == "neck" else s)
    return u + np.array([0.0, G.NUT_Y, G.FRETBOARD_Z])


def from_guitar_frame(points: np.ndarray, track: GuitarTrack, reg: Registration = Registration()) -> np.ndarray:
    """The inverse of `to_guitar_frame` (tests use it to make synthetic captures)."""
    p = np.asarray(points, dtype=np.float64)
    s = reg.factor
    u = p - np.array([0.0, G.NUT_Y, G.FRETBOARD_Z])
    u = u / (np.array([1.0, s, 1.0]) if reg.scale == "neck" else s)
    local = u + np.array([reg.centre_x, reg.nut_along, reg.fretboard_z])
    extra = p.ndim - 2
    o = track.origin.reshape(track.origin.shape[:1] + (1,) * extra + (3,))
    return np.einsum("tij,t...j->t...i", track.rot, local) + o


# ----------------------------------------------------------------------------------------------------- markers

@dataclasses.dataclass(frozen=True)
class MarkerSpec:
    name: str              # marker name without the hand prefix ("B1", "Wan-nei")
    link: str              # hand link it rides on (hands.KEY_LINKS)
    offset: tuple          # nominal offset in that link's frame, right-hand model (the left mirrors x), m
    weight: float = 1.0
    free: str = "xyz"      # link-frame axes the per-clip calibration may move


# Skin height of a marker centre above the bone axis (finger radius ~6 mm + marker base and ball).
DORSAL = 0.009
# Joint markers (PIP, thumb IP and MCP) stay at a nearly constant distance from the markers on both sides of
# their joint in the captures: they sit close to the joint axis.
JOINT_DORSAL = 0.005
# Nail markers: this far behind the fingertip site (the end of the distal capsule axis), fixed, weighted up.
NAIL_BACK = 0.008
NAIL_WEIGHT = 2.0
# Which side of the thumb links (pointing along +x at zero angles) the thumb markers are on is not obvious from the
# model's axes; of +-y, +-z and the diagonals, -z fits the thumb markers of Strum, Pick1 and BendDual best.
THUMB_DORSAL = (0.0, 0.0, -1.0)


def _marker_specs() -> tuple[MarkerSpec, ...]:
    """The nominal marker model of a right hand (fingers along -y, back of the hand +z, thumb toward +x).

    Finger and thumb markers may only slide along their link in the calibration (the data fixes the bone lengths
    between markers; a free offset on a short distal link would trade against the joint angle and drift), palm
    markers move freely (the palm is one rigid link, so its marker layout is well determined)."""
    out = []
    lt = H.LENGTHS["thumb"]
    up = np.asarray(THUMB_DORSAL) * DORSAL
    out += [MarkerSpec("A1", "thumb3", tuple(up + [lt[2] - NAIL_BACK, 0, 0]), NAIL_WEIGHT, free=""),
            MarkerSpec("A2", "thumb2", tuple(up * JOINT_DORSAL / DORSAL + [lt[1], 0, 0]), free="x"),
            MarkerSpec("A3", "thumb1", tuple(up * JOINT_DORSAL / DORSAL + [lt[0], 0, 0]), free="x")]
    for letter, f in zip("BCDE", H.FINGERS):
        ln = H.LENGTHS[f]
        out += [MarkerSpec(f"{letter}1", f"{f}3", (0.0, -(ln[2] - NAIL_BACK), DORSAL), NAIL_WEIGHT, free=""),
                MarkerSpec(f"{letter}2", f"{f}1", (0.0, -ln[0], JOINT_DORSAL), free="y"),
                MarkerSpec(f"{letter}3", "wrist", tuple(H.MCP[f] + np.array([0.0, 0.0, 0.012])))]
    out += [MarkerSpec("Wan-nei", "wrist", (0.030, 0.025, 0.0), 0.5),
            MarkerSpec("Wan-1", "wrist", (0.012, 0.0, 0.022)),
            MarkerSpec("Wan-2", "wrist", (-0.015, 0.012, 0.020)),
            MarkerSpec("Wan-wai", "wrist", (-0.035, 0.025, 0.0), 0.5)]
    return tuple(out)


MARKERS = _marker_specs()
MARKER_NAMES = tuple(m.name for m in MARKERS)
PALM_MARKERS = tuple(i for i, m in enumerate(MARKERS) if m.link == "wrist")
NAIL_MARKERS = tuple(i for i, m in enumerate(MARKERS) if m.name[1:] == "1")
FREE_AXES = np.array([[a in m.free for a in "xyz"] for m in MARKERS], dtype=np.float64)


def nominal_offsets(side: str) -> np.ndarray:
    """(19, 3) nominal marker offsets of that hand model (the left hand mirrors x)."""
    off = np.array([m.offset for m in MARKERS], dtype=np.float64)
    if side == "left":
        off[:, 0] *= -1.0
    return off


# ----------------------------------------------------------------------------------------------------- kinematics

@dataclasses.dataclass(frozen=True, eq=False)
class HandChain:
    """One hand's kinematic tree read from our MuJoCo model, relative to the guitar frame, for FK in JAX.
    Structure (parents, joints) is plain Python; numbers are arrays, so one jitted solver serves both hands."""

    side: str
    parents: tuple[int, ...]                      # per link, its parent link (-1: the guitar)
    joints: tuple[tuple[tuple[int, int, int], ...], ...]   # per link: (dof, type 2 slide / 3 hinge, axis 0..2)
    body_pos: np.ndarray                          # (16, 3)
    body_rot: np.ndarray                          # (16, 3, 3)
    lo: np.ndarray                                # (27,) joint ranges
    hi: np.ndarray
    links: tuple[str, ...]                        # link names (hands.KEY_LINKS order = model order)
    marker_link: np.ndarray                       # (19,) link index of each marker
    depends: np.ndarray                           # (19, 27) 1 where the dof moves the marker
    slide: np.ndarray                             # (27,) 1 for the wrist slides


@functools.lru_cache(maxsize=4)
def hand_chain(side: str) -> HandChain:
    """Read the chain of `side`'s hand model from `scene.build_model(side)` (its own fretting/picking scene)."""
    model = S.build_model(side)
    hand = S.hand_index(model, side)
    bodies = list(hand.key_bodies)
    dof_of_qadr = {a: i for i, a in enumerate(hand.qpos)}
    parents, joints = [], []
    rot = np.zeros((len(bodies), 3, 3))
    for k, b in enumerate(bodies):
        pb = int(model.body_parentid[b])
        parents.append(bodies.index(pb) if pb in bodies else -1)
        if pb not in bodies and pb != mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "guitar"):
            raise RuntimeError(f"hand link {model.body(b).name} is not attached to the guitar")
        js = []
        for j in range(model.body_jntadr[b], model.body_jntadr[b] + model.body_jntnum[b]):
            axis = np.asarray(model.jnt_axis[j])
            if np.any(model.jnt_pos[j] != 0) or np.count_nonzero(axis) != 1 or axis.max() != 1:
                raise RuntimeError(f"joint {model.joint(j).name}: expected a unit x/y/z axis at the body origin")
            js.append((dof_of_qadr[int(model.jnt_qposadr[j])], int(model.jnt_type[j]), int(np.argmax(axis))))
        joints.append(tuple(js))
        m = np.zeros(9)
        mujoco.mju_quat2Mat(m, model.body_quat[b])
        rot[k] = m.reshape(3, 3)
    names = tuple(model.body(b).name[len(S.PREFIX[side]):] for b in bodies)
    rng = np.array([j.range for j in H.joints(side)])
    link = np.array([names.index(m.link) for m in MARKERS])
    depends = np.zeros((len(MARKERS), H.N_DOF))
    slide = np.zeros(H.N_DOF)
    for i, k in enumerate(link):
        while k >= 0:                    # every dof of the marker's link and of its ancestors moves it
            for dof, kind, _ in joints[k]:
                depends[i, dof] = 1.0
                slide[dof] = float(kind == 2)
            k = parents[k]
    return HandChain(side, tuple(parents), tuple(joints), np.array(model.body_pos[bodies], dtype=np.float64), rot,
                     rng[:, 0].copy(), rng[:, 1].copy(), names, link, depends, slide)


def _axis_rot(jnp, axis: int, angle):
    c, s = jnp.cos(angle), jnp.sin(angle)
    one, zero = jnp.ones_like(angle), jnp.zeros_like(angle)
    rows = {0: ((one, zero, zero), (zero, c, -s), (zero, s, c)),
            1: ((c, zero, s), (zero, one, zero), (-s, zero, c)),
            2: ((c, -s, zero), (s, c, zero), (zero, zero, one))}[axis]
    return jnp.stack([jnp.stack(r) for r in rows])


def _fk(structure, body_pos, body_rot, q):
    """Link positions (16, 3) and rotations (16, 3, 3) in the guitar frame for joint values q (27,), as MuJoCo's
    mj_kinematics composes them: each link = parent * body offset, then its joints in order (slides along, hinges
    about, the link's current axes). Also every dof's world axis and anchor (27, 3) for the Jacobian."""
    parents, joints = structure
    pos, rot = [], []
    axes, anchors = [None] * len(q), [None] * len(q)
    for k, par in enumerate(parents):
        if par < 0:
            p, r = body_pos[k], body_rot[k]
        else:
            p = pos[par] + rot[par] @ body_pos[k]
            r = rot[par] @ body_rot[k]
        for dof, kind, axis in joints[k]:
            axes[dof], anchors[dof] = r[:, axis], p
            if kind == 2:
                p = p + r[:, axis] * q[dof]
            else:
                r = r @ _axis_rot(jnp, axis, q[dof])
        pos.append(p)
        rot.append(r)
    return jnp.stack(pos), jnp.stack(rot), jnp.stack(axes), jnp.stack(anchors)


def _markers_fk(structure, body_pos, body_rot, marker_link, offsets, q):
    pos, rot = _fk(structure, body_pos, body_rot, q)[:2]
    return pos[marker_link] + (rot[marker_link] @ offsets[:, :, None])[..., 0]


def _markers_jac(structure, body_pos, body_rot, marker_link, offsets, depends, slide, q):
    """Model markers (19, 3) and their Jacobian (19, 3, 27), analytically: a slide moves a dependent marker along
    its axis, a hinge about its axis through its anchor (axis x (marker - anchor))."""
    pos, rot, axes, anchors = _fk(structure, body_pos, body_rot, q)
    x = pos[marker_link] + (rot[marker_link] @ offsets[:, :, None])[..., 0]
    lever = jnp.cross(axes[None, :, :], x[:, None, :] - anchors[None, :, :])        # (19, 27, 3)
    col = jnp.where(slide[None, :, None] > 0, axes[None, :, :], lever) * depends[:, :, None]
    return x, jnp.swapaxes(col, 1, 2)


def _structure(chain: HandChain):
    return (chain.parents, chain.joints)


@functools.lru_cache(maxsize=8)
def _fk_batch(structure):
    return jax.jit(jax.vmap(functools.partial(_fk, structure), in_axes=(None, None, 0)))


def link_poses(chain: HandChain, qpos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(T, 16, 3) link positions and (T, 16, 3, 3) rotations in the guitar frame for (T, 27) joint values."""
    pos, rot = _fk_batch(_structure(chain))(jnp.asarray(chain.body_pos, jnp.float32),
                                             jnp.asarray(chain.body_rot, jnp.float32),
                                             jnp.asarray(qpos, jnp.float32))[:2]
    return np.asarray(pos, np.float64), np.asarray(rot, np.float64)


def marker_positions(side: str, qpos: np.ndarray, offsets: np.ndarray | None = None) -> np.ndarray:
    """(T, 19, 3) model marker positions (guitar frame) of joint values (T, 27), `MARKER_NAMES` order."""
    chain = hand_chain(side)
    off = nominal_offsets(side) if offsets is None else np.asarray(offsets, dtype=np.float64)
    pos, rot = link_poses(chain, np.atleast_2d(qpos))
    return pos[:, chain.marker_link] + np.einsum("tmij,mj->tmi", rot[:, chain.marker_link], off)


# ----------------------------------------------------------------------------------------------------- IK

@dataclasses.dataclass(frozen=True)
class IKConfig:
    """Weights of the least-squares IK (marker residuals in mm):

    smooth_hinge / smooth_slide  temporal smoothness: a frame-to-frame change of 1/smooth rad (m) costs as much as
                                 1 mm of marker error (default: 0.1 rad, 2 mm; at 120 fps)
    prior                        pull toward the initial pose per rad/m (keeps joints no marker sees in place)
    coupling / coupling_ratio    soft anatomical coupling of each finger's DIP to its PIP, DIP ~ ratio x PIP:
                                 a deviation of 1/coupling rad costs as much as 1 mm of marker error (the nail
                                 marker sits close to the DIP, so its angle is weakly determined otherwise)
    rounds / sweeps              calibration rounds (offsets re-estimated between rounds) and LM sweeps per round
                                 (one sweep updates even frames, then odd frames)
    offset_sigma                 nominal-offset prior of the calibration, m, against 1 mm of noise per frame seen
                                 (weak: a hundredth of one frame's worth at the default)
    robust_scale                 observations this far (m) off the previous round's fit count half (default 0:
                                 off; it also discounts the systematic misfit of our bigger fingers)
    free_nails                   calibrate nail markers along the finger too (see the module docstring)
    """

    smooth_hinge: float = 10.0
    smooth_slide: float = 500.0
    prior: float = 0.02
    coupling: float = 20.0
    coupling_ratio: float = 0.7
    rounds: int = 3
    sweeps: tuple[int, ...] = (40, 25, 25)
    offset_sigma: float = 0.01
    max_offset_change: float = 0.03
    calibrate: bool = True
    free_nails: bool = False
    robust_scale: float = 0.0


def _dof_weights(cfg: IKConfig) -> np.ndarray:
    kinds = np.array([j.kind == "slide" for j in H.joints("left")])
    return np.where(kinds, cfg.smooth_slide, cfg.smooth_hinge)


def _spd_solve(a, b):
    """x = a^-1 b for a symmetric positive definite (n, n) by Gaussian elimination without pivoting (stable for
    SPD), in plain jnp ops. Why not jnp.linalg.solve: its batched LAPACK LU on the XLA CPU thread pool deadlocks
    intermittently (jaxlib 0.10, vmapped inside a loop, large batches)."""
    n = a.shape[-1]
    rows = jnp.arange(n)

    def eliminate(k, ab):
        a, b = ab
        f = jnp.where(rows > k, a[:, k] / a[k, k], 0.0)
        return a - f[:, None] * a[k][None, :], b - f * b[k]

    a, b = jax.lax.fori_loop(0, n, eliminate, (a, b))

    def substitute(i, x):
        k = n - 1 - i
        return x.at[k].set((b[k] - a[k] @ x) / a[k, k])

    return jax.lax.fori_loop(0, n, substitute, jnp.zeros_like(b))


def _coupling(cfg: IKConfig) -> np.ndarray:
    """(4, 27) rows of the linear prior coupling(DIP - ratio PIP) = 0, one per finger (same for both hands: the
    mirror leaves x-hinges alone)."""
    names = [j.name for j in H.joints("right")]
    out = np.zeros((len(H.FINGERS), H.N_DOF))
    for i, f in enumerate(H.FINGERS):
        out[i, names.index(f"{f}3")] = cfg.coupling
        out[i, names.index(f"{f}2")] = -cfg.coupling * cfg.coupling_ratio
    return out


@functools.lru_cache(maxsize=8)
def _solver(structure):
    """A jitted red-black Levenberg-Marquardt on all frames: `sweeps` x (even frames, then odd frames)."""

    def frame_step(q, mu, x, m, qp, qn, hp, hn, qref, consts, lo, hi):
        body_pos, body_rot, marker_link, offsets, wsq, s2, p2, depends, slide, lin = consts
        sw = jnp.sqrt(wsq * m)[:, None] * 1000.0                       # residuals in (weighted) mm

        def cost_of(v, r):
            return (jnp.sum(r ** 2) + jnp.sum(s2 * (hp * (v - qp) ** 2 + hn * (v - qn) ** 2))
                    + jnp.sum(p2 * (v - qref) ** 2) + jnp.sum((lin @ v) ** 2))

        pred, jac = _markers_jac(structure, body_pos, body_rot, marker_link, offsets, depends, slide, q)
        r = ((pred - x) * sw).reshape(-1)
        jac = (jac * sw[:, :, None]).reshape(-1, q.shape[0])
        cost = cost_of(q, r)
        a = jac.T @ jac + jnp.diag(s2 * (hp + hn) + p2) + lin.T @ lin
        g = jac.T @ r + s2 * (hp * (q - qp) + hn * (q - qn)) + p2 * (q - qref) + lin.T @ (lin @ q)
        a_d = a + mu * (jnp.diag(jnp.diag(a)) + 1e-3 * jnp.eye(q.shape[0]))
        dq = -_spd_solve(a_d, g)
        q_try = jnp.clip(q + dq, lo, hi)
        pred_try = _markers_fk(structure, body_pos, body_rot, marker_link, offsets, q_try)
        cost_try = cost_of(q_try, ((pred_try - x) * sw).reshape(-1))
        ok = cost_try < cost
        return (jnp.where(ok, q_try, q), jnp.where(ok, jnp.maximum(mu / 3.0, 1e-5), jnp.minimum(mu * 4.0, 1e5)),
                jnp.minimum(cost, cost_try))

    vstep = jax.vmap(frame_step, in_axes=(0,) * 9 + (None,) * 3)

    def run(q, x, m, qref, has_prev, has_next, consts, lo, hi, sweeps):
        # Frames (T even) as pairs: [:, 0] the even frames, [:, 1] the odd ones.
        pair = lambda a: a.reshape((a.shape[0] // 2, 2) + a.shape[1:])      # noqa: E731
        q, x, m, qref, hp, hn = map(pair, (q, x, m, qref, has_prev, has_next))
        mu = jnp.full(q.shape[:2], 1e-2, q.dtype)
        cost = jnp.zeros(q.shape[:2], q.dtype)

        def sweep(_, carry):
            q, mu, _ = carry
            ev, od = q[:, 0], q[:, 1]
            ev, mu_e, c_e = vstep(ev, mu[:, 0], x[:, 0], m[:, 0], jnp.concatenate([od[:1], od[:-1]]), od,
                                  hp[:, 0], hn[:, 0], qref[:, 0], consts, lo, hi)
            od, mu_o, c_o = vstep(od, mu[:, 1], x[:, 1], m[:, 1], ev, jnp.concatenate([ev[1:], ev[-1:]]),
                                  hp[:, 1], hn[:, 1], qref[:, 1], consts, lo, hi)
            return jnp.stack([ev, od], 1), jnp.stack([mu_e, mu_o], 1), jnp.stack([c_e, c_o], 1)

        q, mu, cost = jax.lax.fori_loop(0, sweeps, sweep, (q, mu, cost))
        return q.reshape((-1,) + q.shape[2:]), cost.reshape(-1)

    return jax.jit(run)


def solve_ik(chain: HandChain, targets: np.ndarray, q_init: np.ndarray, offsets: np.ndarray,
             cfg: IKConfig = IKConfig(), sweeps: int | None = None, q_ref: np.ndarray | None = None,
             frame_weights: np.ndarray | None = None) -> np.ndarray:
    """Joint values (T, 27) fitting the markers `targets` (T, 19, 3; nan = missing, masked out of the loss;
    `frame_weights` (T, 19) scales single observations, e.g. robust weights).

    The objective, over all frames together: sum of weighted squared marker errors (mm) + smoothness between
    consecutive frames + a weak pull toward `q_ref` (default `q_init`). Minimized by Levenberg-Marquardt on each
    frame's 27 joints with its neighbours held fixed, even frames then odd frames (red-black block coordinate
    descent: each half-sweep is exact for its frames, so the total cost never rises), vmapped over frames in JAX;
    joint limits by projection (clip) of every step. Warm start: `q_init` (the previous round's solution)."""
    targets = np.asarray(targets, dtype=np.float64)
    mask = (~np.isnan(targets).any(-1)).astype(np.float64)
    if frame_weights is not None:
        mask = mask * frame_weights
    x = np.nan_to_num(targets)
    w = np.array([m.weight for m in MARKERS])
    s2 = _dof_weights(cfg) ** 2
    p2 = np.full(H.N_DOF, cfg.prior ** 2)
    p2[:3] = (cfg.prior * 100.0) ** 2          # slides in m: 1 cm ~ 1 rad for the prior
    consts = tuple(jnp.asarray(a, jnp.float32) for a in (chain.body_pos, chain.body_rot)) + (
        jnp.asarray(chain.marker_link), jnp.asarray(offsets, jnp.float32), jnp.asarray(w, jnp.float32),
        jnp.asarray(s2, jnp.float32), jnp.asarray(p2, jnp.float32), jnp.asarray(chain.depends, jnp.float32),
        jnp.asarray(chain.slide, jnp.float32), jnp.asarray(_coupling(cfg), jnp.float32))
    run = _solver(_structure(chain))
    q0 = np.clip(q_init, chain.lo, chain.hi)
    qr = q0 if q_ref is None else np.asarray(q_ref, dtype=np.float64)
    t = len(q0)
    pad = t % 2                         # the solver pairs frames: repeat the last one, unseen and unlinked
    ext = lambda a: np.concatenate([a, a[-1:]]) if pad else a                # noqa: E731
    mask = np.concatenate([mask, np.zeros_like(mask[:1])]) if pad else mask
    idx = np.arange(t + pad)
    has_prev = np.repeat(((idx > 0) & (idx < t)).astype(np.float32)[:, None], H.N_DOF, 1)
    has_next = np.repeat((idx < t - 1).astype(np.float32)[:, None], H.N_DOF, 1)
    f32 = lambda a: jnp.asarray(a, jnp.float32)                               # noqa: E731
    q, _ = run(f32(ext(q0)), f32(ext(x)), f32(mask), f32(ext(qr)), f32(has_prev), f32(has_next), consts,
               f32(chain.lo), f32(chain.hi), jnp.asarray(sweeps if sweeps is not None else cfg.sweeps[0]))
    return np.asarray(q, np.float64)[:t]


def euler_xyz(rot: np.ndarray) -> np.ndarray:
    """Angles (a, b, c) with rot = Rx(a) Ry(b) Rz(c), b in [-pi/2, pi/2] (the wrist hinges' order), batched."""
    b = np.arcsin(np.clip(rot[..., 0, 2], -1.0, 1.0))
    a = np.arctan2(-rot[..., 1, 2], rot[..., 2, 2])
    c = np.arctan2(-rot[..., 0, 1], rot[..., 0, 0])
    return np.stack([a, b, c], axis=-1)


def initial_pose(chain: HandChain, targets: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """(T, 27) start poses: the wrist from a Kabsch fit of the palm-link markers (knuckles and wrist markers; the
    nearest frame with three of them where fewer are seen), the fingers from the home pose."""
    t = len(targets)
    q = np.tile(S.HOME[chain.side], (t, 1)).astype(np.float64)
    palm = np.array(PALM_MARKERS)
    dst = targets[:, palm]
    seen = ~np.isnan(dst).any(-1)
    enough = seen.sum(-1) >= 3
    if not enough.any():
        return q
    w = seen * np.array([MARKERS[i].weight for i in palm])
    src = np.broadcast_to(offsets[palm], dst.shape)
    rot, pos = kabsch(src[enough], np.nan_to_num(dst[enough]), w[enough])
    near = _fill_nearest(enough)
    r_all = np.zeros((t, 3, 3))
    p_all = np.zeros((t, 3))
    r_all[enough], p_all[enough] = rot, pos
    r_all, p_all = r_all[near], p_all[near]
    # The wrist link: guitar frame -> body offset (identity here) -> slides -> hinges x, y, z.
    r_all = np.einsum("ji,tjk->tik", chain.body_rot[0], r_all)
    q[:, 0:3] = p_all - chain.body_pos[0]
    ang = np.unwrap(euler_xyz(r_all), axis=0)          # no 2 pi jumps between frames ...
    ang -= 2 * np.pi * np.round(np.median(ang, axis=0) / (2 * np.pi))   # ... and centred in the hinge range
    q[:, 3:6] = ang
    return q


def calibrate_offsets(chain: HandChain, qpos: np.ndarray, targets: np.ndarray, nominal: np.ndarray,
                      cfg: IKConfig = IKConfig()) -> np.ndarray:
    """Per-clip marker offsets given the solved poses: for each marker the point in its link frame closest (least
    squares over the frames where it is seen) to where it was measured, along the marker's free axes only, pulled
    weakly toward the nominal offset (prior sigma `cfg.offset_sigma` against 1 mm of marker noise per frame) and at
    most `max_offset_change` from it. Closed form per axis: o = (sum_t [R_t^T (x_t - p_t)] + k o_nom) / (n + k)."""
    pos, rot = link_poses(chain, qpos)
    pos, rot = pos[:, chain.marker_link], rot[:, chain.marker_link]
    seen = ~np.isnan(targets).any(-1)
    local = np.einsum("tmji,tmj->tmi", rot, np.nan_to_num(targets) - pos)
    k = (0.001 / cfg.offset_sigma) ** 2
    n = seen.sum(0)[:, None]
    off = ((local * seen[..., None]).sum(0) + k * nominal) / (n + k)
    free = FREE_AXES.copy()
    if cfg.free_nails:                   # let nails slide along their distal link too (fit over fingertip placement)
        free[list(NAIL_MARKERS)] = [[a in ("x" if MARKERS[i].link.startswith("thumb") else "y") for a in "xyz"]
                                    for i in NAIL_MARKERS]
    d = (off - nominal) * free
    norm = np.linalg.norm(d, axis=-1, keepdims=True)
    return nominal + d * np.minimum(1.0, cfg.max_offset_change / np.maximum(norm, 1e-12))


@dataclasses.dataclass(frozen=True, eq=False)
class HandFit:
    side: str
    qpos: np.ndarray        # (T, 27)
    offsets: np.ndarray     # (19, 3) calibrated marker offsets
    targets: np.ndarray     # (T, 19, 3) measured markers in the guitar frame (nan = missing)
    fitted: np.ndarray      # (T, 19, 3) model markers at qpos
    seconds: float

    @property
    def errors(self) -> np.ndarray:
        """(T, 19) marker fit error in mm; nan where the marker is missing."""
        return np.linalg.norm(self.fitted - self.targets, axis=-1) * 1000.0

    def table(self) -> dict:
        """Per marker: mean and 95th percentile error (mm) over the frames where it is present, and how many."""
        e = self.errors
        out = {}
        for k, name in enumerate(MARKER_NAMES):
            v = e[:, k][~np.isnan(e[:, k])]
            out[name] = ({"mean": float(v.mean()), "p95": float(np.percentile(v, 95)), "frames": int(v.size)}
                         if v.size else {"mean": None, "p95": None, "frames": 0})
        v = e[~np.isnan(e)]
        out["all"] = {"mean": float(v.mean()) if v.size else None,
                      "p95": float(np.percentile(v, 95)) if v.size else None, "frames": int(v.size)}
        return out


def retarget_targets(side: str, targets: np.ndarray, cfg: IKConfig = IKConfig(),
                     offsets: np.ndarray | None = None) -> HandFit:
    """IK of one hand to markers already in our guitar frame (T, 19, 3), with per-clip offset calibration."""
    t0 = time.perf_counter()
    chain = hand_chain(side)
    nominal = nominal_offsets(side) if offsets is None else np.asarray(offsets, dtype=np.float64)
    off = nominal
    q0 = initial_pose(chain, targets, off)
    q = q0
    robust = None
    for rnd in range(cfg.rounds):
        q = solve_ik(chain, targets, q, off, cfg, sweeps=cfg.sweeps[min(rnd, len(cfg.sweeps) - 1)], q_ref=q0,
                     frame_weights=robust)
        if rnd < cfg.rounds - 1:
            if cfg.calibrate:
                off = calibrate_offsets(chain, q, targets, nominal, cfg)
            if cfg.robust_scale:
                # Cauchy-style reweighting (IRLS across rounds): an observation far off the fit (a marker swapped or
                # a ghost right after an occlusion) pulls less; 1 at 0 mm, 1/2 at robust_scale.
                e = np.linalg.norm(marker_positions(side, q, off) - targets, axis=-1)
                robust = 1.0 / (1.0 + (np.nan_to_num(e) / cfg.robust_scale) ** 2)
    q = np.clip(q, chain.lo, chain.hi)
    fitted = marker_positions(side, q, off)
    return HandFit(side, q, off, targets, fitted, time.perf_counter() - t0)


def drop_duplicates(points: np.ndarray, tol: float = DUPLICATE_TOL) -> tuple[np.ndarray, int]:
    """Markers (T, N, 3) with every pair closer than `tol` in a frame set to nan (both: which of the two labels is
    right cannot be told). Why: the capture has label glitches where an occluded marker reappears at another
    marker's position (e.g. a ring nail at the ring PIP for a frame), which would yank the finger."""
    d = np.linalg.norm(points[:, :, None] - points[:, None, :], axis=-1)
    n = points.shape[1]
    d[:, np.arange(n), np.arange(n)] = np.inf
    dup = (np.nan_to_num(d, nan=np.inf) < tol).any(-1)
    out = points.copy()
    out[dup] = np.nan
    return out, int(dup.sum())


def hand_targets(markers: MarkerData, side: str, track: GuitarTrack, reg: Registration = Registration()) -> np.ndarray:
    """(T, 19, 3) one hand's markers (`MARKER_NAMES` order) in our guitar frame; nan where missing (or duplicated,
    `drop_duplicates`)."""
    p = SIDES[side]
    raw = np.stack([markers.get(f"{p}-{n}") for n in MARKER_NAMES], axis=1)
    return to_guitar_frame(drop_duplicates(raw)[0], track, reg)


def retarget(markers: MarkerData, hands=("left", "right"), reg: Registration = Registration(),
             cfg: IKConfig = IKConfig()) -> dict[str, HandFit]:
    """Register the guitar and retarget the requested hands; raises when a requested hand has no markers."""
    track = register_guitar(markers)
    out = {}
    for side in hands:
        if side not in markers.hands():
            raise RetargetError(f"{markers.path}: no {side}-hand markers ({SIDES[side]}-...) in the file")
        out[side] = retarget_targets(side, hand_targets(markers, side, track, reg), cfg)
    return out


def to_motion(fit: HandFit, fps: float = CAPTURE_FPS, name: str = ""):
    """The fit as our `Motion` (joints clipped into range: the float32 solve can sit a hair outside)."""
    q, _ = clip_to_ranges(fit.qpos, fit.side)
    return Motion(fit.side, fps, q, name)


def output_paths(out: str | Path, hands, both: bool = True) -> dict[str, Path]:
    """`--hand both`: `<stem>-left<suffix>` / `<stem>-right<suffix>` beside `out` (even when the file has one
    hand); a single requested hand: `out` itself."""
    out = Path(out)
    if not both:
        return {h: out for h in hands}
    return {h: out.with_name(f"{out.stem}-{h}{out.suffix}") for h in hands}


def report(markers: MarkerData, fits: dict[str, HandFit], track: GuitarTrack | None = None,
           reg: Registration = Registration()) -> dict:
    """Error statistics only (nothing of the capture itself): per hand and marker mean / p95 fit error in mm and
    the frames it was seen, IK seconds; the guitar template's fit error; the registration used."""
    out = {"file": Path(markers.path).name, "frames": markers.n_frames, "fps": markers.fps,
           "registration": dataclasses.asdict(reg),
           "hands": {s: {"seconds": round(f.seconds, 2), "markers": f.table()} for s, f in fits.items()}}
    if track is not None:
        e = track.fit_error * 1000.0
        out["guitar_markers_mm"] = {m: (float(np.nanmean(e[:, i])) if np.isfinite(e[:, i]).any() else None)
                                    for i, m in enumerate(GUITAR_MARKERS)}
    return out


def retarget_file(csv: str | Path, out: str | Path, hand: str = "both", *, start: int = 0, stop: int | None = None,
                  fps: float | None = None, reg: Registration = Registration(), cfg: IKConfig = IKConfig(),
                  log=None) -> tuple[dict[str, Path], dict]:
    """The `motion retarget` command: read, register, retarget `hand` ("left", "right" or "both": every hand the
    file has markers of), save one motion per hand (`output_paths`), return (paths, `report`)."""
    if hand not in ("left", "right", "both"):
        raise RetargetError(f"--hand must be left, right or both, got {hand!r}")
    markers = read_markers(csv)
    present = markers.hands()
    if hand == "both":
        hands = present
        if not hands:
            raise RetargetError(f"{markers.path}: no hand markers (L-... or R-...) in the file")
        if log and len(hands) < 2:
            log(f"{markers.path}: only {hands[0]}-hand markers in the file; retargeting that hand")
    else:
        hands = (hand,)
    markers = markers.frames(start, stop)
    if markers.n_frames < 1:
        raise RetargetError(f"{markers.path}: no frames in [{start}, {'end' if stop is None else stop})")
    track = register_guitar(markers)
    fits = {}
    for side in hands:
        if side not in present:
            raise RetargetError(f"{markers.path}: no {side}-hand markers ({SIDES[side]}-...) in the file")
        fits[side] = retarget_targets(side, hand_targets(markers, side, track, reg), cfg)
    paths = output_paths(out, hands, both=hand == "both")
    stem = Path(markers.path).stem
    for side, fit in fits.items():
        motion = to_motion(fit, markers.fps, f"{stem} ({side} hand, retargeted)")
        if fps is not None and fps != motion.fps:
            motion = resample(motion, fps)
        save(motion, paths[side])
    return paths, report(markers, fits, track, reg)
