"""Whole motions (joint values per frame) as the envs observe them: key-link states, finger segments, fingertips
and the pick, in the guitar frame, by the one forward kinematics (`world.kinematics.HandKinematics`).

The motion-imitation discriminator compares simulated link states (`GuitarEnv.link_states`: (hands, 16, 7) position
+ unit quaternion wxyz with w >= 0, guitar frame, `hands.KEY_LINKS` order) with reference ones, so references are
computed on the very scene model the env uses, with the motion's joint values written at that hand's qpos addresses.

A motion of the "left" hand model plays the fretting role. `mirror=True` gives the left-handed player's setup (the
env's `EnvConfig(mirror=True)`): the same motion played by the mirror-image hand in the mirrored scene (joint values
through `hands.mirror_qpos`), so the states match that env's observations.
"""
from __future__ import annotations

import numpy as np

from dexguitar.motion.format import Motion, resample
from dexguitar.world import scene as S
from dexguitar.world.geometry import positive_w, quat_conj, quat_mul
from dexguitar.world.kinematics import HandKinematics, hand_kinematics


def _kin(motion: Motion, mirror: bool) -> HandKinematics:
    return hand_kinematics(motion.hand, bool(mirror))


def link_states(motion: Motion, *, mirror: bool = False) -> np.ndarray:
    """(T, 16, 7) float64 key-link position + quaternion (wxyz, w >= 0) in the guitar frame, per motion frame,
    exactly as `GuitarEnv.link_states` computes them for the motion's hand role."""
    k = _kin(motion, mirror)
    return k.link_states(k.model_qpos(motion.hand, motion.qpos))


def finger_segments(motion: Motion, *, mirror: bool = False) -> np.ndarray:
    """(T, 12, 2, 3) finger axis segments (index..pinky, proximal..distal) in the guitar frame, for press
    detection (`world.detect.pressed_frets`)."""
    k = _kin(motion, mirror)
    return k.finger_segments(k.model_qpos(motion.hand, motion.qpos))


def fingertips(motion: Motion, *, mirror: bool = False) -> np.ndarray:
    """(T, 5, 3) thumb, index..pinky fingertip sites in the guitar frame."""
    k = _kin(motion, mirror)
    return k.sites(k.model_qpos(motion.hand, motion.qpos), (k.hand.thumb_tip,) + k.hand.tips)


def pick_positions(motion: Motion, *, mirror: bool = False) -> np.ndarray:
    """(T, 3) pick site of a right-hand motion in the guitar frame."""
    if motion.hand != "right":
        raise ValueError("only the right (picking) hand holds the pick")
    k = _kin(motion, mirror)
    return k.sites(k.model_qpos(motion.hand, motion.qpos), (k.hand.pick,))[:, 0]


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
