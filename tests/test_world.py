"""Guitar geometry, hand models and scenes: numbers worked out by hand, models that load and step in MJX."""
import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest
from mujoco import mjx

from dexguitar.world import detect
from dexguitar.world import hands as H
from dexguitar.world import scene as S
from dexguitar.world.guitar import GUITAR, Guitar


def test_fret_positions_follow_equal_temperament():
    y = GUITAR.fret_y
    assert y[0] == pytest.approx(0.2165)                       # the nut
    # fret 12 halves the scale: 0.2165 - 0.621365 / 2
    assert y[12] == pytest.approx(-0.0941825, abs=1e-7)
    # fret 1: 0.621365 * (1 - 2^(-1/12)) = 0.621365 * 0.0561257 = 0.0348746 from the nut
    assert y[1] == pytest.approx(0.2165 - 0.0348746, abs=1e-6)
    # fret 22: 0.621365 * (1 - 2^(-22/12)) = 0.621365 * 0.7193845 = 0.4470003 -> -0.2305003 (the authors: -0.2305)
    assert y[22] == pytest.approx(-0.2305003, abs=1e-6)
    assert len(y) == 23 and np.all(np.diff(y) < 0)


def test_pitches_in_standard_tuning():
    # string 1 open = E4 (MIDI 64), string 6 open = E2 (40); 5th fret of one string = next open string (but G->B: 4th)
    assert [GUITAR.pitch(s, 0) for s in range(1, 7)] == [64, 59, 55, 50, 45, 40]
    assert GUITAR.pitch(6, 5) == GUITAR.pitch(5, 0) == 45
    assert GUITAR.pitch(3, 4) == GUITAR.pitch(2, 0) == 59
    assert GUITAR.frequency(5, 0) == pytest.approx(110.0)        # A2
    assert GUITAR.frequency(1, 12) == pytest.approx(659.255, abs=1e-3)  # E5
    assert GUITAR.pitch_table.shape == (6, 23) and GUITAR.pitch_table[5, 22] == 62
    with pytest.raises(ValueError):
        GUITAR.pitch(7, 0)


def test_target_point_is_mid_fret_on_the_string():
    # Eq. 4: middle of fret 5 = between wires 4 (0.088313) and 5 (0.060633), on string 3 at string height
    p = GUITAR.target_points[2, 5]
    assert p[1] == pytest.approx((0.0883135 + 0.0606330) / 2, abs=1e-5)
    # string 3 runs from x = 0.0036 (nut, y = 0.2165) to 0.00523 (bridge, y = -0.404865): at y = 0.07447
    # x = 0.0036 + (0.2165 - 0.07447) / 0.621365 * 0.00163 = 0.0039726
    assert p[0] == pytest.approx(0.0039726, abs=1e-6)
    assert p[2] == pytest.approx(0.0123)
    mirrored = Guitar(mirror=True)
    np.testing.assert_allclose(mirrored.target_points[..., 0], -GUITAR.target_points[..., 0])
    np.testing.assert_allclose(mirrored.target_points[..., 1:], GUITAR.target_points[..., 1:])


def test_hand_has_27_dofs_and_mirror_ranges():
    left, right = H.joints("left"), H.joints("right")
    assert len(left) == len(right) == 27 and len(H.KEY_LINKS) == 16
    by_name = {j.name: (lj.range, j.range) for lj, j in zip(left, right)}
    assert by_name["thumb1_y"] == ((-1.5708, 0.0), (0.0, 1.5708))       # y hinge: negated
    assert by_name["thumb1_x"] == ((0.0, 0.698132), (0.0, 0.698132))    # x hinge: kept
    assert by_name["pinky1_z"] == ((-0.349066, 0.698132), (-0.698132, 0.349066))


def test_model_files_are_generated_from_the_code():
    for side in ("left", "right"):
        assert (H.MODELS_DIR / f"{side}_hand.xml").read_text() == H.hand_xml(side)
    assert (H.MODELS_DIR / "guitar.xml").read_text() == S.guitar_xml()


@pytest.mark.parametrize("name,ndof", [("left", 27), ("right", 27), ("duet", 54)])
def test_scene_loads_in_mujoco(name, ndof):
    m = S.build_model(name)
    assert m.nq == m.nv == m.nu == ndof
    assert m.opt.timestep == pytest.approx(1 / 240) and np.all(m.opt.gravity == 0)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    for _ in range(240):                                         # one second at the home pose: stays put
        d.ctrl[:] = m.key_qpos[0]
        mujoco.mj_step(m, d)
    assert np.all(np.isfinite(d.qpos)) and np.abs(d.qpos - m.key_qpos[0]).max() < 0.05
    full = S.build_spec(name, visual=True).compile()            # the rendering model has the strings too
    assert full.ngeom > m.ngeom and mujoco.mj_name2id(full, mujoco.mjtObj.mjOBJ_GEOM, "string1") >= 0


def test_only_thumb_and_index_of_the_picking_hand_touch_each_other():
    m = S.build_model("duet")
    names = lambda g: mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g)  # noqa: E731
    pairs = {(names(a), names(b)) for a, b in zip(m.pair_geom1, m.pair_geom2)}
    assert pairs == {("rh_thumb3", "rh_index2"), ("rh_thumb3", "rh_index3")}
    hand = [g for g in range(m.ngeom) if names(g).startswith(("lh_", "rh_"))]
    for a in hand:
        for b in hand:     # contype/conaffinity rule: no two hand geoms collide by bitmask
            assert not (m.geom_contype[a] & m.geom_conaffinity[b])


def test_four_envs_step_under_jit_and_vmap():
    """The duet scene holds both hand models (the one-hand scenes step inside the envs, tests/test_envs.py)."""
    m = S.build_model("duet")
    mx = mjx.put_model(m)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    batch = jax.tree.map(lambda x: jnp.stack([x] * 4), mjx.put_data(m, d))
    ctrl = jnp.asarray(m.key_qpos[0])[None] + jnp.array([0.0, 0.02, -0.02, 0.05])[:, None]

    @jax.jit
    @jax.vmap
    def step(data, u):
        data = data.replace(ctrl=u)
        return jax.lax.fori_loop(0, S.SUBSTEPS, lambda _, x: mjx.step(mx, x), data)

    out = step(batch, ctrl)
    out = step(out, ctrl)
    q = np.asarray(out.qpos)
    assert q.shape == (4, m.nq) and np.all(np.isfinite(q))
    assert np.allclose(q[0], q[0]) and not np.allclose(q[1], q[3])   # different controls, different states
    assert np.abs(q[0] - m.key_qpos[0]).max() < 0.01                 # env 0 holds the home pose


def test_mirrored_scene_is_the_mirror_image_in_the_guitar_frame():
    poses = []
    for mirror in (False, True):
        m = S.build_model("duet", mirror=mirror)
        d = mujoco.MjData(m)
        mujoco.mj_resetDataKeyframe(m, d, 0)
        mujoco.mj_kinematics(m, d)
        tg = S.to_guitar_frame(m)
        poses.append({role: tg(S.finger_segments(d.xpos, d.site_xpos, S.hand_index(m, role))) for role in S.ROLES})
    for role in S.ROLES:
        np.testing.assert_allclose(poses[1][role][..., 0], -poses[0][role][..., 0], atol=1e-9)
        np.testing.assert_allclose(poses[1][role][..., 1:], poses[0][role][..., 1:], atol=1e-9)
    # the picking role holds the pick whichever hand model plays it, and each role keeps its workspace (x mirrored)
    m, mm = S.build_model("duet"), S.build_model("duet", mirror=True)
    assert S.hand_index(mm, "right").pick >= 0
    assert mujoco.mj_name2id(mm, mujoco.mjtObj.mjOBJ_GEOM, "rh_thumb3") in set(mm.pair_geom1)
    for role in S.ROLES:
        q, qm = S.hand_index(m, role).qpos[:3], S.hand_index(mm, role).qpos[:3]
        (x0, x1), (mx0, mx1) = m.jnt_range[q[0]], mm.jnt_range[qm[0]]
        assert (mx0, mx1) == (-x1, -x0)
        np.testing.assert_array_equal(m.jnt_range[list(q[1:])], mm.jnt_range[list(qm[1:])])


def test_lowered_fingertips_press_the_highest_fret():
    """The home pose hovers the four fingertips 12 mm above string 3 over frets 5-8; lowering the wrist by 9 mm puts
    them 3 mm above it: string 3 is pressed, at fret 8 (the highest of the four), and no neighbour is."""
    m = S.build_model("left")
    d = mujoco.MjData(m)
    hand, tg = S.hand_index(m, "left"), S.to_guitar_frame(m)
    result = []
    for dz in (0.0, -0.009):
        d.qpos[:] = m.key_qpos[0]
        d.qpos[hand.qpos[2]] += dz
        mujoco.mj_kinematics(m, d)
        segments = tg(S.finger_segments(d.xpos, d.site_xpos, hand))
        result.append(np.asarray(detect.pressed_frets(jnp.asarray(segments, jnp.float32))))
    assert result[0].tolist() == [0, 0, 0, 0, 0, 0]
    assert result[1].tolist() == [0, 0, 8, 0, 0, 0]
