"""Export for animation tools: a performance's two hands as reference motions (`<out>-left.npz`, `<out>-right.npz`,
the `motion.format` files) and as one BVH file of both hands (`<out>.bvh`) that Blender, MotionBuilder and other
tools import as an animated skeleton.

The BVH skeleton is the MuJoCo scene's body tree below the guitar, one BVH joint per body, named as the bodies are
(`guitar`, `lh_wrist`, `lh_index1`, ..., `rh_pinky3`; `lh_` is the fretting hand, `rh_` the picking one):

    ROOT guitar      6 channels: the guitar's place and orientation in the world (constant)
      JOINT lh_wrist 6 channels: the wrist slides (position in the guitar frame) and the wrist hinges
        JOINT lh_thumb1 ... 3 rotation channels each; a fingertip is the End Site of the distal joint
      JOINT rh_wrist ...

Units are metres and degrees. The file is y-up, as BVH files are by convention: the root carries the turn from the
simulation's z-up world (x right, y toward the player, z up) to y-up, so Blender's default BVH import (forward -Z,
up Y, scale 1) puts every bone where the simulation has its body.

Rotations: a MuJoCo body turns by its hinges in their order, about axes of its own frame (R = Rx(a) Ry(b) Rz(c) for
hinges x, y, z). A BVH joint turns by its rotation channels in the order they are listed, also composed left to
right. So a hand joint lists its hinges' axes in MuJoCo's order (the axes a body lacks follow, always 0) and its
channel values are the joint angles themselves: exact, and continuous where the angles are (a wrist turning past
180 degrees does not wrap). A body whose rest orientation or hinge axes are not those of its parent (the guitar
root; other models) gets the Euler angles of its local rotation instead, unwrapped over time. Position channels
replace the joint's OFFSET in Blender and add to it elsewhere; every joint that has them has a zero OFFSET, so the
two readings agree.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import mujoco
import numpy as np

from dexguitar.motion.format import RANGE_TOL, Motion, MotionError, clip_to_ranges, save, validate
from dexguitar.world import hands as H
from dexguitar.world import scene as S

# The simulation's z-up world -> the y-up convention of BVH files: (x, y, z) -> (x, z, -y), a turn about x.
Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
AXES = "XYZ"
ROOT_ORDER = "XYZ"      # rotation channel order of joints that need Euler angles


@dataclasses.dataclass(frozen=True)
class Node:
    """One BVH joint: a MuJoCo body."""
    body: int
    name: str
    parent: int                   # index into the node list, -1 for the root
    offset: np.ndarray            # (3,) rest offset in the parent's frame, m
    position: bool                # has Xposition Yposition Zposition channels
    order: str                    # rotation channels, e.g. "XZY"
    end: np.ndarray | None        # End Site offset of a leaf, m


def _rotation(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """(T, 3, 3) rotations by `angle` (T,) about the unit `axis` (Rodrigues)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    s, c = np.sin(angle)[:, None, None], np.cos(angle)[:, None, None]
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)


def _quat_mat(quat: np.ndarray) -> np.ndarray:
    m = np.zeros(9)
    mujoco.mju_quat2Mat(m, np.asarray(quat, dtype=np.float64))
    return m.reshape(3, 3)


def euler(rot: np.ndarray, order: str) -> np.ndarray:
    """(..., 3) angles (rad) a, b, c with rot = R_order[0](a) R_order[1](b) R_order[2](c), the middle one in
    [-pi/2, pi/2]. At the middle angle's +-90 degrees (gimbal lock) the last angle is taken as 0."""
    i, j, k = (AXES.index(a) for a in order)
    s = 1.0 if (j - i) % 3 == 1 else -1.0        # +1 for the cyclic orders XYZ, YZX, ZXY
    r = np.asarray(rot, dtype=np.float64)
    b = np.arcsin(np.clip(s * r[..., i, k], -1.0, 1.0))
    a = np.arctan2(-s * r[..., j, k], r[..., k, k])
    c = np.arctan2(-s * r[..., i, j], r[..., i, i])
    lock = np.abs(np.cos(b)) < 1e-9
    if np.any(lock):
        a = np.where(lock, np.arctan2(s * r[..., k, j], r[..., j, j]), a)
        c = np.where(lock, 0.0, c)
    return np.stack([a, b, c], axis=-1)


def _body_joints(model: mujoco.MjModel, body: int) -> tuple[list[int], list[int]]:
    """The body's slide and hinge joint ids; raises unless it has only those, slides first, hinges at its origin."""
    ids = list(range(model.body_jntadr[body], model.body_jntadr[body] + model.body_jntnum[body]))
    name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body)
    kinds = [int(model.jnt_type[j]) for j in ids]
    slide, hinge = int(mujoco.mjtJoint.mjJNT_SLIDE), int(mujoco.mjtJoint.mjJNT_HINGE)
    if any(t not in (slide, hinge) for t in kinds):
        raise ValueError(f"body {name}: only slide and hinge joints can be written as BVH channels")
    if kinds != sorted(kinds, key=lambda t: t != slide):
        raise ValueError(f"body {name}: a slide after a hinge has no BVH channel")
    hinges = [j for j, t in zip(ids, kinds) if t == hinge]
    if any(np.any(model.jnt_pos[j] != 0) for j in hinges):
        raise ValueError(f"body {name}: a hinge away from the body's origin has no BVH channel")
    return [j for j, t in zip(ids, kinds) if t == slide], hinges


def _direct_order(model: mujoco.MjModel, body: int, hinges: list[int]) -> str | None:
    """The channel order whose values are the hinge angles themselves, or None where the body's rest orientation
    turns it from its parent or a hinge axis is not a coordinate axis (or two share one)."""
    if not np.allclose(_quat_mat(model.body_quat[body]), np.eye(3), atol=1e-12):
        return None
    axes = []
    for j in hinges:
        a = model.jnt_axis[j]
        k = int(np.argmax(np.abs(a)))
        if not np.allclose(np.abs(a), np.eye(3)[k], atol=1e-12) or AXES[k] in axes:
            return None
        axes.append(AXES[k])
    return "".join(axes) + "".join(a for a in AXES if a not in axes)


def skeleton(model: mujoco.MjModel, root: str = "guitar") -> list[Node]:
    """The BVH joints of the body tree below (and including) `root`, depth first: the order of the HIERARCHY and
    of every MOTION line. The root must be fixed in the world."""
    rid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, root)
    if rid <= 0:
        raise ValueError(f"the model has no body {root!r} to be the BVH root")
    b = rid
    while b > 0:
        if model.body_jntnum[b]:
            raise ValueError(f"the BVH root {root!r} must be fixed in the world")
        b = model.body_parentid[b]
    children = {b: [c for c in range(1, model.nbody) if model.body_parentid[c] == b and c != b]
                for b in range(model.nbody)}
    nodes: list[Node] = []

    def visit(body: int, parent: int) -> None:
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body)
        end = None
        if not children[body]:
            sites = [s for s in range(model.nsite) if model.site_bodyid[s] == body]
            end = model.site_pos[sites[0]].copy() if sites else np.zeros(3)
        if parent < 0:
            node = Node(body, name, -1, np.zeros(3), True, ROOT_ORDER, end)
        else:
            slides, hinges = _body_joints(model, body)
            order = _direct_order(model, body, hinges) or ROOT_ORDER
            offset = np.zeros(3) if slides else model.body_pos[body].copy()
            node = Node(body, name, parent, offset, bool(slides), order, end)
        nodes.append(node)
        me = len(nodes) - 1
        for c in children[body]:
            visit(c, me)

    visit(rid, -1)
    return nodes


def channels(model: mujoco.MjModel, nodes: list[Node], qpos: np.ndarray) -> np.ndarray:
    """(T, channels) BVH channel values (m, degrees) for (T, nq) MuJoCo joint values, in hierarchy order."""
    qpos = np.asarray(qpos, dtype=np.float64)
    T = len(qpos)
    cols = []
    for node in nodes:
        if node.parent < 0:
            data = mujoco.MjData(model)
            mujoco.mj_kinematics(model, data)
            pos = Y_UP @ data.xpos[node.body]
            rot = Y_UP @ data.xmat[node.body].reshape(3, 3)
            cols += [np.tile(pos, (T, 1)), np.tile(np.degrees(euler(rot, node.order)), (T, 1))]
            continue
        slides, hinges = _body_joints(model, node.body)
        r0 = _quat_mat(model.body_quat[node.body])
        if node.position:
            shift = sum(qpos[:, model.jnt_qposadr[j], None] * model.jnt_axis[j] for j in slides)
            cols.append(model.body_pos[node.body] + shift @ r0.T)
        if _direct_order(model, node.body, hinges) == node.order:
            angles = np.zeros((T, 3))
            for j in hinges:
                k = int(np.argmax(np.abs(model.jnt_axis[j])))
                angles[:, node.order.index(AXES[k])] = np.sign(model.jnt_axis[j][k]) * qpos[:, model.jnt_qposadr[j]]
        else:
            rot = np.broadcast_to(r0, (T, 3, 3))
            for j in hinges:
                rot = rot @ _rotation(model.jnt_axis[j], qpos[:, model.jnt_qposadr[j]])
            angles = np.unwrap(euler(rot, node.order), axis=0)
        cols.append(np.degrees(angles))
    return np.concatenate(cols, axis=1)


def _fmt(v) -> str:
    return " ".join(f"{float(x):.8f}" for x in v)


def write_model_bvh(path: str | Path, model: mujoco.MjModel, qpos: np.ndarray, fps: float,
                    root: str = "guitar") -> Path:
    """Write the body tree below `root` of a MuJoCo model, posed by (T, nq) joint values at `fps`, as a BVH file."""
    qpos = np.atleast_2d(np.asarray(qpos, dtype=np.float64))
    if qpos.shape[1] != model.nq:
        raise ValueError(f"qpos has {qpos.shape[1]} values per frame, the model {model.nq}")
    nodes = skeleton(model, root)
    values = channels(model, nodes, qpos)
    lines = ["HIERARCHY"]
    depth = []                                  # open nodes, innermost last

    def close_to(parent: int) -> None:
        while depth and depth[-1] != parent:
            depth.pop()
            lines.append("  " * len(depth) + "}")

    fmts = []
    for i, node in enumerate(nodes):
        close_to(node.parent)
        ind = "  " * len(depth)
        lines.append(f"{ind}{'ROOT' if node.parent < 0 else 'JOINT'} {node.name}")
        lines.append(f"{ind}{{")
        lines.append(f"{ind}  OFFSET {_fmt(node.offset)}")
        names = ([f"{a}position" for a in AXES] if node.position else []) + [f"{a}rotation" for a in node.order]
        lines.append(f"{ind}  CHANNELS {len(names)} {' '.join(names)}")
        fmts += ["%.8f"] * (3 if node.position else 0) + ["%.6f"] * 3
        if node.end is not None:
            lines += [f"{ind}  End Site", f"{ind}  {{", f"{ind}    OFFSET {_fmt(node.end)}", f"{ind}  }}"]
        depth.append(i)
    close_to(-1)
    lines += ["MOTION", f"Frames: {len(values)}", f"Frame Time: {1.0 / fps:.8g}"]
    path = Path(path)
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
        np.savetxt(f, values, fmt=fmts, delimiter=" ")
    return path


# ------------------------------------------------------------------------------------------------ hands

def _roles(motions) -> dict:
    """role -> Motion: a "left" hand-model motion frets, a "right" one picks (as `motion.kinematics`)."""
    roles = {}
    for m in motions:
        if m.hand in roles:
            raise ValueError(f"two {m.hand}-hand motions: a BVH holds one motion per hand")
        roles[m.hand] = m
    if not roles or len({m.fps for m in roles.values()}) > 1 or \
            len({m.n_frames for m in roles.values()}) > 1:
        raise ValueError("the motions of a BVH need the same frame rate and number of frames")
    return roles


def write_bvh(path: str | Path, motions, *, mirror: bool = False) -> Path:
    """Write one or two hand motions (a "left" one and / or a "right" one, same fps and length) as a BVH of the
    scene they play in: the guitar with both hands, or one. `mirror`: the left-handed player's scene, where the
    right-hand model frets (as `motion.kinematics` and `EnvConfig(mirror=True)`)."""
    roles = _roles(motions)
    scene = "duet" if len(roles) == 2 else next(iter(roles))
    model = S.build_model(scene, mirror=mirror)
    any_motion = next(iter(roles.values()))
    qpos = np.tile(model.qpos0, (any_motion.n_frames, 1))
    for role, m in roles.items():
        q = np.asarray(m.qpos, dtype=np.float64)
        qpos[:, list(S.hand_index(model, role).qpos)] = H.mirror_qpos(q, side_from=role) if mirror else q
    return write_model_bvh(path, model, qpos, any_motion.fps)


def performance_motions(qpos: np.ndarray, fps: float, *, mirror: bool = False, name: str = "") -> tuple:
    """The (left, right) hand motions of a duet recording's (T, nq) joint values: the fretting role as a "left"
    hand-model motion, the picking role as a "right" one, in the mirrored scene too (their joint values mirrored
    back, so `motion.kinematics` with `mirror=True` reproduces the recording). A value past its joint's range by
    more than `format.RANGE_TOL` (a hard contact can push a joint there) is clipped into the range."""
    model = S.build_model("duet", mirror=mirror)
    qpos = np.asarray(qpos)
    if qpos.ndim != 2 or qpos.shape[1] != model.nq:
        raise ValueError(f"a duet recording has {model.nq} joint values per frame, got shape {qpos.shape}")
    out = []
    for role in S.ROLES:
        q = qpos[:, list(S.hand_index(model, role).qpos)]
        if mirror:
            q = H.mirror_qpos(q, side_from="right" if role == "left" else "left")
        motion = Motion(role, fps, q, f"{name} ({role} hand)" if name else f"{role} hand")
        try:
            validate(motion, tol=RANGE_TOL)
        except MotionError:
            motion = motion.replace(qpos=clip_to_ranges(q, role)[0])
        out.append(motion)
    return tuple(out)


def export_performance(out_prefix: str | Path, qpos: np.ndarray, fps: float, *, mirror: bool = False,
                       name: str = "") -> dict[str, Path]:
    """Write `<out_prefix>-left.npz`, `<out_prefix>-right.npz` (the hands' motions) and `<out_prefix>.bvh` (both
    hands) of a duet recording's (T, nq) joint values. Returns the paths by kind."""
    out_prefix = Path(out_prefix)
    left, right = performance_motions(qpos, fps, mirror=mirror, name=name)
    files = {}
    for motion in (left, right):
        files[f"motion_{motion.hand}"] = save(motion, out_prefix.with_name(f"{out_prefix.name}-{motion.hand}.npz"))
    files["bvh"] = write_bvh(out_prefix.with_name(out_prefix.name + ".bvh"), (left, right), mirror=mirror)
    return files
