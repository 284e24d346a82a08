"""Quaternions and segment distances (dexguitar.world.geometry) on both array modules: NumPy in gives NumPy float64
out, JAX in gives JAX out (here under jit, in float32). Expected values are worked out by hand."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from dexguitar.world.geometry import (
    point_segment_distance,
    positive_w,
    quat_conj,
    quat_mul,
    quat_to_mat,
    segment_distance,
)

BACKENDS = ["numpy", "jax"]
R = np.sqrt(0.5)
Z90 = (R, 0.0, 0.0, R)            # 90 degrees about z: cos 45, sin 45 * (0, 0, 1)


def run(fn, backend, *args):
    """fn on args as float64 NumPy or (jitted) float32 JAX arrays; checks the output kind, returns NumPy."""
    if backend == "numpy":
        out = fn(*(np.asarray(a, np.float64) for a in args))
        for o in out if isinstance(out, tuple) else (out,):
            assert isinstance(o, (np.ndarray, np.floating)) and o.dtype == np.float64
    else:
        out = jax.jit(fn)(*(jnp.asarray(a, jnp.float32) for a in args))
        for o in out if isinstance(out, tuple) else (out,):
            assert isinstance(o, jax.Array)
    return tuple(np.asarray(o) for o in out) if isinstance(out, tuple) else np.asarray(out)


def tol(backend):
    return 1e-12 if backend == "numpy" else 1e-6


# ------------------------------------------------------------------------------------------------ quaternions

@pytest.mark.parametrize("backend", BACKENDS)
def test_quarter_turn_about_z(backend):
    # R = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]: x -> y, y -> -x, z fixed.
    m = run(quat_to_mat, backend, Z90)
    np.testing.assert_allclose(m, [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=tol(backend))
    np.testing.assert_allclose(m @ [1, 0, 0], [0, 1, 0], atol=tol(backend))
    # q v q* with v = (0, 1, 0, 0) (pure quaternion of x) gives y
    rotate = lambda q, v: quat_mul(quat_mul(q, v), quat_conj(q))  # noqa: E731
    np.testing.assert_allclose(run(rotate, backend, Z90, (0, 1, 0, 0)), [0, 0, 1, 0], atol=tol(backend))
    # two quarter turns: a half turn (0, 0, 0, 1)
    np.testing.assert_allclose(run(quat_mul, backend, Z90, Z90), [0, 0, 0, 1], atol=tol(backend))


@pytest.mark.parametrize("backend", BACKENDS)
def test_hamilton_product_conj_and_sign(backend):
    i, j, k = (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1)
    np.testing.assert_array_equal(run(quat_mul, backend, i, j), k)                       # ij = k
    np.testing.assert_array_equal(run(quat_mul, backend, j, i), np.negative(k))          # ji = -k
    np.testing.assert_array_equal(run(quat_mul, backend, [i, j], [j, k]), [k, i])       # batched: jk = i
    np.testing.assert_array_equal(run(quat_conj, backend, (1, 2, 3, 4)), [1, -2, -3, -4])
    np.testing.assert_array_equal(run(positive_w, backend, [(-0.5, 0.5, 0.5, 0.5), (0.5, -0.5, 0.5, 0.5)]),
                                  [(0.5, -0.5, -0.5, -0.5), (0.5, -0.5, 0.5, 0.5)])


def random_quats(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def test_numpy_and_jax_agree_on_random_quaternions():
    rng = np.random.default_rng(0)
    a, b, v = random_quats(rng, 64), random_quats(rng, 64), rng.normal(size=(64, 3))
    for fn, args in ((quat_mul, (a, b)), (quat_conj, (a,)), (positive_w, (a,)), (quat_to_mat, (a,))):
        np.testing.assert_allclose(run(fn, "jax", *args), run(fn, "numpy", *args), atol=1e-6)
    # the matrix rotates as q v q* does
    pure = np.concatenate([np.zeros((64, 1)), v], axis=-1)
    by_quat = quat_mul(quat_mul(a, pure), quat_conj(a))[:, 1:]
    np.testing.assert_allclose(np.einsum("nij,nj->ni", quat_to_mat(a), v), by_quat, atol=1e-12)
    # vmap over single quaternions equals the batched call
    np.testing.assert_allclose(jax.vmap(quat_mul)(jnp.asarray(a), jnp.asarray(b)),
                               quat_mul(jnp.asarray(a), jnp.asarray(b)), atol=1e-7)


def test_mixed_inputs_compute_in_jax():
    assert isinstance(quat_mul(np.asarray(Z90), jnp.asarray(Z90)), jax.Array)
    assert isinstance(point_segment_distance(np.zeros(3), jnp.zeros(3), np.ones(3))[0], jax.Array)


# ------------------------------------------------------------------------------------------ segment distance

@pytest.mark.parametrize("backend", BACKENDS)
def test_point_segment_distance(backend):
    # 3 above the middle of (0,0,0)->(2,0,0): foot (1,0,0) at t = 0.5, dist2 = 9.
    np.testing.assert_allclose(run(point_segment_distance, backend, (1, 0, 3), (0, 0, 0), (2, 0, 0)), [9.0, 0.5],
                               atol=tol(backend))
    # (0.5,1,0) to (0,0,0)->(1,0,0): foot (0.5,0,0), dist2 1.
    np.testing.assert_allclose(run(point_segment_distance, backend, (0.5, 1, 0), (0, 0, 0), (1, 0, 0)), [1.0, 0.5],
                               atol=tol(backend))
    # past the end: (1,0,0), dist2 1
    np.testing.assert_allclose(run(point_segment_distance, backend, (2, 0, 0), (0, 0, 0), (1, 0, 0)), [1.0, 1.0],
                               atol=tol(backend))
    # degenerate segment: 9 + 16 = 25
    np.testing.assert_allclose(run(point_segment_distance, backend, (0, 3, 4), (0, 0, 0), (0, 0, 0)), [25.0, 0.0],
                               atol=10 * tol(backend))


@pytest.mark.parametrize("backend", BACKENDS)
def test_skew_segments(backend):
    # p along x (0,0,0)->(2,0,0); q along y at x = 1, z = 3 from y = -1 to 3: closest p(0.5) = (1,0,0),
    # q(0.25) = (1,0,3) -> dist2 = 3^2 = 9.
    d = run(segment_distance, backend, (0, 0, 0), (2, 0, 0), (1, -1, 3), (1, 3, 3))
    np.testing.assert_allclose(d, [9.0, 0.5, 0.25], atol=tol(backend))
    # Same p, q at x = 3, z = 1, y -1..1: the lines' closest point x = 3 is past p's end -> s = 1 at (2,0,0),
    # q(0.5) = (3,0,1) -> dist2 = 1^2 + 1^2 = 2.
    d = run(segment_distance, backend, (0, 0, 0), (2, 0, 0), (3, -1, 1), (3, 1, 1))
    np.testing.assert_allclose(d, [2.0, 1.0, 0.5], atol=tol(backend))
    # Non-orthogonal skew: p (0,0,0)->(1,1,0) in z = 0, q (1,0,1)->(0,1,1) in z = 1; xy projections cross at
    # (0.5, 0.5) -> s = t = 0.5, dist2 = 1.
    d = run(segment_distance, backend, (0, 0, 0), (1, 1, 0), (1, 0, 1), (0, 1, 1))
    np.testing.assert_allclose(d, [1.0, 0.5, 0.5], atol=tol(backend))


@pytest.mark.parametrize("backend", BACKENDS)
def test_parallel_segments(backend):
    # Overlapping in x over [0.5, 1], 0.2 apart in y -> dist2 = 0.04; any closest pair has p.x = s = q.x = 0.5 + t.
    d2, s, t = run(segment_distance, backend, (0, 0, 0), (1, 0, 0), (0.5, 0.2, 0), (1.5, 0.2, 0))
    np.testing.assert_allclose(d2, 0.04, rtol=1e-5)
    assert 0.5 <= s <= 1.0 and 0.0 <= t <= 0.5
    np.testing.assert_allclose(s, 0.5 + t, atol=tol(backend))
    # Disjoint, q from (2,1,0) to (3,1,0): closest p(1) = (1,0,0), q(0) = (2,1,0) -> dist2 = 1 + 1 = 2.
    d = run(segment_distance, backend, (0, 0, 0), (1, 0, 0), (2, 1, 0), (3, 1, 0))
    np.testing.assert_allclose(d, [2.0, 1.0, 0.0], atol=tol(backend))
    # Anti-parallel, q reversed: the same end point (2,1,0) is now q(1).
    d = run(segment_distance, backend, (0, 0, 0), (1, 0, 0), (3, 1, 0), (2, 1, 0))
    np.testing.assert_allclose(d, [2.0, 1.0, 1.0], atol=tol(backend))


@pytest.mark.parametrize("backend", BACKENDS)
def test_zero_length_and_crossing_segments(backend):
    # p a point (0,0,1) above q (-1,0,0)->(1,0,0): foot at q(0.5) = (0,0,0), dist2 = 1.
    d = run(segment_distance, backend, (0, 0, 1), (0, 0, 1), (-1, 0, 0), (1, 0, 0))
    np.testing.assert_allclose(d, [1.0, 0.0, 0.5], atol=tol(backend))
    # q a point (0.25,0,1) against p (0,0,0)->(1,0,0): foot p(0.25), dist2 = 1.
    d = run(segment_distance, backend, (0, 0, 0), (1, 0, 0), (0.25, 0, 1), (0.25, 0, 1))
    np.testing.assert_allclose(d, [1.0, 0.25, 0.0], atol=tol(backend))
    # Both points: (1,2,3) to (1,0,0) -> dist2 = 0 + 4 + 9 = 13.
    d = run(segment_distance, backend, (1, 2, 3), (1, 2, 3), (1, 0, 0), (1, 0, 0))
    np.testing.assert_allclose(d, [13.0, 0.0, 0.0], atol=10 * tol(backend))
    # x and y axis segments through the origin touch at s = t = 0.5.
    d = run(segment_distance, backend, (-1, 0, 0), (1, 0, 0), (0, -1, 0), (0, 1, 0))
    np.testing.assert_allclose(d, [0.0, 0.5, 0.5], atol=tol(backend))


def test_random_segments_against_sampling_and_each_other():
    """Exact distances never exceed the best of a dense sample of point pairs and come within its spacing; the
    float32 JAX path matches the float64 NumPy one."""
    rng = np.random.default_rng(1)
    p0, p1, q0, q1 = rng.normal(size=(4, 32, 3))
    d2, s, t = run(segment_distance, "numpy", p0, p1, q0, q1)
    u = np.linspace(0, 1, 201)
    a = p0[:, None] + u[None, :, None] * (p1 - p0)[:, None]             # (32, 201, 3)
    b = q0[:, None] + u[None, :, None] * (q1 - q0)[:, None]
    sampled = np.linalg.norm(a[:, :, None] - b[:, None, :], axis=-1).min(axis=(1, 2))
    d = np.sqrt(d2)
    assert np.all(d <= sampled + 1e-12)
    step = (np.linalg.norm(p1 - p0, axis=-1) + np.linalg.norm(q1 - q0, axis=-1)) / 200
    assert np.all(sampled - d <= step)
    closest = p0 + s[:, None] * (p1 - p0) - (q0 + t[:, None] * (q1 - q0))
    np.testing.assert_allclose(np.sum(closest ** 2, -1), d2, atol=1e-12)
    np.testing.assert_allclose(run(segment_distance, "jax", p0, p1, q0, q1)[0], d2, rtol=1e-4, atol=1e-6)
    pd2, pt = run(point_segment_distance, "numpy", p0, q0, q1)
    np.testing.assert_allclose(pd2, run(segment_distance, "numpy", p0, p0, q0, q1)[0], atol=1e-12)
    np.testing.assert_allclose(run(point_segment_distance, "jax", p0, q0, q1), (pd2, pt), rtol=1e-4, atol=1e-6)


@pytest.mark.parametrize("case", [
    ((0, 0, 0), (1, 0, 0), (0.5, 0.2, 0), (1.5, 0.2, 0)),   # parallel
    ((0, 0, 1), (0, 0, 1), (-1, 0, 0), (1, 0, 0)),          # p degenerate
    ((1, 2, 3), (1, 2, 3), (1, 0, 0), (1, 0, 0)),           # both degenerate
    ((-1, 0, 0), (1, 0, 0), (0, -1, 0), (0, 1, 0)),         # crossing at distance 0
    ((0, 0, 0), (0, 0, 0), (0, 0, 0), (0, 0, 0)),           # everything at one point
])
def test_segment_distance_gradients_finite(case):
    args = [jnp.asarray(p, jnp.float32) for p in case]
    grads = jax.jit(jax.grad(lambda *a: segment_distance(*a)[0], argnums=(0, 1, 2, 3)))(*args)
    for g in grads:
        assert np.all(np.isfinite(np.asarray(g)))
