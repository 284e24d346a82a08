"""The stage: a render-only MuJoCo model of a scene, so that videos and pictures look like the paper's Fig. 1.

The physics scenes (`scene.build_spec`) are boxes and capsules: cheap for MJX, plain to look at. The stage starts
from the same spec, so its bodies, joints and qpos order are the physics scene's and a recorded qpos drives it
unchanged; then it swaps the geoms for visual ones: a guitar of our own making (a waisted body outline extruded,
sound hole with a rosette, neck with a rounded back, fretboard, angled headstock with tuners, frets, nut, bridge
and the six strings `string1`..`string6` whose colours the videos set), hands with skin, a rounded palm and nails
over the physics finger capsules, a studio backdrop (a floor curving up into a wall) and two soft lights. Cameras:
"front" frames the guitar and both hands, "closeup" the fretting hand (videos slide it along the neck after the
hand). Meshes are made here with numpy, a few hundred triangles each, and round geoms are drawn coarser than
MuJoCo's default: software OpenGL draws a 1280 x 720 frame in a few tens of milliseconds. Nothing here reaches the
envs: MJX never sees the stage.
"""
from __future__ import annotations

import dataclasses

import mujoco
import numpy as np

from dexguitar.world import scene as S
from dexguitar.world.guitar import BODY_TOP_Z, GUITAR, NECK_END_Y, Guitar

# Body of a steel-string acoustic: joined to the neck at fret 14; dreadnought-like half outline (half-width x,
# distance d below the neck joint), top to bottom, drawn through by a Catmull-Rom spline. Metres.
BODY_JOIN_FRET = 14
BODY_HALF_OUTLINE = ((0.0, 0.0), (0.06, 0.008), (0.108, 0.03), (0.136, 0.09), (0.126, 0.16), (0.116, 0.205),
                     (0.134, 0.26), (0.176, 0.34), (0.182, 0.41), (0.134, 0.474), (0.0, 0.49))
BODY_DEPTH = 0.10
TOP_THICKNESS = 0.003                 # MuJoCo makes a convex hull of every mesh: no flat ones
BINDING = (0.0006, 0.004)             # the cream edge around the top: outward, down
OUTLINE_SAMPLES = 8                   # spline points per control segment
MIN_FACE_AREA = 1e-12                 # m^2 (twice the area): smaller faces are where two outlines meet
SOUND_HOLE = (-0.298, 0.046, 0.058)   # centre y, radius of the hole, outer radius of the rosette
NECK_DEPTH = 0.0075                   # rounded back below the body top (the thumb touches the physics box at -8 mm)
NECK_RING = 12                        # points on the half-ellipse of the neck's back
BOARD_MARGIN = 0.0008                 # fretboard wider than the strings' neck half-width
HEADSTOCK_ANGLE = np.radians(13.0)    # tilted back from the nut
HEADSTOCK_THICKNESS = 0.014
# Headstock half outline (half-width, distance from the nut along the headstock), convex.
HEADSTOCK_OUTLINE = ((0.026, 0.0), (0.040, 0.035), (0.044, 0.15), (0.036, 0.18), (0.018, 0.19))
TUNERS = (0.05, 0.095, 0.14)          # distances of the tuner posts from the nut; strings 1-3 / 4-6 per side
TUNER_X = 0.029
POST = (0.008, 0.003)                 # tuner post above the headstock face: height, radius
PEG = (0.007, 0.03, 0.0025, (0.006, 0.009, 0.004))   # tuner shaft under the face: depth, length, radius; knob radii
STRING_EXTRA_RADIUS = 0.0005          # strings from the nut to the tuners (not coloured)
INLAY_FRETS = (3, 5, 7, 9, 12, 15, 17, 19, 21)

# The palm is the convex hull of round blobs (radii across, along, thick; hand frame) at the knuckles, the heel
# (as wide as HEEL_WIDTH of the knuckles), the thumb's base and the middle of the back of the hand (raised a little).
KNUCKLE_BLOB = (0.011, 0.011, 0.010)
HEEL_BLOB = (0.013, 0.012, 0.010)
THUMB_BLOB = (0.014, 0.018, 0.012)
BACK_BLOB = (0.02, 0.02, 0.006)
BACK_RISE = 0.008
HEEL_WIDTH = 0.85
BLOB_POINTS = 64                      # points per blob (fewer show facets in a close-up)
WRIST = ((0.0, 0.02, -0.002), (0.025, 0.036, 0.018))   # the wrist, an ellipsoid: centre from the heel, radii
NAIL = (0.7, 0.32, 0.28)              # nail half sizes in finger radii (across) / distal lengths (along) / radii
NAIL_RISE = 0.8                       # nail centre above the phalanx axis, in finger radii

# A studio backdrop: a floor that curves up into a wall behind the player (a cyclorama), lit, untextured: a soft
# gradient that costs nothing (a skybox texture doubled the time of a frame in software GL). World frame, metres.
BACKDROP = {"front": 6.0, "back": -1.6, "radius": 1.0, "top": 6.0, "half_width": 8.0, "bend_points": 8}
COLORS = {
    "spruce": (0.80, 0.60, 0.36, 1), "mahogany": (0.36, 0.17, 0.07, 1), "board": (0.13, 0.08, 0.05, 1),
    "bone": (0.95, 0.92, 0.84, 1), "metal": (0.8, 0.8, 0.78, 1), "hole": (0.04, 0.025, 0.02, 1),
    "rosette": (0.22, 0.12, 0.06, 1), "skin": (0.89, 0.69, 0.57, 1), "nail": (0.96, 0.80, 0.74, 1),
    "backdrop": (0.62, 0.6, 0.58, 1),
}
SHINE = {"metal": (0.9, 0.8), "board": (0.3, 0.5), "spruce": (0.35, 0.6), "mahogany": (0.35, 0.6),
         "skin": (0.12, 0.25), "nail": (0.4, 0.6)}       # (specular, shininess); the rest (0.1, 0.2)
# Lights: direction (world), diffuse: a key light from above in front and a fill from the side (each light costs
# about a sixth of a frame in software GL).
LIGHTS = (((0.35, -1.0, -1.0), 0.6), ((-0.8, -0.6, -0.5), 0.3))
HEADLIGHT = (0.3, 0.2)                                     # ambient, diffuse
QUALITY = (16, 8)                                          # slices and stacks of round geoms (MuJoCo: 28, 16)

# Cameras: the point looked at and the eye, in the guitar frame of a right-handed player; vertical field of view.
# "front": the whole guitar, both hands. "closeup": the fretting hand with its wrist at y = 0 (videos slide it
# along the neck after the hand).
FRONT_CAMERA = ((0.0, -0.11, 0.0), (0.1, -0.05, 0.85), 45.0)
CLOSEUP_CAMERA = ((0.045, 0.05, 0.0), (-0.035, -0.075, 0.30), 34.0)


def catmull_rom(points: np.ndarray, samples: int) -> np.ndarray:
    """Points on the closed uniform Catmull-Rom spline through `points` (n, 2), `samples` per segment."""
    p = np.asarray(points, np.float64)
    t = np.arange(samples)[:, None] / samples
    out = []
    for i in range(len(p)):
        p0, p1, p2, p3 = p[i - 1], p[i], p[(i + 1) % len(p)], p[(i + 2) % len(p)]
        out.append(0.5 * (2 * p1 + (p2 - p0) * t + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t ** 2
                          + (3 * p1 - p0 - 3 * p2 + p3) * t ** 3))
    return np.concatenate(out)


def body_outline(samples: int = OUTLINE_SAMPLES) -> np.ndarray:
    """(m, 2) half outline of the body, (half-width, distance below the neck joint), from the top centre to the
    bottom centre; the other half is its mirror image. A closed spline through both halves, so the two meet
    without a corner."""
    half = np.asarray(BODY_HALF_OUTLINE)
    loop = np.concatenate([half, half[-2:0:-1] * [-1.0, 1.0]])
    curve = catmull_rom(loop, samples)
    return curve[: (len(half) - 1) * samples + 1]


def strip_mesh(left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and faces of the surface between two polylines (m, 3) sampled at the same parameter, faces wound so
    the normal is (right - left) x (next - this); no faces of zero area (where the polylines meet)."""
    m = len(left)
    verts = np.concatenate([left, right])
    i = np.arange(m - 1)
    faces = np.concatenate([np.stack([i, m + i, m + i + 1], 1), np.stack([i, m + i + 1, i + 1], 1)])
    a, b, c = (verts[faces[:, k]] for k in range(3))
    return verts, faces[np.linalg.norm(np.cross(b - a, c - a), axis=1) > MIN_FACE_AREA]


def body_meshes(guitar: Guitar, samples: int = OUTLINE_SAMPLES) -> dict:
    """The body as (vertices, faces) meshes in the guitar frame: "top" (the soundboard, facing +z) and "shell"
    (sides and back)."""
    half = body_outline(samples)
    y_join = guitar.fret_y[BODY_JOIN_FRET]
    right = np.stack([half[:, 0], y_join - half[:, 1], np.zeros(len(half))], 1)
    left = right * [-1.0, 1.0, 1.0]
    top, bottom = BODY_TOP_Z, BODY_TOP_Z - BODY_DEPTH
    v, f = strip_mesh(right + [0, 0, top], left + [0, 0, top])      # (left - right) x (down) = +z
    v_under, f_under = strip_mesh(left + [0, 0, top - TOP_THICKNESS], right + [0, 0, top - TOP_THICKNESS])
    meshes = {"top": (np.concatenate([v, v_under]), np.concatenate([f, f_under + len(v)]))}   # a plate, not a plane
    v_back, f_back = strip_mesh(left + [0, 0, bottom], right + [0, 0, bottom])
    ring = np.concatenate([right, left[-2:0:-1]])                   # the closed outline, clockwise seen from +z
    ring = np.concatenate([ring, ring[:1]])
    v_side, f_side = strip_mesh(ring + [0, 0, bottom], ring + [0, 0, top])
    meshes["shell"] = (np.concatenate([v_side, v_back]), np.concatenate([f_side, f_back + len(v_side)]))
    out, down = BINDING
    edge = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(ring[:, :2], axis=0), axis=1))])
    normal = np.gradient(ring[:, :2], edge, axis=0) @ [[0.0, 1.0], [-1.0, 0.0]]     # tangent turned outward
    wider = ring + np.pad(out * normal / np.linalg.norm(normal, axis=1, keepdims=True), ((0, 0), (0, 1)))
    meshes["binding"] = strip_mesh(wider + [0, 0, top - down], wider + [0, 0, top + 0.0002])
    return meshes


def neck_mesh(guitar: Guitar) -> tuple[np.ndarray, np.ndarray]:
    """The neck's rounded back from the nut to the body (a half-ellipse under the fretboard, tapering with it)."""
    ys = (guitar.nut_y, guitar.fret_y[BODY_JOIN_FRET] - 0.05)       # into the body, hidden under its top
    theta = np.linspace(0.0, np.pi, NECK_RING)
    rings = []
    for y in ys:
        hw = float(guitar.neck_half_width(y)) + BOARD_MARGIN
        rings.append(np.stack([hw * np.cos(theta), np.full(NECK_RING, y),
                               BODY_TOP_Z - NECK_DEPTH * np.sin(theta)], 1))
    return strip_mesh(rings[1], rings[0])


def fretboard_vertices(guitar: Guitar) -> np.ndarray:
    """The 8 corners of the tapered fretboard (its convex hull is the mesh): from the nut to its end, from the
    body top up to the fretboard surface."""
    out = []
    for y in (guitar.nut_y, NECK_END_Y):
        hw = float(guitar.neck_half_width(y)) + BOARD_MARGIN
        out += [(sx * hw, y, z) for sx in (-1, 1) for z in (BODY_TOP_Z, guitar.fretboard_z)]
    return np.asarray(out)


def headstock_point(guitar: Guitar, x, s, h=0.0) -> np.ndarray:
    """Guitar-frame point at (x, distance s from the nut along the headstock, height h above its face)."""
    c, sn = np.cos(HEADSTOCK_ANGLE), np.sin(HEADSTOCK_ANGLE)
    z0 = BODY_TOP_Z + 0.004
    return np.array([x, guitar.nut_y + s * c + h * sn, z0 - s * sn + h * c])


def headstock_vertices(guitar: Guitar) -> np.ndarray:
    """Corners of the headstock plate (convex: its hull is the mesh)."""
    return np.asarray([headstock_point(guitar, sx * hw, s, h) for hw, s in HEADSTOCK_OUTLINE for sx in (-1, 1)
                       for h in (0.0, -HEADSTOCK_THICKNESS)])


def tuner_posts(guitar: Guitar) -> np.ndarray:
    """(6, 3) top of the tuner post of strings 1..6: the treble strings on the +x side (1 nearest the nut), the
    bass strings on the -x side (6 nearest the nut)."""
    sign = guitar.sign
    posts = [headstock_point(guitar, sign * TUNER_X, s, POST[0]) for s in TUNERS]
    posts += [headstock_point(guitar, -sign * TUNER_X, s, POST[0]) for s in TUNERS[::-1]]
    return np.asarray(posts)


def blob(center, radii, n: int = BLOB_POINTS) -> np.ndarray:
    """n points on an ellipsoid (a Fibonacci sphere scaled): a round corner of a convex hull."""
    k = np.arange(n) + 0.5
    z = 1 - 2 * k / n
    phi = np.pi * (1 + 5 ** 0.5) * k
    r = np.sqrt(1 - z * z)
    return np.asarray(center) + np.stack([r * np.cos(phi), r * np.sin(phi), z], 1) * radii


def capsule_ends(model: mujoco.MjModel, geom: int) -> tuple[np.ndarray, np.ndarray]:
    """The two end points of a capsule geom in its body's frame, the one nearer the body's origin first (a palm
    capsule's heel, a phalanx's joint)."""
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, model.geom_quat[geom])
    axis = rot.reshape(3, 3)[:, 2] * model.geom_size[geom, 1]
    ends = model.geom_pos[geom] - axis, model.geom_pos[geom] + axis
    return tuple(sorted(ends, key=np.linalg.norm))


def look_at(eye, target, up) -> np.ndarray:
    """MuJoCo `xyaxes` (image right, image up) of a camera at `eye` looking at `target`, `up` upward."""
    fwd = np.asarray(target, float) - eye
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, up)
    right /= np.linalg.norm(right)
    return np.concatenate([right, np.cross(right, fwd)])


def guitar_rotation(mirror: bool) -> np.ndarray:
    """The guitar frame's orientation in the world (columns: its axes)."""
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, S.guitar_quat(mirror))
    return rot.reshape(3, 3)


def flip_x(mirror: bool) -> np.ndarray:
    """Factors that mirror x for a left-handed player's stage (ones otherwise)."""
    return np.array([-1.0 if mirror else 1.0, 1.0, 1.0])


def camera_pose(target, eye, mirror: bool) -> tuple[np.ndarray, np.ndarray]:
    """pos and xyaxes in the guitar frame of a camera at `eye` looking at `target` (guitar frame of a right-handed
    player), world up upward. Mirrored (a left-handed player): x negated, so the picture is the mirror image of the
    right-handed one."""
    up = guitar_rotation(False).T @ [0.0, 0.0, 1.0]
    eye = np.asarray(eye, float) * flip_x(mirror)
    return eye, look_at(eye, np.asarray(target, float) * flip_x(mirror), up * flip_x(mirror))


def backdrop_mesh() -> tuple[np.ndarray, np.ndarray]:
    """The cyclorama (world frame): the floor from the front to the bend, a quarter circle up, the wall behind."""
    b = BACKDROP
    angle = np.linspace(0.0, np.pi / 2, b["bend_points"])
    bend = np.stack([b["back"] - b["radius"] * np.sin(angle), b["radius"] * (1 - np.cos(angle))], 1)
    profile = np.concatenate([[[b["front"], 0.0]], bend, [[b["back"] - b["radius"], b["top"]]]])   # (y, z)
    side = lambda x: np.stack([np.full(len(profile), x), profile[:, 0], profile[:, 1]], 1)  # noqa: E731
    return strip_mesh(side(b["half_width"]), side(-b["half_width"]))


def _add_materials(spec: mujoco.MjSpec) -> None:
    for name, rgba in COLORS.items():
        specular, shininess = SHINE.get(name, (0.1, 0.2))
        spec.add_material(name=name, rgba=rgba, specular=specular, shininess=shininess)


def _add_mesh(spec, body, name, material, verts, faces=None):
    """A visual mesh geom; without faces the mesh is the convex hull of the vertices."""
    mesh = spec.add_mesh(name=name, uservert=np.asarray(verts, np.float64).ravel().tolist())
    if faces is not None:
        mesh.userface = np.asarray(faces, np.int32).ravel().tolist()
    mesh.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL     # open surfaces: no volume to weigh
    return body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name, material=material)


def _add_guitar(spec: mujoco.MjSpec, guitar: Guitar) -> None:
    body = spec.body("guitar")
    box, cyl, cap, sph = (mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtGeom.mjGEOM_CYLINDER, mujoco.mjtGeom.mjGEOM_CAPSULE,
                          mujoco.mjtGeom.mjGEOM_SPHERE)
    meshes = body_meshes(guitar)
    _add_mesh(spec, body, "body_top", "spruce", *meshes["top"])
    _add_mesh(spec, body, "body_shell", "mahogany", *meshes["shell"])
    _add_mesh(spec, body, "binding", "bone", *meshes["binding"])
    _add_mesh(spec, body, "neck", "mahogany", *neck_mesh(guitar))
    _add_mesh(spec, body, "fretboard", "board", fretboard_vertices(guitar))
    _add_mesh(spec, body, "headstock", "board", headstock_vertices(guitar))
    hole_y, hole_r, rosette_r = SOUND_HOLE
    body.add_geom(name="rosette", type=cyl, pos=[0, hole_y, BODY_TOP_Z + 0.0002], size=[rosette_r, 0.0002, 0],
                  material="rosette")
    body.add_geom(name="soundhole", type=cyl, pos=[0, hole_y, BODY_TOP_Z + 0.0004], size=[hole_r, 0.0002, 0],
                  material="hole")
    fz = guitar.fretboard_z
    body.add_geom(name="nut", type=box, pos=[0, guitar.nut_y, fz + 0.0015],
                  size=[float(guitar.neck_half_width(guitar.nut_y)) + BOARD_MARGIN, 0.0018, 0.0015],
                  material="bone")
    by = guitar.bridge_y
    body.add_geom(name="bridge", type=box, pos=[0, by - 0.004, BODY_TOP_Z + 0.0045], size=[0.075, 0.014, 0.0045],
                  material="board")
    body.add_geom(name="saddle", type=box, pos=[0, by, guitar.string_z - 0.0045], size=[0.04, 0.0012, 0.0045],
                  material="bone")
    for a, b in guitar.strings:                                      # bridge pins behind the saddle
        body.add_geom(type=sph, pos=[b[0], by - 0.011, BODY_TOP_Z + 0.009], size=[0.0022, 0, 0], material="bone")
    for k in range(1, guitar.n_frets + 1):
        y = guitar.fret_y[k]
        body.add_geom(name=f"fret{k}", type=box, pos=[0, y, fz + 0.0009],
                      size=[float(guitar.neck_half_width(y)) + BOARD_MARGIN, 0.0006, 0.0009], material="metal")
    for k in INLAY_FRETS:
        y = (guitar.fret_y[k] + guitar.fret_y[k - 1]) / 2
        for x in ((-0.007, 0.007) if k == 12 else (0.0,)):
            body.add_geom(type=cyl, pos=[x, y, fz], size=[0.0025, 0.0002, 0], material="bone")
    face_normal = headstock_point(guitar, 0, 0, 1.0) - headstock_point(guitar, 0, 0, 0.0)
    (height, post_radius), (depth, length, radius, knob) = POST, PEG
    for i, ((a, b), post) in enumerate(zip(guitar.strings, tuner_posts(guitar)), start=1):
        body.add_geom(name=f"string{i}", type=cap, fromto=[*a, *b], size=[0.0004 + 0.00012 * i, 0, 0],
                      material="metal")
        body.add_geom(type=cap, fromto=[*a, *post], size=[STRING_EXTRA_RADIUS, 0, 0], material="metal")
        body.add_geom(type=cyl, fromto=[*(post - height * face_normal), *post], size=[post_radius, 0, 0],
                      material="metal")
        shaft = post - (height + depth) * face_normal
        out = np.array([np.sign(post[0]), 0.0, 0.0])
        body.add_geom(type=cap, fromto=[*shaft, *(shaft + length * out)], size=[radius, 0, 0], material="metal")
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_ELLIPSOID, pos=shaft + (length + 2 * radius) * out, size=knob,
                      material="bone")


def _add_hand(spec: mujoco.MjSpec, physics: mujoco.MjModel, prefix: str) -> None:
    """Skin over the physics finger capsules (kept as the phalanges), a rounded palm instead of the two palm
    capsules (the convex hull of blobs at their ends and at the thumb's base) and nails on the dorsal side (+z in
    every finger body: the bodies are axis-aligned with the wrist at zero angles, the palm faces -z)."""
    gid = lambda n: mujoco.mj_name2id(physics, mujoco.mjtObj.mjOBJ_GEOM, prefix + n)  # noqa: E731
    bid = lambda n: mujoco.mj_name2id(physics, mujoco.mjtObj.mjOBJ_BODY, prefix + n)  # noqa: E731
    knuckles = np.asarray([physics.body_pos[bid(f"{f}1")] for f in ("index", "middle", "ring", "pinky")])
    heel = np.mean([capsule_ends(physics, gid(f))[0] for f in ("palm_index", "palm_pinky")], axis=0)
    middle = knuckles[[0, 3]].mean(0)
    heels = [[middle[0] + HEEL_WIDTH * (k[0] - middle[0]), heel[1], heel[2]] for k in knuckles[[0, 3]]]
    back = np.mean([*knuckles, *heels], axis=0) + [0.0, 0.0, BACK_RISE]
    points = [blob(k, KNUCKLE_BLOB) for k in knuckles] + [blob(h, HEEL_BLOB) for h in heels]
    points += [blob(physics.body_pos[bid("thumb1")], THUMB_BLOB), blob(back, BACK_BLOB)]
    spec.delete(spec.geom(prefix + "palm_index"))
    spec.delete(spec.geom(prefix + "palm_pinky"))
    wrist = spec.body(prefix + "wrist")
    _add_mesh(spec, wrist, prefix + "palm", "skin", np.concatenate(points))
    offset, radii = WRIST
    wrist.add_geom(name=prefix + "wrist", type=mujoco.mjtGeom.mjGEOM_ELLIPSOID, pos=heel + offset, size=radii,
                   material="skin")
    for f in ("thumb", "index", "middle", "ring", "pinky"):
        for k in (1, 2, 3):
            spec.geom(f"{prefix}{f}{k}").material = "skin"
        g = gid(f"{f}3")
        joint, tip = capsule_ends(physics, g)
        along = tip - joint
        length, radius = np.linalg.norm(along), physics.geom_size[g, 0]
        across, lengthwise, thick = NAIL
        size = [radius * across, length * lengthwise, radius * thick]
        if abs(along[0]) > abs(along[1]):                               # the thumb points along x
            size[:2] = size[1], size[0]
        pos = tip - along * lengthwise + [0.0, 0.0, radius * NAIL_RISE]
        spec.body(f"{prefix}{f}3").add_geom(name=f"{prefix}{f}_nail", type=mujoco.mjtGeom.mjGEOM_ELLIPSOID,
                                            pos=pos, size=size, material="nail")


def _add_surroundings(spec: mujoco.MjSpec, mirror: bool) -> None:
    target, eye, _ = FRONT_CAMERA
    ahead = guitar_rotation(mirror) @ ((np.asarray(target) - eye) * flip_x(mirror))
    yaw = np.arctan2(ahead[0], -ahead[1])                   # the wall square to the front camera
    _add_mesh(spec, spec.worldbody, "backdrop", "backdrop", *backdrop_mesh()).quat = [np.cos(yaw / 2), 0, 0,
                                                                                        np.sin(yaw / 2)]
    for i, (direction, diffuse) in enumerate(LIGHTS):
        d = np.asarray(direction) * flip_x(mirror)
        spec.worldbody.add_light(name=f"light{i}", type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL,
                                 pos=[0, 0, 2], dir=d / np.linalg.norm(d), diffuse=[diffuse] * 3,
                                 specular=[0.15] * 3, castshadow=False)
    spec.visual.headlight.ambient = [HEADLIGHT[0]] * 3
    spec.visual.headlight.diffuse = [HEADLIGHT[1]] * 3
    spec.visual.headlight.specular = [0.05] * 3
    spec.visual.quality.numslices, spec.visual.quality.numstacks = QUALITY
    body = spec.body("guitar")
    for name, (target, eye, fovy) in (("front", FRONT_CAMERA), ("closeup", CLOSEUP_CAMERA)):
        pos, xyaxes = camera_pose(target, eye, mirror)
        body.add_camera(name=name, pos=pos, xyaxes=xyaxes, fovy=fovy)


def build_stage(scene: str = "duet", *, mirror: bool = False, guitar: Guitar = GUITAR) -> mujoco.MjSpec:
    """The render-only spec of a scene ("left", "right" or "duet"): the physics scene's bodies and joints with
    the stage's geoms, lights and cameras."""
    spec = S.build_spec(scene, mirror=mirror, visual=False, guitar=guitar)
    spec.modelname = spec.modelname.replace("dexguitar_", "dexguitar_stage_")
    spec.compiler.discardvisual = False
    physics = spec.compile()
    g = dataclasses.replace(guitar, mirror=mirror)
    for item in list(spec.body("guitar").geoms) + list(spec.materials):     # the physics scene's guitar
        spec.delete(item)
    _add_materials(spec)
    _add_guitar(spec, g)
    for role in S.SCENES[scene]:
        _add_hand(spec, physics, S.PREFIX[role])
    _add_surroundings(spec, mirror)
    return spec


def stage_model(scene: str = "duet", *, mirror: bool = False) -> mujoco.MjModel:
    """The compiled stage of a scene."""
    return build_stage(scene, mirror=mirror).compile()
