"""Reference motions: the file format, resampling, forward kinematics against the env, the authors' clip reader, the
shipped default clips and rendering."""
import json
import warnings
from pathlib import Path

import mujoco
import numpy as np
import pytest

from dexguitar.motion import defaults, kinematics as K, official as O
from dexguitar.motion.format import Motion, MotionError, joint_ranges, load, resample, save, validate
from dexguitar.world import hands as H
from dexguitar.world import scene as S

STRUM = Path(__file__).resolve().parents[2] / "shared" / "data" / "official" / "motions" / "strum.json"


def random_motion(hand="left", n=10, fps=60.0, seed=0):
    rng = np.random.default_rng(seed)
    r = joint_ranges(hand)
    return Motion(hand, fps, rng.uniform(r[:, 0], r[:, 1], size=(n, H.N_DOF)), "random")


# ------------------------------------------------------------------------------------------------ format

@pytest.mark.parametrize("suffix", [".npz", ".json"])
def test_save_load_round_trip(tmp_path, suffix):
    m = random_motion("right", n=7, fps=120)
    path = save(m, tmp_path / f"clip{suffix}")
    back = load(path)
    assert (back.hand, back.fps, back.name, back.qpos.shape) == ("right", 120.0, "random", (7, 27))
    np.testing.assert_allclose(back.qpos, m.qpos, atol=1e-6)
    if suffix == ".npz":
        assert back.qpos.dtype == np.float32


def test_validation_errors_name_the_file(tmp_path):
    path = tmp_path / "bad.json"
    doc = {"hand": "left", "fps": 60, "qpos": [[0.0] * 26]}
    path.write_text(json.dumps(doc))
    with pytest.raises(MotionError, match=r"bad\.json.*27"):
        load(path)
    q = np.tile(S.HOME["left"], (3, 1))
    q[1, 13] = np.nan
    path.write_text(json.dumps({"hand": "left", "fps": 60, "qpos": q.tolist()}))
    with pytest.raises(MotionError, match=r"bad\.json:frame 1, joint index2: non-finite value"):
        load(path)
    q[1, 13] = 3.0                                   # index2 beyond its 1.57 rad limit
    path.write_text(json.dumps({"hand": "left", "fps": 60, "qpos": q.tolist()}))
    with pytest.raises(MotionError, match=r"bad\.json:frame 1, joint index2: 3\.0000 is outside the joint's range"):
        load(path)
    names = [j.name for j in H.joints("left")]
    names[3], names[4] = names[4], names[3]
    path.write_text(json.dumps({"hand": "left", "fps": 60, "joints": names, "qpos": [S.HOME["left"].tolist()]}))
    with pytest.raises(MotionError, match=r"bad\.json:joint 3: 'wrist_ry', expected 'wrist_rx'"):
        load(path)
    if STRUM.exists():                               # the authors' format is recognised and pointed out
        with pytest.raises(MotionError, match="authors"):
            load(STRUM)


def test_resample_is_linear():
    t = np.arange(13) / 120.0
    q = np.tile(S.HOME["left"], (13, 1))
    q[:, 0] = 0.05 + 0.1 * t                         # a slide moving at constant speed
    q[:, 13] = 0.2 + 3.0 * t                         # a hinge too
    m = resample(Motion("left", 120, q), 60)
    assert m.fps == 60 and m.n_frames == 7 and m.seconds == pytest.approx(0.1)
    np.testing.assert_allclose(m.qpos[:, 0], 0.05 + 0.1 * np.arange(7) / 60, atol=1e-12)
    np.testing.assert_allclose(m.qpos[:, 13], 0.2 + 3.0 * np.arange(7) / 60, atol=1e-12)
    up = resample(m, 240)
    assert up.n_frames == 25
    np.testing.assert_allclose(up.qpos[::4], m.qpos, atol=1e-12)


# ------------------------------------------------------------------------------------------------ kinematics

def test_fk_matches_env_link_states():
    """Our link states equal the env's (`GuitarEnv.link_states`, MJX) at its reset pose (the home keyframe; with
    init_noise = 0 the reset state is that keyframe) and at a random pose."""
    from mujoco import mjx

    from dexguitar import envs
    from dexguitar.music.song import Song, make_note
    env = envs.make("left", [Song(100, (make_note("1/8", [-1, 3, -1, -1, -1, -1]),))], init_noise=0.0)
    home = np.asarray(env.link_states(env._data0))[0]
    ours = K.link_states(Motion("left", 60, S.HOME["left"][None]))[0]
    assert ours.shape == (16, 7)
    np.testing.assert_allclose(ours, home, atol=1e-5)

    m = random_motion("left", n=1, seed=3)
    d = mujoco.MjData(env.model)
    d.qpos[list(env.hands[0].qpos)] = m.qpos[0]
    mujoco.mj_kinematics(env.model, d)
    theirs = np.asarray(env.link_states(mjx.put_data(env.model, d)))[0]
    np.testing.assert_allclose(K.link_states(m)[0], theirs, atol=1e-5)


def test_reference_frames_and_velocities():
    m = defaults.default_motion("right")
    short = m.replace(qpos=m.qpos[:121])             # 2 s
    ref = K.reference_frames(resample(short, 120), fps=60)
    assert ref.shape == (121, 16, 7) and ref.dtype == np.float32
    np.testing.assert_allclose(np.linalg.norm(ref[..., 3:], axis=-1), 1.0, atol=1e-5)
    assert (ref[..., 3] >= 0).all()
    feats = K.reference_frames(short, velocities=True)
    assert feats.shape == (121, 16, 13)
    np.testing.assert_allclose(feats[0, :, 7:], 0.0, atol=1e-5)
    np.testing.assert_allclose(feats[5, :, 7:10], (ref[5, :, :3] - ref[4, :, :3]) * 60, atol=1e-3)


# ------------------------------------------------------------------------------------------------ the authors' clips

def test_single_axis_quaternion_to_angle():
    for theta in (-1.2, 0.0, 0.4, 1.55, 2.9):
        q = np.array([0.0, 0.0, np.sin(theta / 2), np.cos(theta / 2)])     # xyzw, about z
        assert O.hinge_angle(q, "z") == pytest.approx(theta)
        assert O.hinge_angle(np.array([q[2], 0.0, 0.0, q[3]]), "x") == pytest.approx(theta)


def test_three_hinge_decomposition_matches_mujoco():
    """A body with hinges x, y, z at a known Euler triple: MuJoCo's body quaternion decomposes back into it, and
    two hinges x, z come back exactly too."""
    xml = """<mujoco><worldbody>
      <body><joint axis="1 0 0"/><joint axis="0 1 0"/><joint axis="0 0 1"/><geom size="0.1"/></body>
      <body><joint axis="1 0 0"/><joint axis="0 0 1"/><geom size="0.1"/></body></worldbody></mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    triple, pair = np.array([0.3, -0.7, 1.9]), np.array([-0.5, 0.25])
    d.qpos[:] = np.r_[triple, pair]
    mujoco.mj_kinematics(m, d)
    to_xyzw = lambda q: np.r_[q[1:], q[0]]  # noqa: E731
    np.testing.assert_allclose(O.euler_xyz(to_xyzw(d.xquat[1])), triple, atol=1e-9)
    np.testing.assert_allclose(O.quat_from_euler_xyz(*triple), to_xyzw(d.xquat[1]), atol=1e-9)
    np.testing.assert_allclose(O.euler_xz(to_xyzw(d.xquat[2])), pair, atol=1e-9)


@pytest.mark.skipif(not STRUM.exists(), reason="the authors' strum clip is not here: "
                    "../shared/data/official/motions/strum.json beside the clone")
def test_official_strum_clip():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = O.read_official_json(STRUM)
    assert (m.hand, m.fps, m.n_frames) == ("right", 120.0, 278)
    validate(m, STRUM, tol=0.0)
    index2 = [j.name for j in H.joints("right")].index("index2")
    np.testing.assert_allclose(m.qpos[:, index2], np.radians(89.0), atol=0.01)      # as documented: ~89 deg
    first = json.loads(STRUM.read_text())["frames"][0]
    assert m.qpos[0, 0] == pytest.approx(first["RH:wrist_dx"][0])
    # The wrist link's orientation in the guitar frame is the clip's wrist rotation (xyzw -> wxyz).
    q = np.array(first["RH:wrist"])
    wrist = K.link_states(m.replace(qpos=m.qpos[:1]))[0, 0, 3:]
    np.testing.assert_allclose(wrist, np.r_[q[3], q[:3]] * np.sign(q[3]), atol=1e-6)


def test_official_errors_name_file_and_frame(tmp_path):
    path = tmp_path / "clip.json"
    frame = {f"RH:{b}": ([0.0, 0.0, 0.0] if k == "slide" else [0.0, 0.0, 0.0, 1.0]) for b, k, _ in O.LAYOUT}
    broken = dict(frame)
    del broken["RH:index2"]
    path.write_text(json.dumps({"fps": 120, "frames": [frame, broken]}))
    with pytest.raises(MotionError, match=r"clip\.json:frame 1: missing body 'RH:index2'"):
        O.read_official_json(path)


# ------------------------------------------------------------------------------------------------ default clips

def test_default_clips_load_and_stay_in_range():
    left, right = defaults.default_motion("left"), defaults.default_motion("right")
    assert left.hand == "left" and right.hand == "right" and left.fps == right.fps == 60
    assert 38 <= left.seconds <= 42
    assert 10 <= right.seconds <= 20
    for m in (left, right):
        validate(m, tol=0.01)
    assert sum(p.stat().st_size for p in defaults.CLIPS_DIR.glob("*.npz")) < 400_000


def test_default_clip_names_are_not_shadowed_by_folders(tmp_path, monkeypatch):
    """`dexguitar sync` run where a folder `left/` exists (a run's stage folder) read that folder as the reference
    motion, and failed; a file named `left` is still read as one."""
    from dexguitar.motion import load_motion
    monkeypatch.chdir(tmp_path)
    (tmp_path / "left").mkdir()
    np.testing.assert_array_equal(load_motion("left").qpos, defaults.default_motion("left").qpos)
    (tmp_path / "right").write_text("not a motion")
    with pytest.raises(MotionError, match="right"):
        load_motion("right")


def test_left_clip_presses_frets():
    import jax
    import jax.numpy as jnp

    from dexguitar.world import detect
    m = defaults.default_motion("left")
    frames = np.arange(30, m.n_frames, 23)           # ~100 frames across the clip
    segs = K.finger_segments(m.replace(qpos=m.qpos[frames]))
    pressed = np.asarray(jax.jit(jax.vmap(detect.pressed_frets))(jnp.asarray(segs, jnp.float32)))
    one = (pressed > 0).sum(1) == 1
    assert one.mean() > 0.75
    assert ((pressed[one] >= 1) & (pressed[one] <= 22)).any(1).all()
    assert len(set(pressed[one].max(1))) >= 10        # successive frets along the neck


# ------------------------------------------------------------------------------------------------ render

def test_render_writes_png(tmp_path, offscreen_gl):
    from dexguitar.motion.render import png_size, render_motion
    m = defaults.default_motion("left")
    out = render_motion(m, tmp_path / "strip.png", frames=3, width=96, height=64)
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert png_size(out) == (3 * 96, 64)
    import zlib
    raw = zlib.decompress(data[data.index(b"IDAT") + 4:data.index(b"IEND") - 8])
    img = np.frombuffer(raw, np.uint8).reshape(64, 1 + 3 * 96 * 3)[:, 1:]
    assert img.std() > 5                              # not a blank image


def test_cli_info(capsys):
    from dexguitar.motion.cli import main
    assert main(["motion", "info", "right", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["hand"] == "right" and info["frames"] > 600 and len(info["joints"]) == 27
    assert main(["motion", "info", "/nonexistent/clip.npz"]) == 2
