"""BVH export (`motion.export`) and `play --motion`: the BVH is read back by a small parser of its own here, and its
forward kinematics (OFFSET, then the channels: positions, rotations composed in the listed order) is checked against
MuJoCo's `mj_kinematics` on the same joint values. NumPy and MuJoCo C only: no XLA compile."""
import mujoco
import numpy as np
import pytest

from dexguitar.motion import export as EX
from dexguitar.motion import format as F
from dexguitar.world import hands as H
from dexguitar.world import scene as S

# z-up world (x, y, z) -> the y-up BVH world (x, z, -y)
UP = np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]])


# ------------------------------------------------------------------------------------------------ a BVH reader

def parse_bvh(text: str) -> dict:
    """{joints: [{name, parent, offset, channels, end}], frames, frame_time, data (frames, channels)}."""
    tokens = text.split()
    joints, stack, i = [], [], 0
    assert tokens[0] == "HIERARCHY"
    i = 1
    while tokens[i] != "MOTION":
        t = tokens[i]
        if t in ("ROOT", "JOINT"):
            assert (t == "ROOT") == (not stack)
            joints.append({"name": tokens[i + 1], "parent": stack[-1] if stack else -1, "end": None})
            assert tokens[i + 2] == "{" and tokens[i + 3] == "OFFSET"
            joints[-1]["offset"] = np.array([float(x) for x in tokens[i + 4:i + 7]])
            assert tokens[i + 7] == "CHANNELS"
            n = int(tokens[i + 8])
            joints[-1]["channels"] = tokens[i + 9:i + 9 + n]
            stack.append(len(joints) - 1)
            i += 9 + n
        elif t == "End":
            assert tokens[i + 1:i + 4] == ["Site", "{", "OFFSET"] and tokens[i + 7] == "}"
            joints[stack[-1]]["end"] = np.array([float(x) for x in tokens[i + 4:i + 7]])
            i += 8
        elif t == "}":
            stack.pop()
            i += 1
        else:
            raise AssertionError(f"unexpected token {t!r}")
    assert not stack
    assert tokens[i + 1] == "Frames:" and tokens[i + 3:i + 5] == ["Frame", "Time:"]
    frames, frame_time = int(tokens[i + 2]), float(tokens[i + 5])
    lines = text.split("MOTION", 1)[1].strip().splitlines()[2:]
    data = np.array([[float(x) for x in line.split()] for line in lines])
    n_channels = sum(len(j["channels"]) for j in joints)
    assert data.shape == (frames, n_channels)
    return {"joints": joints, "frames": frames, "frame_time": frame_time, "data": data}


def elementary(axis: str, deg: float) -> np.ndarray:
    a = np.radians(deg)
    c, s = np.cos(a), np.sin(a)
    return {"X": np.array([[1, 0, 0], [0, c, -s], [0, s, c]]),
            "Y": np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
            "Z": np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])}[axis]


def bvh_fk(bvh: dict, frame: int) -> tuple[dict, dict]:
    """World (position, rotation) of every joint and the world position of every End Site (by its joint's name)."""
    row = iter(bvh["data"][frame])
    world, ends = {}, {}
    for j in bvh["joints"]:
        values = {c: next(row) for c in j["channels"]}
        local = j["offset"].copy()
        if "Xposition" in values:
            assert np.all(local == 0)         # position channels replace or add to the offset: the same at zero
            local = np.array([values[f"{a}position"] for a in "XYZ"])
        rot = np.eye(3)
        for c in j["channels"]:
            if c.endswith("rotation"):
                rot = rot @ elementary(c[0], values[c])
        if j["parent"] < 0:
            p, r = local, rot
        else:
            pp, pr = world[bvh["joints"][j["parent"]]["name"]]
            p, r = pp + pr @ local, pr @ rot
        world[j["name"]] = (p, r)
        if j["end"] is not None:
            ends[j["name"]] = p + r @ j["end"]
    return world, ends


def random_poses(hand: str, n: int, rng) -> np.ndarray:
    rng_ = F.joint_ranges(hand)
    return rng.uniform(rng_[:, 0], rng_[:, 1], size=(n, H.N_DOF))


def check_against_mujoco(bvh: dict, model, qpos: np.ndarray, every: int = 1) -> int:
    """Compare the BVH's FK of every `every`th frame with mj_kinematics on those frames' joint values (float64);
    returns the number of points compared."""
    data = mujoco.MjData(model)
    tip = {s: model.site_bodyid[s] for s in range(model.nsite)}
    checked = 0
    for t in range(0, len(qpos), every):
        data.qpos[:] = qpos[t]
        mujoco.mj_kinematics(model, data)
        world, ends = bvh_fk(bvh, t)
        for name, (p, r) in world.items():
            b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
            np.testing.assert_allclose(p, UP @ data.xpos[b], atol=1e-6, err_msg=name)
            np.testing.assert_allclose(r, UP @ data.xmat[b].reshape(3, 3), atol=1e-6, err_msg=name)
            checked += 1
        for name, p in ends.items():
            b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
            s = min(s for s, body in tip.items() if body == b)
            np.testing.assert_allclose(p, UP @ data.site_xpos[s], atol=1e-6, err_msg=name + " end")
            checked += 1
    return checked


# ------------------------------------------------------------------------------------------------ tests

@pytest.mark.parametrize("mirror", [False, True])
def test_bvh_of_both_hands_is_mujocos_kinematics(tmp_path, mirror):
    """Random poses over the whole joint ranges (wrist hinges to +-180 degrees): every body and fingertip of the
    BVH, read back, sits where MuJoCo puts it, to 1e-6 m, in the normal and the mirrored (left-handed) scene."""
    rng = np.random.default_rng(3)
    left = F.Motion("left", 60, random_poses("left", 6, rng))
    right = F.Motion("right", 60, random_poses("right", 6, rng))
    path = EX.write_bvh(tmp_path / "hands.bvh", [left, right], mirror=mirror)
    bvh = parse_bvh(path.read_text())
    assert bvh["frames"] == 6 and bvh["frame_time"] == pytest.approx(1 / 60, rel=1e-7)
    joints = bvh["joints"]
    assert len(joints) == 1 + 2 * 16 and joints[0]["name"] == "guitar" and joints[0]["parent"] == -1
    by_name = {j["name"]: j for j in joints}
    assert [joints[j["parent"]]["name"] for j in joints if j["name"].endswith("wrist")] == ["guitar", "guitar"]
    assert len(joints[0]["channels"]) == 6 and joints[0]["channels"][:3] == ["Xposition", "Yposition", "Zposition"]
    for name, j in by_name.items():
        assert len(j["channels"]) == (6 if name in ("guitar", "lh_wrist", "rh_wrist") else 3), name
        assert sorted(c[0] for c in j["channels"] if c.endswith("rotation")) == ["X", "Y", "Z"]
    assert joints[by_name["lh_index2"]["parent"]]["name"] == "lh_index1"
    ends = sorted(j["name"] for j in joints if j["end"] is not None)
    assert ends == sorted(f"{p}{f}3" for p in ("lh_", "rh_") for f in ("thumb",) + H.FINGERS)
    model = S.build_model("duet", mirror=mirror)
    qpos = np.tile(model.qpos0, (6, 1))
    for role, m in (("left", left), ("right", right)):
        q = H.mirror_qpos(m.qpos, side_from=role) if mirror else m.qpos
        qpos[:, list(S.hand_index(model, role).qpos)] = q
    assert check_against_mujoco(bvh, model, qpos) == 6 * (33 + 10)


def test_hand_channels_are_the_joint_angles(tmp_path):
    """The hand joints' channels are the hinge angles in degrees, in MuJoCo's axis order: a wrist pitched 120
    degrees reads 120 (Euler angles of the same rotation would read 60, the other two angles turned by 180)."""
    q = S.HOME["right"].copy()
    q[3:6] = np.radians([10.0, 120.0, -150.0])
    q2 = q.copy()
    q2[3:6] = np.radians([-175.0, -100.0, 179.0])
    path = EX.write_bvh(tmp_path / "r.bvh", [F.Motion("right", 30, np.stack([q, q2]))])
    bvh = parse_bvh(path.read_text())
    assert bvh["frame_time"] == pytest.approx(1 / 30, rel=1e-7)
    names = [j["name"] for j in bvh["joints"]]
    assert names[:2] == ["guitar", "rh_wrist"] and len(names) == 17
    wrist = bvh["joints"][1]
    assert wrist["channels"][3:] == ["Xrotation", "Yrotation", "Zrotation"]
    np.testing.assert_allclose(bvh["data"][:, 6:9], [q[:3], q2[:3]], atol=1e-8)           # the slides, m
    np.testing.assert_allclose(bvh["data"][:, 9:12], np.degrees([q[3:6], q2[3:6]]), atol=1e-6)
    index1 = bvh["joints"][names.index("rh_index1")]
    assert index1["channels"] == ["Xrotation", "Zrotation", "Yrotation"]


def test_euler_angles_recompose():
    """`euler` in each of the six orders gives angles whose rotations, composed in that order, are the input,
    at gimbal lock too."""
    rng = np.random.default_rng(0)
    quats = rng.normal(size=(50, 4))
    rots = np.stack([EX._quat_mat(q / np.linalg.norm(q)) for q in quats])
    for order in ("XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"):
        lock = np.stack([elementary(order[0], 30.0) @ elementary(order[1], s * 90.0) @ elementary(order[2], 50.0)
                         for s in (1, -1)])
        for rot, angles in zip(np.concatenate([rots, lock]), EX.euler(np.concatenate([rots, lock]), order)):
            back = (elementary(order[0], np.degrees(angles[0])) @ elementary(order[1], np.degrees(angles[1]))
                    @ elementary(order[2], np.degrees(angles[2])))
            np.testing.assert_allclose(back, rot, atol=1e-9, err_msg=order)


ODD_MODEL = """
<mujoco>
  <worldbody>
    <body name="base" pos="0.1 -0.2 0.3" quat="0.9 0.2 -0.3 0.1">
      <body name="arm" pos="0.05 0 0.02" quat="0.7 0.1 0.6 -0.2">
        <joint name="s" type="slide" axis="1 2 -1"/>
        <joint name="h1" type="hinge" axis="0.3 -1 0.2"/>
        <joint name="h2" type="hinge" axis="0 0 1"/>
        <geom size="0.01"/>
        <body name="hand" pos="0 0.1 0">
          <joint name="h3" type="hinge" axis="0 -1 0"/>
          <geom size="0.01"/>
          <site name="tip" pos="0.02 0.03 0"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_bodies_turned_from_their_parents(tmp_path):
    """A model whose bodies have rest orientations and oblique axes (Euler angles, not joint angles, in the
    channels): FK still matches MuJoCo, and a hinge turning twice round gives channels that do not wrap at 180
    degrees."""
    model = mujoco.MjModel.from_xml_string(ODD_MODEL)
    t = np.linspace(0.0, 1.0, 240)
    qpos = np.stack([0.1 * np.sin(6 * t), 4 * np.pi * t, np.pi * np.cos(3 * t), -4 * np.pi * t], axis=1)
    path = EX.write_model_bvh(tmp_path / "odd.bvh", model, qpos, 240.0, root="base")
    bvh = parse_bvh(path.read_text())
    assert [j["name"] for j in bvh["joints"]] == ["base", "arm", "hand"]
    assert [len(j["channels"]) for j in bvh["joints"]] == [6, 6, 3]
    assert bvh["joints"][2]["channels"][0] == "Yrotation"            # its one hinge, about -y: the angle negated
    np.testing.assert_allclose(bvh["data"][:, -3], -np.degrees(qpos[:, 3]), atol=1e-6)
    assert check_against_mujoco(bvh, model, qpos, every=7) > 0
    steps = np.abs(np.diff(bvh["data"], axis=0))
    assert steps.max() < 180.0                      # degrees per frame: unwrapped (a wrap at +-180 would be ~360)


def test_recorded_values_past_their_ranges_are_clipped():
    """A hard contact can push a joint past its range: beyond the format's tolerance it is clipped into the range,
    within it kept, so the .npz loads."""
    model = S.build_model("duet")
    qpos = np.tile(model.key_qpos[0], (3, 1))
    adr = S.hand_index(model, "left").qpos
    hi = F.joint_ranges("left")[20, 1]
    qpos[1, adr[20]] = hi + F.RANGE_TOL / 2
    left, right = EX.performance_motions(qpos, 60.0)
    assert left.qpos[1, 20] == hi + F.RANGE_TOL / 2 and right.qpos.shape == (3, 27)
    qpos[2, adr[20]] = hi + 2 * F.RANGE_TOL
    left, _ = EX.performance_motions(qpos, 60.0)
    assert left.qpos[2, 20] == hi and left.qpos[1, 20] == hi
    np.testing.assert_array_equal(left.qpos[0], qpos[0, list(adr)])


def test_play_motion_writes_npz_and_bvh(tmp_path, monkeypatch):
    """`dexguitar play --motion` (its rollout replaced by a hand-made recording whose hands move): OUT-left.npz and
    OUT-right.npz load as 60 Hz motions of every recorded frame, with the recorded joint values, and OUT.bvh has
    as many frames; without --motion none of them is written."""
    from test_perform import hand_made_performance

    from dexguitar import cli
    from dexguitar.perform import play as PL
    from dexguitar.perform import video as V
    song, rec = hand_made_performance()
    T = len(rec["press"])
    model = S.build_model("duet")
    rng = np.random.default_rng(1)
    qpos = np.tile(model.key_qpos[0], (T, 1)) + 0.05 * np.sin(np.linspace(0, 3, T))[:, None] * rng.normal(size=54)
    for role in S.ROLES:
        adr = list(S.hand_index(model, role).qpos)
        qpos[:, adr] = np.clip(qpos[:, adr], *F.joint_ranges(role).T)
    rec.update(qpos=qpos.astype(np.float32), frames=T, rollout_seconds=0.0)
    monkeypatch.setattr(PL, "play", lambda *a, **k: rec)
    monkeypatch.setattr(PL, "load_song", lambda s: song)
    monkeypatch.setattr(PL, "pair", lambda left, right: ({}, None))
    monkeypatch.setattr(V, "render_frames_png", lambda *a, **k: None)       # no picture: not what is tested here
    out = tmp_path / "perf"
    argv = ["play", "--left", "L", "--right", "R", "--song", "s", "--frames-only", "--json", "--out", str(out)]
    assert cli.main(argv) == 0
    assert not list(tmp_path.glob("*.npz")) and not list(tmp_path.glob("*.bvh"))
    assert cli.main(argv + ["--motion"]) == 0
    for role in S.ROLES:
        m = F.load(tmp_path / f"perf-{role}.npz")
        assert (m.hand, m.fps, m.n_frames) == (role, 60.0, T)
        np.testing.assert_array_equal(m.qpos, rec["qpos"][:, list(S.hand_index(model, role).qpos)])
    bvh = parse_bvh((tmp_path / "perf.bvh").read_text())
    assert bvh["frames"] == T and bvh["frame_time"] == pytest.approx(1 / 60, rel=1e-7)
    assert check_against_mujoco(bvh, model, qpos.astype(np.float32).astype(np.float64), every=40) > 0
