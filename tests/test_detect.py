"""Press / pick detection (dexguitar.world.detect). Expected values are worked out by hand from the geometry.

Geometry used below (dexguitar/world/guitar.py): nut y = 0.2165, scale L = 0.621365, bridge y = 0.2165 - L =
-0.404865, fret wire k at y_k = 0.2165 - L (1 - 2^(-k/12)), strings at z = 0.0123, x of string i at y by linear
interpolation x = x_nut + (0.2165 - y) / L * (x_bridge - x_nut).
"""
import jax
import jax.numpy as jnp
import numpy as np

from dexguitar.world.detect import NOT_PICKED_T, pick_crossings, pressed_frets, string_distances
from dexguitar.world.guitar import GUITAR, Guitar

MIRRORED = Guitar(mirror=True)


def f32(*x):
    return jnp.asarray(x, jnp.float32)


# ---------------------------------------------------------------------------------------------------- presses

# Fret wires (by hand from y_k = 0.2165 - 0.621365 (1 - 2^(-k/12))):
#   k=1: 2^(-1/12) = 0.943874 -> 0.2165 - 0.621365 * 0.056126 = 0.181625
#   k=2: 2^(-2/12) = 0.890899 -> 0.2165 - 0.621365 * 0.109101 = 0.148708
#   k=4: 2^(-4/12) = 0.793701 -> 0.2165 - 0.621365 * 0.206299 = 0.088313
#   k=5: 2^(-5/12) = 0.749154 -> 0.2165 - 0.621365 * 0.250846 = 0.060633
#   k=6: 2^(-6/12) = 0.707107 -> 0.2165 - 0.621365 * 0.292893 = 0.034506
#   k=7: 2^(-7/12) = 0.667420 -> 0.2165 - 0.621365 * 0.332580 = 0.009846
#   k=22: 2^(-22/12) = 0.280616 -> 0.2165 - 0.621365 * 0.719384 = -0.230500
Y_MID_1 = 0.199063   # (0.2165 + 0.181625) / 2
Y_MID_2 = 0.165167   # (0.181625 + 0.148708) / 2
Y_MID_5 = 0.074473   # (0.088313 + 0.060633) / 2
Y_MID_7 = 0.022176   # (0.034506 + 0.009846) / 2
# String x at those y: f = (0.2165 - y) / 0.621365.
#   y = Y_MID_5: f = 0.142027 / 0.621365 = 0.228573
#     string 3: 0.0036 + 0.228573 * (0.00523 - 0.0036) = 0.0036 + 0.000373 = 0.003973
#     string 2: 0.0105 + 0.228573 * (0.01527 - 0.0105) = 0.0105 + 0.001090 = 0.011590
#     string 4: -0.003973
#   y = Y_MID_2: f = 0.051333 / 0.621365 = 0.082613; string 2: 0.0105 + 0.082613 * 0.00477 = 0.010894
#   y = Y_MID_7: f = 0.194324 / 0.621365 = 0.312738; string 2: 0.0105 + 0.312738 * 0.00477 = 0.011992
X3_MID_5 = 0.003973
X2_MID_2 = 0.010894
X2_MID_7 = 0.011992
Z_STRING = 0.0123
Z_PRESS = Z_STRING + 0.003   # axis 3 mm above the strings
HALF = 0.001                 # half-length of a fingertip segment lying along x


def seg_x(x, y, z, half=HALF):
    """A segment along x centred at (x, y, z)."""
    return [[x - half, y, z], [x + half, y, z]]


def seg_y(x, y, z, half):
    return [[x, y + half, z], [x, y - half, z]]


def press(segments, guitar=GUITAR, **kw):
    fn = jax.jit(lambda s: pressed_frets(s, guitar, **kw))
    return np.asarray(fn(jnp.asarray(segments, jnp.float32))).tolist()


def test_fingertip_along_x_presses_string_3_fret_5():
    # Segment x in [0.002973, 0.004973] at y = Y_MID_5, z = 0.0153. The finger axis and string 3 lie in the
    # horizontal planes z = 0.0153 and z = 0.0123 and their xy projections cross -> distance 3 mm < 6 mm, closest
    # point y = Y_MID_5 in (0.060633, 0.088313) = fret 5.
    # Neighbours: string 2 at 0.011590 is 0.011590 - 0.004973 = 0.006617 off in x -> distance
    # sqrt(0.006617^2 + 0.003^2) = sqrt(4.379e-5 + 0.9e-5) = 0.007266 > 0.006; string 4 at -0.003973 is
    # 0.002973 + 0.003973 = 0.006946 off -> sqrt(4.825e-5 + 0.9e-5) = 0.007566 > 0.006.
    segs = [seg_x(X3_MID_5, Y_MID_5, Z_PRESS)]
    assert press(segs) == [0, 0, 5, 0, 0, 0]
    d = np.asarray(jax.jit(string_distances)(jnp.asarray(segs, jnp.float32)))
    np.testing.assert_allclose(d[2], 0.003, atol=2e-6)
    np.testing.assert_allclose(d[1], 0.007266, atol=2e-5)
    np.testing.assert_allclose(d[3], 0.007566, atol=2e-5)


def test_fingertip_along_y_presses_string_3_fret_5():
    # Along y from Y_MID_5 + 0.01 = 0.084473 to Y_MID_5 - 0.01 = 0.064473 (inside fret 5) at x = 0.003973: it crosses
    # string 3's xy projection at Y_MID_5 -> 3 mm, fret 5. Strings 2 / 4 are >= 7.6 mm away in x over this range
    # (the strings drift < 0.0016 * 0.02 / 0.62 = 5e-5 m in x over 2 cm).
    assert press([seg_y(X3_MID_5, Y_MID_5, Z_PRESS, 0.01)]) == [0, 0, 5, 0, 0, 0]


def test_too_high_presses_nothing():
    # 8 mm above the string: distance 0.008 > 0.006.
    assert press([seg_x(X3_MID_5, Y_MID_5, Z_STRING + 0.008)]) == [0] * 6
    assert press([seg_y(X3_MID_5, Y_MID_5, Z_STRING + 0.008, 0.01)]) == [0] * 6


def test_highest_fret_wins():
    # String 2 at fret 2 (x = 0.010894) and at fret 7 (x = 0.011992); each 3 mm above it. Neighbours at fret 2:
    # string 1 at 0.01765 + 0.082613 * 0.0078 = 0.018294, 0.018294 - 0.011894 = 0.0064 off in x; string 3 at
    # 0.0036 + 0.082613 * 0.00163 = 0.003735, 0.009894 - 0.003735 = 0.00616 off -> both > 6 mm already in x.
    # At fret 7: string 1 at 0.01765 + 0.312738 * 0.0078 = 0.020089 (0.007097 off), string 3 at
    # 0.0036 + 0.312738 * 0.00163 = 0.004110 (0.006882 off).
    segs = [seg_x(X2_MID_2, Y_MID_2, Z_PRESS), seg_x(X2_MID_7, Y_MID_7, Z_PRESS)]
    assert press(segs) == [0, 7, 0, 0, 0, 0]
    assert press(segs[::-1]) == [0, 7, 0, 0, 0, 0]


def test_barre_at_fret_1():
    # Along x from -0.025 to 0.025 (wider than 2 * 0.01765) at y = Y_MID_1 in (0.181625, 0.2165), 3 mm above:
    # every string's projection crosses it -> all at distance 3 mm, fret 1.
    assert press([seg_x(0.0, Y_MID_1, Z_PRESS, half=0.025)]) == [1] * 6


def test_twelve_segments():
    # A hand's 12 segments: 11 far above the strings (z = 0.06, > 4.7 cm away), one pressing string 3 at fret 5.
    far = [seg_x(0.0, 0.1 - 0.01 * i, 0.06) for i in range(11)]
    segs = far[:5] + [seg_x(X3_MID_5, Y_MID_5, Z_PRESS)] + far[5:]
    assert press(segs) == [0, 0, 5, 0, 0, 0]


def test_beyond_nut_and_past_last_fret():
    # 2 mm beyond the nut (y = 0.2185): the closest point on string 3 is its nut end, distance
    # sqrt(0.002^2 + 0.003^2) = 0.0036 < 0.006, but it is not in a fret space -> 0.
    x3_nut = 0.0036
    assert press([seg_x(x3_nut, 0.2165 + 0.002, Z_PRESS)]) == [0] * 6
    # Between fret wire 22 (-0.230500) and the end of the fretboard (-0.2418): y = -0.236, over string 3 at
    # x = 0.0036 + (0.2165 + 0.236) / 0.621365 * 0.00163 = 0.0036 + 0.728236 * 0.00163 = 0.004787 -> 0.
    assert press([seg_x(0.004787, -0.236, Z_PRESS)]) == [0] * 6
    # Just inside fret 22: y = -0.229 -> x = 0.0036 + 0.716 * 0.00163 ~ 0.004767 -> 22.
    assert press([seg_x(0.004767, -0.229, Z_PRESS)]) == [0, 0, 22, 0, 0, 0]


def test_threshold_argument():
    # 5 mm above: pressed with the default 6 mm, not with 4 mm.
    segs = [seg_x(X3_MID_5, Y_MID_5, Z_STRING + 0.005)]
    assert press(segs) == [0, 0, 5, 0, 0, 0]
    assert press(segs, threshold=0.004) == [0] * 6


def test_mirrored_guitar():
    # The x-mirrored segment (centred at x = -0.003973) presses string 3 at fret 5 on the mirrored guitar; on the
    # normal guitar -0.003973 is string 4's x at Y_MID_5, so there it presses string 4.
    segs = [seg_x(-X3_MID_5, Y_MID_5, Z_PRESS)]
    assert press(segs, MIRRORED) == [0, 0, 5, 0, 0, 0]
    assert press(segs, GUITAR) == [0, 0, 0, 5, 0, 0]
    segs = [seg_x(0.0, Y_MID_1, Z_PRESS, half=0.025)]
    assert press(segs, MIRRORED) == [1] * 6


def test_press_vmap_and_static_guitar():
    batch = jnp.asarray([
        [seg_x(X3_MID_5, Y_MID_5, Z_PRESS), seg_x(0.0, 0.0, 0.06)],
        [seg_x(X2_MID_2, Y_MID_2, Z_PRESS), seg_x(X2_MID_7, Y_MID_7, Z_PRESS)],
        [seg_x(0.0, Y_MID_1, Z_PRESS, half=0.025), seg_x(0.0, 0.0, 0.06)],
        [seg_x(X3_MID_5, Y_MID_5, Z_STRING + 0.008), seg_x(0.0, 0.0, 0.06)],
    ], jnp.float32)
    fn = jax.jit(jax.vmap(pressed_frets, in_axes=(0, None)), static_argnums=1)
    out = np.asarray(fn(batch, GUITAR))
    assert out.dtype == np.int32
    assert out.tolist() == [[0, 0, 5, 0, 0, 0], [0, 7, 0, 0, 0, 0], [1] * 6, [0] * 6]
    d = np.asarray(jax.jit(jax.vmap(string_distances))(batch))
    assert d.shape == (4, 6) and np.all(np.isfinite(d))


def test_string_distances_gradient():
    segs = jnp.asarray([seg_x(X3_MID_5, Y_MID_5, Z_PRESS)], jnp.float32)
    g = jax.grad(lambda s: jnp.sum(string_distances(s)))(segs)
    g = np.asarray(g)
    assert np.all(np.isfinite(g))
    # d(distance to string 3)/dz = +1 in total over both end points; other strings add positive z-gradients too.
    assert g[..., 2].sum() > 0


# ------------------------------------------------------------------------------------------------------ picks

# Picking zone y = -0.33: f = (0.2165 + 0.33) / 0.621365 = 0.5465 / 0.621365 = 0.879515
#   string 6: -0.01765 - 0.879515 * 0.0078  = -0.01765 - 0.006860 = -0.024510
#   string 5: -0.0105  - 0.879515 * 0.00477 = -0.0105  - 0.004195 = -0.014695
#   string 4: -0.0036  - 0.879515 * 0.00163 = -0.0036  - 0.001434 = -0.005034
#   string 3: +0.005034
Y_PICK = -0.33
X6, X5, X4 = -0.024510, -0.014695, -0.005034
X_START = X6 - 0.005          # -0.029510
X_END = X4 + 0.003            # -0.002034
Z_BELOW = 0.0093              # 3 mm below the strings
# Crossing parameters along the sweep (length 0.027476): string 6 at 0.005 / 0.027476 = 0.18198,
# string 5 at (0.029510 - 0.014695) / 0.027476 = 0.53920, string 4 at 0.024476 / 0.027476 = 0.89082.


def pick(p_prev, p_now, guitar=GUITAR, depth=0.0):
    fn = jax.jit(pick_crossings, static_argnums=2)
    c = fn(jnp.asarray(p_prev, jnp.float32), jnp.asarray(p_now, jnp.float32), guitar, depth)
    return [np.asarray(v) for v in c]


def test_downstroke_sweep():
    picked, t, direction, order = pick([X_START, Y_PICK, Z_BELOW], [X_END, Y_PICK, Z_BELOW])
    assert picked.tolist() == [False, False, False, True, True, True]
    assert direction.tolist() == [0, 0, 0, 1, 1, 1]
    assert order.tolist() == [0, 0, 0, 3, 2, 1]
    np.testing.assert_allclose(t[3:], [0.89082, 0.53920, 0.18198], atol=2e-4)
    assert np.all(t[:3] == NOT_PICKED_T)
    assert direction.dtype == np.int32 and order.dtype == np.int32 and picked.dtype == bool


def test_upstroke_sweep():
    picked, t, direction, order = pick([X_END, Y_PICK, Z_BELOW], [X_START, Y_PICK, Z_BELOW])
    assert picked.tolist() == [False, False, False, True, True, True]
    assert direction.tolist() == [0, 0, 0, -1, -1, -1]
    assert order.tolist() == [0, 0, 0, 1, 2, 3]
    # Reversed path: t -> 1 - t.
    np.testing.assert_allclose(t[3:], [1 - 0.89082, 1 - 0.53920, 1 - 0.18198], atol=2e-4)


def test_above_strings_picks_nothing():
    picked, t, direction, order = pick([X_START, Y_PICK, 0.02], [X_END, Y_PICK, 0.02])
    assert not picked.any() and not direction.any() and not order.any()


def test_depth():
    # depth 1 mm: the pick must be below 0.0123 - 0.001 = 0.0113.
    picked = pick([X_START, Y_PICK, 0.0118], [X_END, Y_PICK, 0.0118], depth=0.001)[0]   # 0.5 mm below: no
    assert not picked.any()
    picked = pick([X_START, Y_PICK, 0.0108], [X_END, Y_PICK, 0.0108], depth=0.001)[0]   # 1.5 mm below: yes
    assert picked.tolist() == [False, False, False, True, True, True]
    # depth 0: 0.5 mm below is enough.
    picked = pick([X_START, Y_PICK, 0.0118], [X_END, Y_PICK, 0.0118])[0]
    assert picked.tolist() == [False, False, False, True, True, True]


def test_z_interpolated_along_path():
    # z goes from 0.0023 at X_START to 0.0223 at X_END (slope 0.02 per path); at string 6 (t = 0.18198) the pick is
    # at 0.0023 + 0.0036 = 0.0059 (below), at string 5 (t = 0.53920) at 0.0131 (above 0.0123), at string 4 higher.
    picked = pick([X_START, Y_PICK, 0.0023], [X_END, Y_PICK, 0.0223])[0]
    assert picked.tolist() == [False, False, False, False, False, True]


def test_stop_before_string():
    # Stop 0.5 mm short of string 4 (x = -0.005534): strings 6, 5 only.
    picked, _, _, order = pick([X_START, Y_PICK, Z_BELOW], [X4 - 0.0005, Y_PICK, Z_BELOW])
    assert picked.tolist() == [False, False, False, False, True, True]
    assert order.tolist() == [0, 0, 0, 0, 2, 1]
    # The next step starting there crosses string 4 only.
    picked, _, _, order = pick([X4 - 0.0005, Y_PICK, Z_BELOW], [X_END, Y_PICK, Z_BELOW])
    assert picked.tolist() == [False, False, False, True, False, False]
    assert order.tolist() == [0, 0, 0, 1, 0, 0]


def test_outside_string_extent():
    # Beyond the bridge (y = -0.42 < -0.404865) and beyond the nut (y = 0.23 > 0.2165): nothing.
    for y in (-0.42, 0.23):
        assert not pick([-0.04, y, Z_BELOW], [0.04, y, Z_BELOW])[0].any()


def test_path_parallel_to_strings():
    # Along string 4's direction (nut -> bridge: dx = -0.00523 + 0.0036 = -0.00163, dy = -0.621365), starting
    # 2 mm toward +x of string 4 at y = -0.30 (x4 = -0.0036 - (0.5165 / 0.621365) * 0.00163 = -0.004955).
    x0 = -0.004955 + 0.002
    p_prev = [x0, -0.30, Z_BELOW]
    p_now = [x0 - 0.1 * 0.00163, -0.30 - 0.1 * 0.621365, Z_BELOW]
    for out in pick(p_prev, p_now):
        assert np.all(np.isfinite(out.astype(np.float64)))
    assert not pick(p_prev, p_now)[0].any()
    # On string 4's line itself (its nut and bridge points, moved below the string): no crossing either.
    picked, t, _, _ = pick([-0.0036, 0.2165, Z_BELOW], [-0.00523, -0.404865, Z_BELOW])
    assert not picked.any() and np.all(np.isfinite(t))
    # Not moving at all.
    picked, t, _, _ = pick([X4, Y_PICK, Z_BELOW], [X4, Y_PICK, Z_BELOW])
    assert not picked.any() and np.all(np.isfinite(t))


def test_mirrored_guitar_pick():
    # Mirrored: the low-E side is +x, so the x-mirrored downward sweep (from -X_START to -X_END) is a downstroke.
    picked, _, direction, order = pick([-X_START, Y_PICK, Z_BELOW], [-X_END, Y_PICK, Z_BELOW], MIRRORED)
    assert picked.tolist() == [False, False, False, True, True, True]
    assert direction.tolist() == [0, 0, 0, 1, 1, 1]
    assert order.tolist() == [0, 0, 0, 3, 2, 1]
    # The unmirrored path on the mirrored guitar goes from x = -0.0295 to -0.0020: strings 1 (at -0.024510),
    # 2 (-0.014695) and 3 (-0.005034), toward the low-E side -> upstroke, 1 first.
    picked, _, direction, order = pick([X_START, Y_PICK, Z_BELOW], [X_END, Y_PICK, Z_BELOW], MIRRORED)
    assert picked.tolist() == [True, True, True, False, False, False]
    assert direction.tolist() == [-1, -1, -1, 0, 0, 0]
    assert order.tolist() == [1, 2, 3, 0, 0, 0]


def test_pick_vmap_batch():
    p_prev = jnp.asarray([
        [X_START, Y_PICK, Z_BELOW],        # downstroke 6, 5, 4
        [X_END, Y_PICK, Z_BELOW],          # upstroke 4, 5, 6
        [X_START, Y_PICK, 0.02],           # above: none
        [X_START, Y_PICK, Z_BELOW],        # stops short of 4: 6, 5
    ], jnp.float32)
    p_now = jnp.asarray([
        [X_END, Y_PICK, Z_BELOW],
        [X_START, Y_PICK, Z_BELOW],
        [X_END, Y_PICK, 0.02],
        [X4 - 0.0005, Y_PICK, Z_BELOW],
    ], jnp.float32)
    fn = jax.jit(jax.vmap(lambda a, b: pick_crossings(a, b, GUITAR, 0.0)))
    c = fn(p_prev, p_now)
    assert c.picked.shape == (4, 6)
    assert np.asarray(c.order).tolist() == [
        [0, 0, 0, 3, 2, 1], [0, 0, 0, 1, 2, 3], [0] * 6, [0, 0, 0, 0, 2, 1]]
    assert np.asarray(c.direction).tolist() == [
        [0, 0, 0, 1, 1, 1], [0, 0, 0, -1, -1, -1], [0] * 6, [0, 0, 0, 0, 1, 1]]
    # depth traced through vmap as well.
    fn2 = jax.jit(jax.vmap(lambda a, b, d: pick_crossings(a, b, GUITAR, d)))
    depth = jnp.asarray([0.0, 0.0, 0.0, 0.004], jnp.float32)   # last: must be below 0.0083, is at 0.0093 -> none
    c2 = fn2(p_prev, p_now, depth)
    assert np.asarray(c2.picked).sum(axis=1).tolist() == [3, 3, 0, 0]
