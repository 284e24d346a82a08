"""Quaternions and segment distances: the one home of the small geometry that the envs, detection, the learner and
the NumPy motion code all use.

Every function works on NumPy and on JAX inputs and answers in kind: if any input is a `jax.Array` (tracers
included, so under `jit`, `vmap` and `grad`) it computes with `jax.numpy`, otherwise with NumPy (float64 stays
float64, and the NumPy planner never turns into JAX). No Python branching on values, so the JAX path is jit- and
vmap-able.

Quaternions are w-first (w, x, y, z), as MuJoCo stores them.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

# A segment shorter than sqrt(LEN2_EPS) (1 um) is treated as a point.
LEN2_EPS = 1e-12
# Segments whose directions have sin^2(angle) below this are treated as parallel (float32 cancellation margin).
_PARALLEL_EPS = 1e-6


def array_module(*xs):
    """`jax.numpy` if any of xs is a JAX array or tracer, else `numpy`."""
    return jnp if any(isinstance(x, jax.Array) for x in xs) else np


# ---------------------------------------------------------------------------------------------------- quaternions

def quat_mul(a, b):
    """Hamilton product a b of quaternions (..., 4)."""
    xp = array_module(a, b)
    w1, x1, y1, z1 = xp.moveaxis(a, -1, 0)
    w2, x2, y2, z2 = xp.moveaxis(b, -1, 0)
    return xp.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2], axis=-1)


def quat_conj(q):
    """Conjugate (the inverse of a unit quaternion)."""
    xp = array_module(q)
    return q * xp.array([1.0, -1.0, -1.0, -1.0])


def positive_w(q):
    """The sign of q with w >= 0: q and -q are the same rotation, and observations must pick one."""
    xp = array_module(q)
    return xp.where(q[..., :1] < 0, -q, q)


def quat_to_mat(q):
    """(..., 3, 3) rotation matrix of unit quaternions (..., 4): R v rotates v by q."""
    xp = array_module(q)
    w, x, y, z = xp.moveaxis(q, -1, 0)
    return xp.stack([xp.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
                     xp.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
                     xp.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], -2)


# ---------------------------------------------------------------------------------------------------- segments

def dot(a, b):
    """Dot product over the last axis."""
    return array_module(a, b).sum(a * b, axis=-1)


def safe_div(num, den, ok, fallback=0.0):
    """num / den where `ok`, else `fallback`; the double `where` keeps gradients finite where not ok."""
    xp = array_module(num, den, ok)
    return xp.where(ok, num / xp.where(ok, den, 1.0), fallback)


def point_segment_distance(p, a, b):
    """Squared distance from points p to segments a->b (..., 3), broadcasting, and the closest point's parameter
    t in [0, 1] (the closest point is a + t (b - a)). A zero-length segment is its point a."""
    xp = array_module(p, a, b)
    ab = b - a
    l2 = dot(ab, ab)
    t = xp.clip(safe_div(dot(p - a, ab), l2, l2 > LEN2_EPS), 0.0, 1.0)
    diff = p - (a + t[..., None] * ab)          # p minus its foot (this rounding order planned the shipped clips)
    return dot(diff, diff), t


def segment_distance(p0, p1, q0, q1):
    """Squared closest distance between segments p0->p1 and q0->q1 (..., 3), broadcasting over leading dims.

    Returns (dist2, s, t): the closest points are p0 + s (p1 - p0) and q0 + t (q1 - q0), s, t in [0, 1].
    Parallel and zero-length segments give a valid (not necessarily unique) closest pair, no NaN (also in
    gradients).
    """
    xp = array_module(p0, p1, q0, q1)
    d1 = p1 - p0
    d2 = q1 - q0
    r = p0 - q0
    a = dot(d1, d1)
    e = dot(d2, d2)
    b = dot(d1, d2)
    c = dot(d1, r)
    f = dot(d2, r)
    a_ok = a > LEN2_EPS
    e_ok = e > LEN2_EPS
    denom = a * e - b * b
    general = a_ok & e_ok & (denom > _PARALLEL_EPS * a * e)
    # s minimising the distance to q's infinite line (general case), or to the point q0 (q degenerate);
    # parallel: s = 0, then t and s are fixed up below.
    s_line = xp.clip(safe_div(b * f - c * e, denom, general), 0.0, 1.0)
    s_point = xp.clip(safe_div(-c, a, a_ok), 0.0, 1.0)
    s = xp.where(general, s_line, xp.where(e_ok, 0.0, s_point))
    t = safe_div(b * s + f, e, e_ok)
    # t outside [0, 1]: clamp it and take the s closest to that end point of q.
    s_at_q0 = s_point
    s_at_q1 = xp.clip(safe_div(b - c, a, a_ok), 0.0, 1.0)
    s = xp.where(t < 0.0, s_at_q0, xp.where(t > 1.0, s_at_q1, s))
    t = xp.clip(t, 0.0, 1.0)
    diff = r + s[..., None] * d1 - t[..., None] * d2
    return dot(diff, diff), s, t
