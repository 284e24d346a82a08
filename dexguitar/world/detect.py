"""Press and pick detection: which string is held down at which fret, and which strings the pick crossed.

Pure JAX (jit- and vmap-able, float32-safe, no Python branching on traced values). All inputs are in the guitar
frame (see `dexguitar.world.guitar`). The guitar geometry enters as constants, so a `Guitar` (frozen, hashable)
is meant to be a closure value or a static argument, never a traced one.

- `segment_distance`, `point_segment_distance`: closest points between segments / a point and a segment (from
  `dexguitar.world.geometry`, re-exported here for the press and reward code).
- `string_contacts`, `string_distances`, `pressed_frets`: left-hand presses from finger capsule axes.
- `pick_crossings`: right-hand picks from one control step of pick motion.
"""
from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from dexguitar.world.geometry import LEN2_EPS, dot, safe_div, segment_distance
from dexguitar.world.guitar import GUITAR, PRESS_DISTANCE, Guitar

__all__ = ["Crossings", "NOT_PICKED_T", "fret_at", "pick_crossings", "pressed_frets", "string_contacts",
           "string_distances"]

# A pick within this distance (m) of a string's line counts as on the line (neither side).
_ON_LINE_TOL = 1e-6
# `Crossings.t` where a string was not picked (any value > 1 would do; finite to keep arithmetic NaN-free).
NOT_PICKED_T = 1e9


def _float_dtype(x):
    return jnp.promote_types(jnp.asarray(x).dtype, jnp.float32)


# ----------------------------------------------------------------------------------------------------- presses


def string_contacts(segments, guitar: Guitar = GUITAR):
    """Closest approach of every finger segment axis (S, 2, 3) to every string.

    Returns (dist2 (S, 6), y (S, 6)): squared axis-to-string distance and the guitar-frame y of the closest point
    on the string (clamped to the nut..bridge extent).
    """
    dt = _float_dtype(segments)
    segments = jnp.asarray(segments, dt)
    strings = jnp.asarray(guitar.strings, dt)                      # (6, 2, 3)
    p0 = segments[:, None, 0, :]                                   # (S, 1, 3)
    p1 = segments[:, None, 1, :]
    q0 = strings[None, :, 0, :]                                    # (1, 6, 3)
    q1 = strings[None, :, 1, :]
    dist2, _, t = segment_distance(p0, p1, q0, q1)
    y = q0[..., 1] + t * (q1[..., 1] - q0[..., 1])
    return dist2, y


def fret_at(y, guitar: Guitar = GUITAR):
    """Fret k (int32) whose space holds guitar-frame y (fret_y[k] < y < fret_y[k-1]); 0 beyond the nut or past the
    last fret wire."""
    y = jnp.asarray(y)
    wires = jnp.asarray(guitar.fret_y, _float_dtype(y))           # (n_frets + 1,), decreasing
    k = jnp.sum(wires > y[..., None], axis=-1).astype(jnp.int32)   # wires on the headstock side of y
    return jnp.where(k > guitar.n_frets, 0, k)


def string_distances(segments, guitar: Guitar = GUITAR):
    """(6,) minimum distance (m) from any finger segment axis (S, 2, 3) to each string (gradient-safe sqrt)."""
    dist2, _ = string_contacts(segments, guitar)
    d2 = jnp.min(dist2, axis=0)
    ok = d2 > LEN2_EPS
    return jnp.where(ok, jnp.sqrt(jnp.where(ok, d2, 1.0)), 0.0)


def pressed_frets(segments, guitar: Guitar = GUITAR, threshold: float = PRESS_DISTANCE):
    """(6,) int32 fret pressed on each string (0 = open / not pressed) by finger segments (S, 2, 3).

    String i is pressed at fret k when a segment axis comes within `threshold` of the string and the closest point
    on the string lies in fret space k; over several such segments the highest fret wins.
    """
    dist2, y = string_contacts(segments, guitar)
    k = fret_at(y, guitar)                                         # (S, 6)
    k = jnp.where(dist2 <= threshold * threshold, k, 0)
    return jnp.max(k, axis=0).astype(jnp.int32)


# ------------------------------------------------------------------------------------------------------- picks


class Crossings(NamedTuple):
    """Strings crossed by the pick during one control step (all (6,), index 0 = string 1)."""

    picked: jnp.ndarray      # bool
    t: jnp.ndarray           # crossing parameter in (0, 1] along the path; NOT_PICKED_T where not picked
    direction: jnp.ndarray   # int32: +1 downstroke (toward string 1), -1 upstroke, 0 not picked
    order: jnp.ndarray       # int32: 1-based picking order within the step, 0 where not picked


def pick_crossings(p_prev, p_now, guitar: Guitar = GUITAR, depth: float = 0.0) -> Crossings:
    """Strings the pick point crossed moving p_prev -> p_now (guitar frame, (3,)).

    A string counts when, in the xy plane, the path crosses the string's line between nut and bridge (path
    parameter t in (0, 1]; a start on the line does not count, an end on it does) and the pick's z there is below
    the string height minus `depth`.
    """
    dt = jnp.promote_types(_float_dtype(p_prev), _float_dtype(p_now))
    p_prev = jnp.asarray(p_prev, dt)
    p_now = jnp.asarray(p_now, dt)
    strings = np.asarray(guitar.strings)
    a = jnp.asarray(strings[:, 0], dt)                             # (6, 3) nut end
    d = jnp.asarray(strings[:, 1] - strings[:, 0], dt)             # (6, 3) nut -> bridge
    d_len = np.linalg.norm(strings[:, 1, :2] - strings[:, 0, :2], axis=-1)
    # Unit xy normal of each string; it points to +x (the strings run along -y), i.e. toward string 1 unless
    # the guitar is mirrored.
    n = jnp.asarray(np.stack([-(strings[:, 1, 1] - strings[:, 0, 1]), strings[:, 1, 0] - strings[:, 0, 0]], -1)
                    / d_len[:, None], dt)                          # (6, 2)
    side_prev = dot(p_prev[None, :2] - a[:, :2], n)               # signed xy distance to each string's line
    side_now = dot(p_now[None, :2] - a[:, :2], n)
    tol = _ON_LINE_TOL
    crosses = ((side_prev > tol) & (side_now <= tol)) | ((side_prev < -tol) & (side_now >= -tol))
    # If side_now is inside the tolerance band, the crossing may be reached fractionally after t = 1: clip.
    u = jnp.clip(safe_div(side_prev, side_prev - side_now, crosses), 0.0, 1.0)
    x = p_prev[None, :] + u[:, None] * (p_now - p_prev)[None, :]   # (6, 3) pick at the crossing
    v = dot(x[:, :2] - a[:, :2], d[:, :2]) / jnp.asarray(d_len ** 2, dt)
    z_string = a[:, 2] + jnp.clip(v, 0.0, 1.0) * d[:, 2]
    picked = crosses & (u > 0.0) & (v >= 0.0) & (v <= 1.0) & (x[:, 2] < z_string - depth)

    toward_plus_x = side_now > side_prev
    direction = jnp.where(toward_plus_x, 1, -1) * jnp.int32(guitar.sign)
    direction = jnp.where(picked, direction, 0).astype(jnp.int32)
    t = jnp.where(picked, u, jnp.asarray(NOT_PICKED_T, dt))
    # Order by t; exact ties go in stroke order (downstroke: string 6 before 5, upstroke: 1 before 2).
    idx = jnp.arange(t.shape[0])
    t_i, t_j = t[:, None], t[None, :]
    before = (t_j < t_i) | ((t_j == t_i) & (direction[:, None] * (idx[None, :] - idx[:, None]) > 0))
    before = before & picked[None, :]
    order = jnp.where(picked, 1 + jnp.sum(before, axis=1), 0).astype(jnp.int32)
    return Crossings(picked=picked, t=t, direction=direction, order=order)
