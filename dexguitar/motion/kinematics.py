"""Forward kinematics in the guitar frame, the one implementation: motions (joint values) -> key-link states as the
envs observe them, and single poses for the IK planner (`motion.planner`).

The motion-imitation discriminator compares simulated link states (`GuitarEnv.link_states`: (hands, 16, 7) position
+ unit quaternion wxyz with w >= 0, guitar frame, `hands.KEY_LINKS` order) with reference ones, so references must be
computed the same way: MuJoCo C `mj_kinematics` on the very scene model the env uses (`scene.build_model(role,
mirror=...)`), with the motion's joint values written at that hand's qpos addresses, then the same world -> guitar
frame transform (`scene.guitar_pose`, `scene.guitar_quat`).

A motion of the "left" hand model plays the fretting role. `mirror=True` gives the left-handed player's setup (the
env's `EnvConfig(mirror=True)`): the same motion played by the mirror-image hand in the mirrored scene (joint values
through `hands.mirror_qpos`), so the states match that env's observations.
"""
from __future__ import annotations

import functools

import mujoco
import numpy as np

from dexguitar.motion.format import Motion, resample
from dexguitar.world import hands as H
from dexguitar.world import scene as S
from dexguitar.world.geometry import positive_w, quat_conj, quat_mul


class HandKinematics:
    """One hand's forward kinematics in its env scene, in the guitar frame.

    Two uses, one implementation: whole motions (`link_states`, `finger_segments`, `sites`) for reference clips, and
    one pose at a time (`set`, then `site`, `body`, `segments`, `site_jac`) for the IK planner (`motion.planner`).
    The reference code shares instances through `hand_kinematics`; the planner makes its own, since it leaves a pose
    set between calls.
    """

    def __init__(self, role: str, mirror: bool = False):
        self.role, self.mirror = role, mirror
        self.model = S.build_model(role, mirror=mirror)
        self.data = mujoco.MjData(self.model)
        mujoco.mj_resetDataKeyframe(self.model, self.data, 0)
        self.hand = S.hand_index(self.model, role)
        self.qadr = np.asarray(self.hand.qpos)
        self.bodies = np.asarray(self.hand.key_bodies)
        self.g_pos, self.g_rot = S.guitar_pose(self.model)
        self.g_quat_inv = quat_conj(S.guitar_quat(mirror))
        self.home = self.data.qpos[self.qadr].copy()
        # joint ids and qpos addresses coincide (hinges and slides only)
        self.lo = self.model.jnt_range[:, 0][self.qadr].copy()
        self.hi = self.model.jnt_range[:, 1][self.qadr].copy()

    def model_qpos(self, motion: Motion) -> np.ndarray:
        """(T, 27) joint values for this scene's hand model: the motion's, mirrored when the setup is."""
        if motion.hand != self.role:
            raise ValueError(f"a {motion.hand}-hand motion cannot drive the {self.role} role")
        q = np.asarray(motion.qpos, dtype=np.float64)
        return H.mirror_qpos(q, side_from=motion.hand) if self.mirror else q

    def run(self, qpos: np.ndarray):
        """Yield MjData after kinematics of every frame of (T, 27) model joint values (the same object each time)."""
        for q in qpos:
            self.set(q)
            yield self.data

    def to_guitar(self, p: np.ndarray) -> np.ndarray:
        return (p - self.g_pos) @ self.g_rot

    # --- one pose at a time
    def set(self, q: np.ndarray) -> None:
        """Pose the hand at model joint values q (27,)."""
        self.data.qpos[self.qadr] = q
        mujoco.mj_kinematics(self.model, self.data)

    def site(self, sid: int) -> np.ndarray:
        return self.to_guitar(self.data.site_xpos[sid])

    def body(self, bid: int) -> np.ndarray:
        return self.to_guitar(self.data.xpos[bid])

    def segments(self) -> np.ndarray:
        """(12, 2, 3) finger axis segments index..pinky, proximal..distal."""
        return self.to_guitar(S.finger_segments(self.data.xpos, self.data.site_xpos, self.hand))

    def site_jac(self, sid: int) -> np.ndarray:
        """(3, 27) Jacobian of a site's guitar-frame position w.r.t. this hand's joints (after `set`)."""
        mujoco.mj_comPos(self.model, self.data)
        jp = np.zeros((3, self.model.nv))
        mujoco.mj_jacSite(self.model, self.data, jp, None, sid)
        return self.g_rot.T @ jp[:, self.qadr]     # qpos and dof addresses coincide (hinges and slides only)

    # --- whole motions
    def link_states(self, qpos: np.ndarray) -> np.ndarray:
        pos = np.empty((len(qpos), len(self.bodies), 3))
        quat = np.empty((len(qpos), len(self.bodies), 4))
        for t, d in enumerate(self.run(qpos)):
            pos[t] = d.xpos[self.bodies]
            quat[t] = d.xquat[self.bodies]
        quat = positive_w(quat_mul(self.g_quat_inv, quat))
        return np.concatenate([self.to_guitar(pos), quat], axis=-1)

    def finger_segments(self, qpos: np.ndarray) -> np.ndarray:
        out = np.empty((len(qpos), 12, 2, 3))
        for t, _ in enumerate(self.run(qpos)):
            out[t] = self.segments()
        return out

    def sites(self, qpos: np.ndarray, site_ids) -> np.ndarray:
        ids = list(site_ids)
        out = np.empty((len(qpos), len(ids), 3))
        for t, d in enumerate(self.run(qpos)):
            out[t] = d.site_xpos[ids]
        return self.to_guitar(out)


@functools.lru_cache(maxsize=8)
def hand_kinematics(role: str, mirror: bool = False) -> HandKinematics:
    return HandKinematics(role, mirror)


def _kin(motion: Motion, mirror: bool) -> HandKinematics:
    return hand_kinematics(motion.hand, bool(mirror))


def link_states(motion: Motion, *, mirror: bool = False) -> np.ndarray:
    """(T, 16, 7) float64 key-link position + quaternion (wxyz, w >= 0) in the guitar frame, per motion frame,
    exactly as `GuitarEnv.link_states` computes them for the motion's hand role."""
    k = _kin(motion, mirror)
    return k.link_states(k.model_qpos(motion))


def finger_segments(motion: Motion, *, mirror: bool = False) -> np.ndarray:
    """(T, 12, 2, 3) finger axis segments (index..pinky, proximal..distal) in the guitar frame, for press
    detection (`world.detect.pressed_frets`)."""
    k = _kin(motion, mirror)
    return k.finger_segments(k.model_qpos(motion))


def fingertips(motion: Motion, *, mirror: bool = False) -> np.ndarray:
    """(T, 5, 3) thumb, index..pinky fingertip sites in the guitar frame."""
    k = _kin(motion, mirror)
    return k.sites(k.model_qpos(motion), (k.hand.thumb_tip,) + k.hand.tips)


def pick_positions(motion: Motion, *, mirror: bool = False) -> np.ndarray:
    """(T, 3) pick site of a right-hand motion in the guitar frame."""
    if motion.hand != "right":
        raise ValueError("only the right (picking) hand holds the pick")
    k = _kin(motion, mirror)
    return k.sites(k.model_qpos(motion), (k.hand.pick,))[:, 0]


def link_velocities(links: np.ndarray, fps: float) -> np.ndarray:
    """(T, ..., 6) linear and angular velocity of link states (T, ..., 7) by backward differences, as the env's
    `link_features` computes them from consecutive control steps (angular: 2 * vec(q_t q_{t-1}^*) * fps, a
    small-angle rate); frame 0 gets zero velocity, as after a reset."""
    prev = np.concatenate([links[:1], links[:-1]], axis=0)
    vel = (links[..., :3] - prev[..., :3]) * fps
    dq = positive_w(quat_mul(links[..., 3:], quat_conj(prev[..., 3:])))
    return np.concatenate([vel, 2.0 * dq[..., 1:] * fps], axis=-1)


def link_features(links: np.ndarray, fps: float) -> np.ndarray:
    """(T, ..., 13): position, quaternion, linear and angular velocity, the env's per-link feature layout."""
    return np.concatenate([links, link_velocities(links, fps)], axis=-1)


def reference_frames(motion: Motion, fps: float = S.CONTROL_HZ, *, mirror: bool = False,
                     velocities: bool = False) -> np.ndarray:
    """The motion resampled to the control rate and turned into link states: (T_fps, 16, 7) float32, or
    (T_fps, 16, 13) with finite-difference velocities. The learner samples 3-frame windows of consecutive rows."""
    links = link_states(resample(motion, fps), mirror=mirror)
    if velocities:
        links = link_features(links, fps)
    return links.astype(np.float32)
