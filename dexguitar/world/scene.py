"""Scene assembly: guitar + hands as one MuJoCo model, for MuJoCo (rendering, tools) and MJX (training).

Three scenes: the left hand with the guitar (fretting), the right hand with the guitar (picking) and both. The hands
are attached as children of the fixed guitar body, so their wrist slides move in the guitar frame. Roles are named
as for a right-handed player: the "left" hand (prefix `lh_`) frets and the "right" hand (prefix `rh_`) picks. With
`mirror=True` (a left-handed player) the guitar's x axis is mirrored, the fretting role is played by the right-hand
model and the picking role by the left-hand model; everything downstream works in the guitar frame and is unchanged.

Strings and fret wires are virtual (visual only): colliding fret boxes cost ~5x in MJX throughput. The fretting
hand collides with the neck, the picking hand with the body; fingers of one hand do not collide with each other
except the right thumb with the index finger, which hold the pick together. Visual geoms are dropped from the
training model (`visual=False`): they would only cost kinematics.
"""
from __future__ import annotations

import dataclasses
import functools

import mujoco
import numpy as np

from dexguitar.world import hands as H
from dexguitar.world.guitar import (BODY_TOP_Z, GUITAR, GUITAR_POS, GUITAR_QUAT, NECK_END_Y, Guitar)

CONTROL_HZ = 60
PHYSICS_HZ = 240
SUBSTEPS = PHYSICS_HZ // CONTROL_HZ
ROLES = ("left", "right")
PREFIX = {"left": "lh_", "right": "rh_"}
SCENES = {"left": ("left",), "right": ("right",), "duet": ("left", "right")}

# Collision bits: the fretting hand meets the neck, the picking hand meets the body.
HAND_CONTYPE = {"left": 1, "right": 2}
NECK_AFFINITY, BODY_AFFINITY = 1, 2

# Home poses for a right-handed player (guitar frame): the left hand around fret 5 with the thumb behind the neck,
# the right hand over the strings between the end of the fretboard and the bridge holding the pick.
# 27 values each in `hands.joints` order; found by least squares on fingertip and pick targets, and rounded.
HOME = {
    "left": np.array([0.0907, -0.0181, -0.014, -0.1298, 1.0632, -2.0536, 0.6452, -0.9723, 0.7358, 0.6063, 0.4211,
                      0.4382, -0.0543, 0.7912, 0.4892, 0.4323, -0.0521, 1.1287, 0.7207, 0.5472, -0.0616, 1.139,
                      0.7008, 0.7445, -0.0504, 0.9171, 0.5233]),
    "right": np.array([-0.0901, -0.3676, 0.1088, 0.9753, 0.2929, 0.8035, 0.2555, 0.7521, -0.6857, -0.7051, -0.5201,
                       0.3092, -0.0329, 1.111, 0.5383, 1.0, 0.0, 1.2, 0.8, 1.0213, 0.0285, 1.2044, 0.8, 1.0198, 0.0218,
                       1.2072, 0.8]),
}


def _mat_to_quat(mat: np.ndarray) -> np.ndarray:
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.asarray(mat, dtype=np.float64).reshape(9))
    return q


def guitar_quat(mirror: bool) -> np.ndarray:
    """World orientation of the guitar frame. Mirrored: reflect the world across x = 0 (the camera's left/right)
    and the guitar frame across its own x, which composes into a proper rotation."""
    q = np.asarray(GUITAR_QUAT, dtype=np.float64)
    q = q / np.linalg.norm(q)
    if not mirror:
        return q
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, q)
    flip = np.diag([-1.0, 1.0, 1.0])
    return _mat_to_quat(flip @ rot.reshape(3, 3) @ flip)


def guitar_xml(guitar: Guitar = GUITAR, mirror: bool | None = None) -> str:
    """MJCF of the guitar: a neck box and a body box to touch, everything else visual."""
    g = guitar if mirror is None else dataclasses.replace(guitar, mirror=mirror)
    f = lambda v: " ".join(f"{float(x):.6g}" for x in np.atleast_1d(v))  # noqa: E731
    neck_len = g.nut_y - NECK_END_Y
    neck_mid = (g.nut_y + NECK_END_Y) / 2
    lines = [
        '<mujoco model="guitar">',
        '  <!-- Written by dexguitar.world.scene from the geometry in dexguitar.world.guitar. -->',
        '  <default>',
        '    <default class="visual"><geom contype="0" conaffinity="0" group="1"/></default>',
        '  </default>',
        '  <asset>',
        '    <material name="wood" rgba="0.45 0.25 0.12 1"/>',
        '    <material name="board" rgba="0.18 0.1 0.06 1"/>',
        '    <material name="top" rgba="0.85 0.6 0.3 1"/>',
        '    <material name="metal" rgba="0.8 0.8 0.78 1"/>',
        '    <material name="bone" rgba="0.95 0.93 0.85 1"/>',
        '  </asset>',
        '  <worldbody>',
        f'    <body name="guitar" pos="{f(GUITAR_POS)}" quat="{f(guitar_quat(g.mirror))}">',
        # Collision: the neck (fretboard top at z = FRETBOARD_Z) and the body below the picking zone.
        f'      <geom name="neck" type="box" pos="0 {neck_mid:.6g} {(g.fretboard_z - 0.008) / 2:.6g}" '
        f'size="0.024 {neck_len / 2:.6g} {(g.fretboard_z + 0.008) / 2:.6g}" contype="0" '
        f'conaffinity="{NECK_AFFINITY}" material="board" group="1"/>',
        f'      <geom name="body" type="box" pos="0 -0.4 {BODY_TOP_Z - 0.02:.6g}" size="0.15 0.17 0.02" contype="0" '
        f'conaffinity="{BODY_AFFINITY}" material="top" group="1"/>',
        f'      <geom name="headstock" class="visual" type="box" pos="0 {g.nut_y + 0.09:.6g} 0" '
        f'size="0.045 0.09 0.008" material="wood"/>',
        f'      <geom name="nut" class="visual" type="box" pos="0 {g.nut_y:.6g} {g.fretboard_z + 0.0015:.6g}" '
        f'size="0.0215 0.0015 0.0015" material="bone"/>',
        f'      <geom name="bridge" class="visual" type="box" pos="0 {g.bridge_y:.6g} {BODY_TOP_Z + 0.006:.6g}" '
        f'size="0.04 0.006 0.006" material="bone"/>',
        f'      <geom name="soundhole" class="visual" type="cylinder" pos="0 -0.3 {BODY_TOP_Z + 0.0002:.6g}" '
        f'size="0.045 0.0002" rgba="0.05 0.03 0.02 1"/>',
    ]
    for k in range(1, g.n_frets + 1):
        y = g.fret_y[k]
        lines.append(f'      <geom name="fret{k}" class="visual" type="box" '
                     f'pos="0 {y:.6g} {g.fretboard_z + 0.0009:.6g}" '
                     f'size="{float(g.neck_half_width(y)):.6g} 0.0006 0.0009" material="metal"/>')
    for i, (a, b) in enumerate(g.strings, start=1):
        lines.append(f'      <geom name="string{i}" class="visual" type="capsule" fromto="{f(a)} {f(b)}" '
                     f'size="{0.0004 + 0.00012 * i:.5f}" material="metal"/>')
    for k in (3, 5, 7, 9, 12, 15, 17, 19, 21):
        y = (g.fret_y[k] + g.fret_y[k - 1]) / 2
        for x in ((-0.007, 0.007) if k == 12 else (0.0,)):
            lines.append(f'      <geom class="visual" type="cylinder" pos="{x:.4g} {y:.6g} {g.fretboard_z:.6g}" '
                         f'size="0.0025 0.0002" material="bone"/>')
    lines += ['    </body>', '  </worldbody>', '</mujoco>', '']
    return "\n".join(lines)


def build_spec(scene: str = "duet", *, mirror: bool = False, visual: bool = True,
               guitar: Guitar = GUITAR) -> mujoco.MjSpec:
    """Assemble a scene ("left", "right" or "duet") as an MjSpec."""
    if scene not in SCENES:
        raise ValueError(f"unknown scene {scene!r}; expected one of {', '.join(SCENES)}")
    spec = mujoco.MjSpec.from_string(guitar_xml(guitar, mirror))
    spec.modelname = f"dexguitar_{scene}" + ("_mirrored" if mirror else "")
    spec.option.timestep = 1.0 / PHYSICS_HZ
    spec.option.gravity = [0.0, 0.0, 0.0]   # the hands are weightless (reference §2.1); nothing else moves
    spec.option.iterations = 4
    spec.option.ls_iterations = 8
    spec.compiler.discardvisual = not visual
    spec.visual.global_.offwidth, spec.visual.global_.offheight = 1280, 720
    body = spec.body("guitar")
    if visual:
        spec.worldbody.add_light(pos=[0.0, 1.0, 2.5], dir=[0.0, -0.4, -1.0], diffuse=[0.8, 0.8, 0.8])
        # in front of the player, looking back at the guitar (image right = world -x)
        spec.worldbody.add_camera(name="front", pos=[-0.15, 0.8, 1.0], xyaxes=[-1, 0, 0, 0, -0.2, 1])
    for role in SCENES[scene]:
        model_side = role if not mirror else ("right" if role == "left" else "left")
        hand = mujoco.MjSpec.from_string(H.hand_xml(model_side, role))
        spec.attach(hand, prefix=PREFIX[role], frame=body.add_frame())
        for geom in spec.geoms:
            if geom.name.startswith(PREFIX[role]):
                geom.contype, geom.conaffinity = HAND_CONTYPE[role], 0
    home = np.concatenate([home_qpos(role, mirror) for role in SCENES[scene]])
    spec.add_key(name="home", qpos=home, ctrl=home)
    return spec


def home_qpos(role: str, mirror: bool = False) -> np.ndarray:
    q = HOME[role]
    return H.mirror_qpos(q, side_from=role) if mirror else q.copy()


@functools.lru_cache(maxsize=16)
def build_model(scene: str = "duet", *, mirror: bool = False, visual: bool = False) -> mujoco.MjModel:
    return build_spec(scene, mirror=mirror, visual=visual).compile()


@dataclasses.dataclass(frozen=True)
class HandIndex:
    """Where one hand lives inside a compiled scene (all plain ints/tuples: hashable, usable as jit constants)."""

    role: str
    qpos: tuple[int, ...]          # 27 qpos addresses (= qvel addresses: hinges and slides only)
    actuators: tuple[int, ...]     # 27 actuator ids, same order
    key_bodies: tuple[int, ...]    # 16 key links (hands.KEY_LINKS order)
    segments: tuple[tuple[int, int, int], ...]  # per finger: (body 1, body 2, body 3) of index..pinky
    tips: tuple[int, ...]          # fingertip sites index..pinky
    thumb_tip: int
    pick: int                      # pick site (right role only, else -1)


def hand_index(model: mujoco.MjModel, role: str) -> HandIndex:
    p = PREFIX[role]
    jid = lambda n: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, p + n)  # noqa: E731
    bid = lambda n: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, p + n)  # noqa: E731
    sid = lambda n: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, p + n)  # noqa: E731
    aid = lambda n: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, p + n)  # noqa: E731
    js = H.joints("left")
    if jid(js[0].name) < 0:
        raise ValueError(f"the model has no {role} hand")
    return HandIndex(
        role=role,
        qpos=tuple(int(model.jnt_qposadr[jid(j.name)]) for j in js),
        actuators=tuple(aid(j.name) for j in js),
        key_bodies=tuple(bid(n) for n in H.KEY_LINKS),
        segments=tuple((bid(f"{f}1"), bid(f"{f}2"), bid(f"{f}3")) for f in H.FINGERS),
        tips=tuple(sid(f"{f}_tip") for f in H.FINGERS),
        thumb_tip=sid("thumb_tip"),
        pick=_required(sid("pick"), "the picking hand has no pick site") if role == "right" else -1,
    )


def _required(index: int, message: str) -> int:
    if index < 0:
        raise ValueError(message)
    return index


def guitar_pose(model: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray]:
    """(position, rotation matrix) of the guitar frame in the world; constant (the guitar is fixed)."""
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "guitar")
    return data.xpos[b].copy(), data.xmat[b].reshape(3, 3).copy()


def write_models(directory=H.MODELS_DIR) -> list:
    """Write models/guitar.xml and the three scenes (full, with visuals) for viewers and inspection."""
    from pathlib import Path
    paths = [Path(directory) / "guitar.xml"]
    paths[0].write_text(guitar_xml())
    for name in SCENES:
        path = Path(directory) / f"scene_{name}.xml"
        path.write_text(build_spec(name).to_xml())
        paths.append(path)
    return paths


def to_guitar_frame(model: mujoco.MjModel):
    """A function mapping world points (..., 3) to the guitar frame: p_g = R^T (p - p_0). Works on numpy and jax."""
    pos, rot = guitar_pose(model)

    def apply(p):
        return (p - pos) @ rot
    return apply


def finger_segments(xpos, site_xpos, hand: HandIndex):
    """(12, 2, 3) axis segments MCP->PIP, PIP->DIP, DIP->tip of index..pinky, in the frame of `xpos`."""
    starts, ends = [], []
    for (b1, b2, b3), tip in zip(hand.segments, hand.tips):
        starts += [xpos[b1], xpos[b2], xpos[b3]]
        ends += [xpos[b2], xpos[b3], site_xpos[tip]]
    stack = np.stack if isinstance(xpos, np.ndarray) else __import__("jax.numpy").numpy.stack
    return stack([stack(starts), stack(ends)], axis=1)
