"""The render-only stage (`world.stage`): the physics scene's joints (a recorded qpos drives it unchanged), a physics
model left alone, strings where the guitar geometry puts them, a waisted body, outward-facing meshes, cameras that
frame what they should, the close-up following the fretting hand, and (with an offscreen GL, `offscreen_gl`) 720p
frames whose strings take the colours set and whose caption changes only its corner. Also `perform.glcheck`."""
import mujoco
import numpy as np
import pytest

from dexguitar.perform import colors as C
from dexguitar.motion import glcheck
from dexguitar.perform import video as V
from dexguitar.world import hands as H
from dexguitar.world import scene as S
from dexguitar.world import stage
from dexguitar.world.guitar import GUITAR


def names(model, kind, count):
    return [mujoco.mj_id2name(model, kind, i) for i in range(count)]


def posed(model, qpos):
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    mujoco.mj_camlight(model, data)
    return data


def project(model, data, camera: str, point, width=1280, height=720):
    """(column, row) of a world point in a fixed camera's picture (pinhole: the camera looks along its -z); NaN for
    a point behind the camera."""
    cid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
    p = data.cam_xmat[cid].reshape(3, 3).T @ (np.asarray(point) - data.cam_xpos[cid])
    if p[2] >= 0:
        return np.nan, np.nan
    focal = height / 2 / np.tan(np.radians(model.cam_fovy[cid]) / 2)
    return width / 2 + focal * p[0] / -p[2], height / 2 - focal * p[1] / -p[2]


def inside(pixel, width=1280, height=720, margin=0.05):
    col, row = pixel
    return margin * width < col < (1 - margin) * width and margin * height < row < (1 - margin) * height


@pytest.mark.parametrize("scene", ["left", "right", "duet"])
@pytest.mark.parametrize("mirror", [False, True])
def test_stage_has_the_physics_joints(scene, mirror):
    physics, shown = S.build_model(scene, mirror=mirror), stage.stage_model(scene, mirror=mirror)
    assert shown.nq == physics.nq == 27 * len(S.SCENES[scene])
    assert names(shown, mujoco.mjtObj.mjOBJ_JOINT, shown.njnt) == names(physics, mujoco.mjtObj.mjOBJ_JOINT,
                                                                         physics.njnt)
    assert names(shown, mujoco.mjtObj.mjOBJ_BODY, shown.nbody) == names(physics, mujoco.mjtObj.mjOBJ_BODY,
                                                                         physics.nbody)
    assert np.array_equal(shown.jnt_qposadr, physics.jnt_qposadr)
    assert np.array_equal(shown.key_qpos, physics.key_qpos)
    rng = np.random.default_rng(0)
    q = rng.uniform(physics.jnt_range[:, 0], physics.jnt_range[:, 1])     # hinges and slides: one qpos each
    a, b = posed(physics, q), posed(shown, q)
    assert np.allclose(a.xpos, b.xpos) and np.allclose(a.xquat, b.xquat)


def test_building_a_stage_leaves_the_physics_model_alone():
    physics = S.build_model("duet")
    # world + guitar + 16 links per hand; 27 DoF per hand; the neck and body boxes + per hand 2 palm capsules and
    # 3 capsules for each of 5 fingers
    assert (physics.nbody, physics.nq, physics.ngeom) == (2 + 2 * len(H.KEY_LINKS), 2 * H.N_DOF, 2 + 2 * (2 + 15))
    arrays = ("body_pos", "body_quat", "body_mass", "geom_size", "geom_pos", "geom_rgba", "geom_contype",
              "jnt_range", "actuator_gainprm", "cam_pos", "light_pos")
    before = {k: getattr(physics, k).copy() for k in arrays}
    counts = (physics.ngeom, physics.ncam, physics.nlight, physics.nmat, physics.nmesh)
    shown = stage.stage_model("duet")
    assert shown.ngeom > physics.ngeom and shown.nmesh > 0 and shown.ncam == 2
    assert (physics.ngeom, physics.ncam, physics.nlight, physics.nmat, physics.nmesh) == counts
    assert all(np.array_equal(before[k], getattr(physics, k)) for k in arrays)
    assert S.build_model("duet") is physics                             # still the cached model


@pytest.mark.parametrize("mirror", [False, True])
def test_strings_run_from_nut_to_bridge(mirror):
    shown = stage.stage_model("duet", mirror=mirror)
    sign = -1.0 if mirror else 1.0
    for i in range(1, 7):
        g = mujoco.mj_name2id(shown, mujoco.mjtObj.mjOBJ_GEOM, f"string{i}")
        assert g >= 0 and shown.geom_type[g] == mujoco.mjtGeom.mjGEOM_CAPSULE
        assert mujoco.mj_id2name(shown, mujoco.mjtObj.mjOBJ_BODY, shown.geom_bodyid[g]) == "guitar"
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, shown.geom_quat[g])
        half = rot.reshape(3, 3)[:, 2] * shown.geom_size[g, 1]
        ends = {tuple(np.round(shown.geom_pos[g] + s * half, 6)) for s in (-1, 1)}
        nut, bridge = GUITAR.strings[i - 1] * [sign, 1, 1]
        assert ends == {tuple(np.round(nut, 6)), tuple(np.round(bridge, 6))}


def test_body_outline_is_waisted():
    half = stage.body_outline()
    width, down = 2 * half[:, 0], half[:, 1]
    assert np.all(np.diff(down) > 0) and down[0] == 0 and width[0] == 0 and width[-1] == pytest.approx(0, abs=1e-9)
    upper = np.argmax(np.where(down < 0.15, width, 0))
    lower = np.argmax(width)
    waist = upper + np.argmin(width[upper:lower])
    assert down[upper] < down[waist] < down[lower]
    assert width[waist] < width[upper] < width[lower]
    assert 0.30 < width[lower] < 0.45 and width[waist] < 0.85 * width[upper]   # an acoustic guitar's proportions


def face_normals(verts, faces):
    a, b, c = (verts[faces[:, k]] for k in range(3))
    return np.cross(b - a, c - a), (a + b + c) / 3


def test_body_meshes_face_outward():
    meshes = stage.body_meshes(GUITAR)
    verts, faces = meshes["top"]
    normals, centers = face_normals(verts, faces)
    up = centers[:, 2] > centers[:, 2].min() + 1e-6                    # the top face of the plate
    assert np.all(normals[up, 2] > 0) and np.all(normals[~up, 2] < 0)
    verts, faces = meshes["shell"]
    normals, centers = face_normals(verts, faces)
    middle = verts[:, :2].mean(0)
    side = np.abs(normals[:, 2]) < 1e-9
    assert side.sum() > 50
    assert np.all(np.einsum("ij,ij->i", normals[side, :2], centers[side, :2] - middle) > 0)
    assert np.all(normals[~side, 2] < 0)                                 # the back faces down


@pytest.mark.parametrize("mirror", [False, True])
def test_cameras_frame_the_hands(mirror):
    shown = stage.stage_model("duet", mirror=mirror)
    data = posed(shown, shown.key_qpos[0])
    left, right = S.hand_index(shown, "left"), S.hand_index(shown, "right")
    tips = [data.site_xpos[s] for s in left.tips + right.tips]
    wrists = [data.xpos[left.key_bodies[0]], data.xpos[right.key_bodies[0]]]
    assert all(inside(project(shown, data, "front", p)) for p in tips + wrists)
    guitar = data.xpos[mujoco.mj_name2id(shown, mujoco.mjtObj.mjOBJ_BODY, "guitar")]
    assert inside(project(shown, data, "front", guitar), margin=0.3)   # the guitar near the middle
    # the close-up at the home pose (wrist 2 cm from where the close-up is set): the fretting fingertips, not the
    # picking hand
    assert all(inside(project(shown, data, "closeup", data.site_xpos[s])) for s in left.tips)
    assert not inside(project(shown, data, "closeup", data.xpos[right.key_bodies[0]]), margin=0.0)


def test_closeup_follows_the_fretting_hand_smoothly():
    shown = stage.stage_model("duet")
    ty = S.hand_index(shown, "left").qpos[1]
    q = np.tile(shown.key_qpos[0], (120, 1))
    q[:, ty] = np.where(np.arange(120) < 60, 0.0, 0.1)                 # the wrist jumps 10 cm up the neck
    fps = 30.0
    off = V.follow_fretting_hand(shown, q, fps)
    assert off.shape == (120, 3) and np.all(off[:, [0, 2]] == 0)
    assert np.allclose(off[:30, 1], 0) and np.allclose(off[-30:, 1], 0.1)
    assert np.all(np.diff(off[:, 1]) >= 0) and np.diff(off[:, 1]).max() <= 0.1 / (V.FOLLOW_SECONDS * fps) + 1e-12
    assert V.camera_offsets(shown, q, fps, "front") is None


# ------------------------------------------------------------------------------------------------ pictures

@pytest.fixture(scope="module")
def frames(offscreen_gl):
    """The stage at its home pose, 1280 x 720 from the front: strings red, strings green, a caption."""
    shown = stage.stage_model("duet")
    q = shown.key_qpos[0]
    with V.SceneRenderer(shown, 1280, 720, "front") as r:
        out = {"red": r.frame(q, np.tile(C.RED, (6, 1))), "green": r.frame(q, np.tile(C.GREEN, (6, 1))),
               "caption": r.frame(q, np.tile(C.GREEN, (6, 1)), "Song\n100 bpm\nF1 both hands: 0.500 (2 notes)")}
    return shown, q, out


def test_frame_is_a_picture_and_strings_take_their_colour(frames):
    shown, q, out = frames
    red, green = out["red"].astype(int), out["green"].astype(int)
    assert red.shape == (720, 1280, 3) and red.std() > 20
    assert len(np.unique(red.reshape(-1, 3) // 16, axis=0)) > 50           # shading, not a few flat colours
    changed = np.abs(red - green).sum(-1) > 60
    assert 2000 < changed.sum() < 0.05 * changed.size                      # thin strings, not the whole frame
    assert np.mean(red[changed, 0] > red[changed, 1:].max(-1) + 40) > 0.9
    assert np.mean(green[changed][:, 1] > green[changed][:, [0, 2]].max(-1) + 40) > 0.9
    data = posed(shown, q)
    guitar = mujoco.mj_name2id(shown, mujoco.mjtObj.mjOBJ_BODY, "guitar")
    rows, cols = np.nonzero(changed)
    for i in (1, 6):                            # the outer strings' midpoints (the 12th fret, between the hands)
        point = data.xpos[guitar] + data.xmat[guitar].reshape(3, 3) @ GUITAR.strings[i - 1].mean(0)
        col, row = project(shown, data, "front", point)
        assert np.min(np.hypot(cols - col, rows - row)) < 3


def test_caption_changes_only_its_corner(frames):
    _, _, out = frames
    changed = np.abs(out["caption"].astype(int) - out["green"].astype(int)).sum(-1) > 0
    rows, cols = np.nonzero(changed)
    assert changed.sum() > 1000 and rows.max() < 720 / 4 and cols.max() < 1280 / 3


# ------------------------------------------------------------------------------------------------ glcheck

@pytest.fixture
def fresh_backend(monkeypatch):
    """glcheck.backend() without the environment's choice and without its cached answer, given back after."""
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    monkeypatch.delenv("PYOPENGL_PLATFORM", raising=False)
    glcheck.backend.cache_clear()
    yield
    glcheck.backend.cache_clear()


def test_backend_takes_the_first_that_draws(monkeypatch, fresh_backend):
    tried = []
    monkeypatch.setattr(glcheck, "probe", lambda name: tried.append(name) or (None if name == "egl" else "broken"))
    assert glcheck.backend() == "egl" and tried == ["osmesa", "egl"]
    glcheck.backend.cache_clear()
    monkeypatch.setattr(glcheck, "probe", lambda name: "no driver")
    with pytest.raises(glcheck.NoGL, match=r"osmesa: no driver; egl: no driver.*apt-get install libosmesa6"):
        glcheck.backend()
    monkeypatch.setenv("MUJOCO_GL", "egl")
    assert glcheck.backend() == "egl"                                    # chosen, not tried
    assert glcheck.main(["egl"]) == 1 and glcheck.main(["vulkan"]) == 2


def test_probe_says_why_not():
    why = glcheck.probe("nonexistent")
    assert why is not None and "nonexistent" in why
