"""Forward kinematics of one hand in its env scene, in the guitar frame: MuJoCo C `mj_kinematics` on the very model
the env uses (`scene.build_model(role, mirror=...)`), then the env's world -> guitar frame transform
(`scene.guitar_pose`, `scene.guitar_quat`), so that poses computed here are the poses the env observes. The IK planner
(`dexguitar.planner`) poses one hand at a time; `motion.kinematics` turns whole motions into reference link states.
"""
from __future__ import annotations

import functools

import mujoco
import numpy as np

from dexguitar.world import hands as H
from dexguitar.world import scene as S
from dexguitar.world.geometry import positive_w, quat_conj, quat_mul


class HandKinematics:
    """One hand's forward kinematics in its env scene, in the guitar frame.

    Two uses, one implementation: whole motions (`link_states`, `finger_segments`, `sites`) for reference clips, and
    one pose at a time (`set`, then `site`, `body`, `segments`, `site_jac`) for the IK planner (`dexguitar.planner`).
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

    def model_qpos(self, hand: str, qpos: np.ndarray) -> np.ndarray:
        """(T, 27) joint values of a `hand` model for this scene's hand model: mirrored when the setup is."""
        if hand != self.role:
            raise ValueError(f"a {hand}-hand motion cannot drive the {self.role} role")
        q = np.asarray(qpos, dtype=np.float64)
        return H.mirror_qpos(q, side_from=hand) if self.mirror else q

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
