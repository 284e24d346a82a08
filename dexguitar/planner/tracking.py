"""What both hands' planners share: a song window as numpy (`Notes`), minimum-jerk timing, bounded least squares
solved to convergence (`converge`), and the `Tracker` that turns a desired joint trajectory into the env's PD
targets.

The hands are slow PD systems (kp = 10; the 0.2 kg wrist rings for ~0.5 s), so a desired trajectory is not an action:
the tracker finds, step by step, the PD targets whose simulated next state is the desired one (a one-step inverse
model by finite differences with `mujoco.rollout` on the env's model), which gives an open-loop action sequence.
"""
from __future__ import annotations

import copy
import dataclasses

import mujoco
import numpy as np
from mujoco import rollout

from dexguitar.world import scene as S
from dexguitar.world.geometry import point_segment_distance
from dexguitar.world.kinematics import HandKinematics


DT = 1.0 / S.CONTROL_HZ


# ------------------------------------------------------------------------------------------------- notes

@dataclasses.dataclass(frozen=True)
class Notes:
    """A song window as numpy: left goal (n, 6), pick targets (n, 6), onsets (n + 1,) in control steps."""

    left: np.ndarray
    pick: np.ndarray
    onset: np.ndarray

    @property
    def n(self) -> int:
        return len(self.left)

    @property
    def frames(self) -> int:
        return int(self.onset[-1])

    @classmethod
    def from_window(cls, window) -> "Notes":
        n = int(np.asarray(window.n))
        dur = np.asarray(window.dur)[:n].astype(int)
        return cls(np.asarray(window.left)[:n].astype(int), np.asarray(window.pick)[:n].astype(bool),
                   np.concatenate([[0], np.cumsum(dur)]))


def min_jerk(s):
    s = np.clip(s, 0.0, 1.0)
    return s ** 3 * (10 - 15 * s + 6 * s ** 2)


# ------------------------------------------------------------------------------------------------- tracking

class Tracker:
    """PD targets that make MuJoCo follow a desired joint trajectory.

    Each control step holds one PD target for `SUBSTEPS` physics steps. The step's effect on (qpos, qvel) is close to
    affine in the target, so one batched rollout (nominal + one perturbation per actuator) gives the local inverse
    model; the target minimises |q - q_des| + w_v |v - v_des| at the end of the step (slides weighted x10: 1 cm ~
    0.1 rad), regularised toward the desired pose. The perturbed rollouts run without contacts: across a contact
    onset finite differences are meaningless and once made the tracker kick the wrist by 0.4 m; the contact-free
    model is a smooth approximate Jacobian, and the nominal rollout (with contacts) keeps the prediction exact.
    Closing the loop in simulation makes the plan exact for MuJoCo C; MJX replays it open-loop and the PD absorbs the
    small differences.
    """

    def __init__(self, scene: str, w_v: float = 0.03, reg: float = 1e-4, eps: float = 1e-3):
        self.model = S.build_model(scene)
        self.data = mujoco.MjData(self.model)
        self.threads = [mujoco.MjData(self.model)]
        m = self.model
        self.free = _without_contacts(m)
        lo, hi = m.actuator_ctrlrange.T
        self.home = m.key_qpos[0].copy()
        half = (hi - lo) / 2
        self.half = half
        # `GuitarEnv.action_to_ctrl`: ctrl = clip(home + clip(a, -1, 1) * half, lo, hi)
        self.u_lo, self.u_hi = np.maximum(lo, self.home - half), np.minimum(hi, self.home + half)
        self.scale = np.ones(m.nv)
        for j in range(m.njnt):
            if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE:
                self.scale[m.jnt_dofadr[j]] = 10.0
        self.w_v, self.reg, self.eps = w_v, reg, eps
        assert m.nq == m.nv == m.nu, "hinges and slides only, one actuator per joint"
        assert all(m.actuator_trnid[i, 0] == i for i in range(m.nu)), "actuator i drives joint i"

    def track(self, q_des: np.ndarray, start: bool = False):
        """q_des (T + 1, nq) with q_des[0] the start pose: the home keyframe, or q_des[0] at rest with `start`.
        Returns ctrl (T, nu), q (T + 1, nq)."""
        m, d = self.model, self.data
        mujoco.mj_resetDataKeyframe(m, d, 0)
        if start:
            d.qpos[:] = q_des[0]
        mujoco.mj_forward(m, d)
        T, nu, nq = len(q_des) - 1, m.nu, m.nq
        v_des = np.gradient(q_des, DT, axis=0)
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        state = np.empty(mujoco.mj_stateSize(m, spec))
        pert = np.vstack([np.zeros((2, nu)), self.eps * np.eye(nu)])
        models = [m] + [self.free] * (nu + 1)
        w = np.concatenate([self.scale, self.w_v * self.scale])
        ctrl = np.empty((T, nu))
        qs = np.empty((T + 1, nq))
        qs[0] = d.qpos
        for t in range(T):
            mujoco.mj_getState(m, d, state, spec)
            u0 = np.clip(q_des[t + 1], self.u_lo, self.u_hi)
            sign = np.where(u0 + self.eps > self.u_hi, -1.0, 1.0)       # stay inside ctrlrange (MuJoCo clamps)
            controls = np.repeat((u0 + pert * sign)[:, None, :], S.SUBSTEPS, axis=1)
            out, _ = rollout.rollout(models, self.threads, state[None], controls,
                                     initial_warmstart=d.qacc_warmstart[None].copy())
            x = out[:, -1, 1:1 + nq + m.nv]                    # FULLPHYSICS: time, qpos, qvel, ...
            B = (x[2:] - x[1]).T / (self.eps * sign)           # (2 nv, nu), contact-free
            err = np.concatenate([q_des[t + 1], v_des[t + 1]]) - x[0]
            Bw, ew = B * w[:, None], err * w
            du = np.linalg.solve(Bw.T @ Bw + self.reg * np.eye(nu), Bw.T @ ew)
            u = np.clip(u0 + du, self.u_lo, self.u_hi)
            d.ctrl[:] = u
            for _ in range(S.SUBSTEPS):
                mujoco.mj_step(m, d)
            ctrl[t] = u
            qs[t + 1] = d.qpos
        return ctrl, qs

    def to_action(self, ctrl):
        """The env action whose PD targets are `ctrl` (inverse of `GuitarEnv.action_to_ctrl` inside its reach)."""
        return (ctrl - self.home) / self.half


def _without_contacts(model: mujoco.MjModel) -> mujoco.MjModel:
    free = copy.copy(model)
    free.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    return free


# ------------------------------------------------------------------------------------------------- clearance

def clearance(a0, a1, b0, b1, n=9):
    """Approximate closest distance between segments a0->a1 and b0->b1: the nearest of n points along the first.
    Enough for a soft clearance term, and what the shipped clips were planned with (the exact
    `geometry.segment_distance` would re-plan them)."""
    t = np.linspace(0, 1, n)[:, None]
    d2, _ = point_segment_distance(a0[None] + t * (a1 - a0)[None], b0[None], b1[None])
    return np.sqrt(d2.min())


# ------------------------------------------------------------------------------------------------- least squares

def converge(residual, x0, lo, hi, jac=None, iters: int = 1000, tol: float = 1e-10, h: float = 1e-6) -> np.ndarray:
    """argmin |residual(x)|^2 over lo <= x <= hi, run until no step lowers it: Levenberg-Marquardt, a variable
    that a step would take out of its bounds held at the bound. jac(x): the Jacobian (default: central differences).

    The hand's IK problems are ill-conditioned (posture terms of weight 0.01-0.02 beside targets of weight 10-30). A
    solver stopped by a relative cost tolerance (`scipy.optimize.least_squares`'s ftol) halts somewhere along the
    flat valley, and where is decided by rounding: the BLAS kernels of two CPUs put a hand position 0.03 rad apart
    and the barre hand 0.2 rad, and a barre trial holds on one and not on the other. Run to convergence, a solve
    gives the valley's minimum, the same to ~1e-8 whatever the rounding (`tests/test_plan_robustness.py`)."""
    if jac is None:
        eye = h * np.eye(len(x0))
        jac = lambda x: np.stack([residual(x + e) - residual(x - e) for e in eye], axis=1) / (2 * h)  # noqa: E731
    x = np.clip(np.asarray(x0, float), lo, hi)
    r = residual(x)
    cost, mu = r @ r, 1e-3
    for _ in range(iters):
        J = jac(x)
        g, A = J.T @ r, J.T @ J
        scale = np.diag(A) + 1e-12
        held = ((x <= lo) & (g > 0)) | ((x >= hi) & (g < 0))        # pressed against a bound
        step = None
        while step is None and mu < 1e12:
            dx, fixed = np.zeros_like(x), held.copy()
            for _ in range(len(x)):                                  # hold those a step would take beyond a bound
                free = ~fixed
                rhs = g[free] + A[np.ix_(free, fixed)] @ dx[fixed]
                dx[free] = np.linalg.solve(A[np.ix_(free, free)] + mu * np.diag(scale[free]), -rhs)
                over = free & ((x + dx < lo) | (x + dx > hi))
                if not over.any():
                    break
                dx[over] = np.clip(x + dx, lo, hi)[over] - x[over]
                fixed |= over
            xn = np.clip(x + dx, lo, hi)
            rn = residual(xn)
            if rn @ rn < cost:
                step = np.abs(xn - x).max()
                x, r, cost, mu = xn, rn, rn @ rn, max(mu / 3, 1e-9)
            else:
                mu *= 4
        if step is None or step < tol:
            break
    return x


def body_jac(k: HandKinematics, bid: int) -> np.ndarray:
    """(3, 27) Jacobian of a body origin's guitar-frame position w.r.t. the hand's joints (after `k.set`), as
    `HandKinematics.site_jac` is for a site."""
    mujoco.mj_comPos(k.model, k.data)
    jp = np.zeros((3, k.model.nv))
    mujoco.mj_jacBody(k.model, k.data, jp, None, bid)
    return k.g_rot.T @ jp[:, k.qadr]


# ------------------------------------------------------------------------------------------------- right hand

# The right planner's version number, written into exported residual policies (`policy.json`'s "right_feedforward")
# so that older releases, which kept several planners, play them on this one; the only one `learn.policy` reads.
