"""The two hands: link names, DoF order, finger segments and the MJCF writer for `models/*_hand.xml`.

Each hand has 16 links and 27 DoF: the wrist (3 slides + 3 hinges relative to the guitar), the thumb (MCP 3 + IP 1
+ 1) and four fingers (MCP 2 + PIP 1 + DIP 1). Finger segments are capsules between joint centres (the paper's
"cylinder parts"), so press detection and rewards can use the same axis segments the physics collides with.
Dimensions, joint ranges, masses and PD gains follow the authors' MPL-based models (reference §2).

The right hand is written out here; the left hand is its mirror image across the hand's x = 0 plane: positions
get x negated, hinges about y or z get their ranges negated (an axial vector flips those components under a
reflection), hinges about x keep them. All hand bodies are axis-aligned at zero joint angles, which keeps this
mirror exact, so a left-handed player's scene is the same machinery with the hands swapped.

Regenerate the MJCF with `python -m dexguitar.world.hands` (a test checks the files are up to date).
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

MODELS_DIR = Path(__file__).resolve().parents[2] / "models"
FINGERS = ("index", "middle", "ring", "pinky")
KEY_LINKS = ("wrist", "thumb1", "thumb2", "thumb3") + tuple(f"{f}{k}" for f in FINGERS for k in (1, 2, 3))
N_DOF = 27
WRIST_DOF = 6                # the joints start with the wrist's 3 slides and 3 hinges (`joints`), then 21 fingers'

# PD gains and joint armature (reference §2.2): kp = 10 everywhere, kd = 0.4 on the wrist, 0.2 on fingers.
KP = 10.0
KD_WRIST = 0.4
KD_FINGER = 0.2
ARMATURE = 0.01
WRIST_MASS = 0.147           # wrist + palm of the MPL model, kg

# Right-hand geometry in the hand frame (fingers along -y, palm facing -z, thumb toward +x); metres.
# MCP centres = palm offset (0.025, 0, 0.006934) + the finger's offset from the palm (reference §2.1).
PALM = np.array([0.025, 0.0, 0.006934])
MCP = {
    "thumb": PALM + [-0.000561, -0.016681, -0.008512],
    "index": PALM + [0.00843, -0.071250, 0.003268],
    "middle": PALM + [-0.012834, -0.075001, 0.00708],
    "ring": PALM + [-0.034098, -0.069156, 0.003114],
    "pinky": PALM + [-0.053317, -0.060683, -0.005084],
}
# Segment lengths proximal, middle, distal (joint centre to joint centre; the last ends at the fingertip).
LENGTHS = {
    "thumb": (0.043057, 0.037597, 0.036110),
    "index": (0.043390, 0.025914, 0.019169),
    "middle": (0.045774, 0.029999, 0.023868),
    "ring": (0.043062, 0.027877, 0.021533),
    "pinky": (0.033165, 0.022145, 0.016532),
}
RADII = {  # capsule radii; ~6 mm as the paper's finger parts (Eq. 5 normalizes by 0.007)
    "thumb": (0.0075, 0.007, 0.0065),
    "index": (0.0065, 0.006, 0.006),
    "middle": (0.0065, 0.006, 0.006),
    "ring": (0.0065, 0.006, 0.006),
    "pinky": (0.006, 0.0055, 0.0055),
}
MASSES = {  # kg, from the MPL inertials
    "thumb": (0.00596, 0.0060, 0.0060),
    "index": (0.00478, 0.00345, 0.00274),
    "middle": (0.00478, 0.00345, 0.00274),
    "ring": (0.00478, 0.00345, 0.00274),
    "pinky": (0.00341, 0.00251, 0.00273),
}
# Right-hand joint ranges (rad); the left hand negates the y/z hinge ranges.
FINGER_RANGES = {
    "index": ((-0.698132, 1.5708), (-0.523599, 0.523599)),
    "middle": ((-0.698132, 1.5708), (-0.349066, 0.349066)),
    "ring": ((-0.698132, 1.5708), (-0.349066, 0.349066)),
    "pinky": ((-0.698132, 1.5708), (-0.698132, 0.349066)),
}
PIP_RANGE = (0.0, 1.5708)
DIP_RANGE = (-0.0872665, 1.5708)
THUMB_RANGES = {"thumb1_x": (0.0, 0.698132), "thumb1_y": (0.0, 1.5708), "thumb1_z": (-1.5708, 0.0),
                "thumb2": (-1.5708, 0.0), "thumb3": (-1.5708, 0.0872665)}
WRIST_HINGE_RANGE = (-3.14159, 3.14159)
# Wrist slide ranges in the guitar frame: the workspace of each hand (a bit larger than the authors' termination
# boxes, reference §3.7), so that a PD target inside the range is a reachable wrist position.
WRIST_SLIDE_RANGES = {
    "left": ((-0.15, 0.30), (-0.35, 0.35), (-0.20, 0.10)),
    "right": ((-0.30, 0.30), (-0.65, 0.05), (-0.10, 0.30)),
}
PICK_OFFSET = (0.007, -0.048, -0.005)   # pick point in the right index2 frame (reference §2.1)


@dataclasses.dataclass(frozen=True)
class Joint:
    name: str
    kind: str        # "slide" or "hinge"
    axis: str        # "x", "y" or "z"
    range: tuple[float, float]
    damping: float


def joints(side: str, role: str | None = None) -> tuple[Joint, ...]:
    """The 27 joints of one hand in DoF (= action) order, with ranges for that side. The wrist slides span the
    workspace of the hand's role (fretting = "left", picking = "right"); a hand playing the other side's role (the
    mirrored, left-handed setup) gets that role's workspace mirrored in x."""
    role = role or side
    slides = WRIST_SLIDE_RANGES[role]
    if role != side:
        slides = ((-slides[0][1], -slides[0][0]),) + slides[1:]
    def hinge(name, axis, rng, kd=KD_FINGER):
        if side == "left" and axis in "yz":
            rng = (-rng[1], -rng[0])
        return Joint(name, "hinge", axis, tuple(rng), kd)

    out = [Joint(f"wrist_t{a}", "slide", a, slides[i], KD_WRIST) for i, a in enumerate("xyz")]
    out += [hinge(f"wrist_r{a}", a, WRIST_HINGE_RANGE, KD_WRIST) for a in "xyz"]
    out += [hinge(f"thumb1_{a}", a, THUMB_RANGES[f"thumb1_{a}"]) for a in "xyz"]
    out += [hinge("thumb2", "z", THUMB_RANGES["thumb2"]), hinge("thumb3", "z", THUMB_RANGES["thumb3"])]
    for f in FINGERS:
        out += [hinge(f"{f}1_x", "x", FINGER_RANGES[f][0]), hinge(f"{f}1_z", "z", FINGER_RANGES[f][1]),
                hinge(f"{f}2", "x", PIP_RANGE), hinge(f"{f}3", "x", DIP_RANGE)]
    assert len(out) == N_DOF
    return tuple(out)


def mirror_qpos(qpos: np.ndarray, side_from: str = "left") -> np.ndarray:
    """Joint values of the mirror-image pose in the other hand's model: slide x and hinges about y/z change sign."""
    sign = np.array([-1.0 if (j.kind == "slide" and j.axis == "x") or (j.kind == "hinge" and j.axis in "yz")
                     else 1.0 for j in joints(side_from)])
    return np.asarray(qpos) * sign


def _fmt(v) -> str:
    return " ".join(f"{float(x):.6g}" for x in np.atleast_1d(v))


def hand_xml(side: str, role: str | None = None) -> str:
    """MJCF of one hand, to be attached to the guitar body (joints relative to the guitar frame). Names carry no
    prefix: the scene builder adds one per role. The picking role (default: the right hand) holds the pick."""
    if side not in ("left", "right"):
        raise ValueError(f"hand side must be 'left' or 'right', got {side!r}")
    role = role or side
    p = ""
    mx = np.array([-1.0, 1.0, 1.0]) if side == "left" else np.ones(3)
    js = {j.name: j for j in joints(side, role)}

    def joint(name, ind):
        j = js[name]
        axis = {"x": "1 0 0", "y": "0 1 0", "z": "0 0 1"}[j.axis]
        return (f'{ind}<joint name="{p}{j.name}" type="{j.kind}" axis="{axis}" '
                f'range="{_fmt(j.range)}" damping="{j.damping:g}"/>')

    lines = [f'<mujoco model="{side}_hand">',
             '  <!-- Written by dexguitar.world.hands; regenerate with `python -m dexguitar.world.hands`. -->',
             '  <compiler angle="radian"/>',
             '  <default>',
             '    <default class="hand">',
             f'      <joint armature="{ARMATURE:g}" limited="true"/>',
             '      <geom type="capsule" contype="1" conaffinity="0" condim="3" friction="1 0.05 0.05" '
             'rgba="0.85 0.68 0.58 1" group="2"/>',
             f'      <position kp="{KP:g}" ctrllimited="true"/>',
             '    </default>',
             '  </default>',
             '  <worldbody>',
             f'    <body name="{p}wrist" childclass="hand">']
    ind = "      "
    for a in "xyz":
        lines.append(joint(f"wrist_t{a}", ind))
    for a in "xyz":
        lines.append(joint(f"wrist_r{a}", ind))
    # Palm: two capsules from the heel of the hand to the index and pinky knuckles.
    for f, heel in (("index", PALM + [-0.003, -0.012, 0.0]), ("pinky", PALM + [-0.03, -0.012, 0.0])):
        knuckle = MCP[f] + [0.006 if f == "index" else 0.0, 0.012, 0.0]
        lines.append(f'{ind}<geom name="{p}palm_{f}" fromto="{_fmt(mx * heel)} {_fmt(mx * knuckle)}" size="0.013" '
                     f'mass="{WRIST_MASS / 2:.4g}"/>')
    for f in ("thumb",) + FINGERS:
        lines += _finger_xml(p, f, role == "right", mx, joint, ind)
    lines.append("    </body>")
    lines += ["  </worldbody>", "  <contact>"]
    if role == "right":
        # The pick is held between thumb and index: their contact is the one self-contact we keep (Eq. 15).
        for a, b in (("thumb3", "index2"), ("thumb3", "index3")):
            lines.append(f'    <pair geom1="{p}{a}" geom2="{p}{b}" condim="3"/>')
    lines.append("  </contact>")
    lines.append("  <actuator>")
    for j in joints(side, role):
        lines.append(f'    <position name="{p}{j.name}" class="hand" joint="{p}{j.name}" ctrlrange="{_fmt(j.range)}"/>')
    lines += ["  </actuator>", "</mujoco>", ""]
    return "\n".join(lines)


def _finger_xml(p, f, picking, mx, joint, ind):
    if f == "thumb":
        direction = np.array([1.0, 0.0, 0.0]) * mx          # the thumb points sideways at zero angles
        names = (("thumb1_x", "thumb1_y", "thumb1_z"), ("thumb2",), ("thumb3",))
    else:
        direction = np.array([0.0, -1.0, 0.0])               # fingers point along -y
        names = ((f"{f}1_x", f"{f}1_z"), (f"{f}2",), (f"{f}3",))
    lines = []
    for k in range(3):
        pos = mx * MCP[f] if k == 0 else direction * LENGTHS[f][k - 1]
        lines.append(f'{ind + "  " * k}<body name="{p}{f}{k + 1}" pos="{_fmt(pos)}">')
        d = ind + "  " * (k + 1)
        lines += [joint(n, d) for n in names[k]]
        end = direction * LENGTHS[f][k]
        lines.append(f'{d}<geom name="{p}{f}{k + 1}" fromto="0 0 0 {_fmt(end)}" size="{RADII[f][k]}" '
                     f'mass="{MASSES[f][k]}"/>')
        if k == 2:
            lines.append(f'{d}<site name="{p}{f}_tip" pos="{_fmt(end)}" size="0.002"/>')
        if f == "index" and k == 1 and picking:
            lines.append(f'{d}<site name="{p}pick" pos="{_fmt(mx * PICK_OFFSET)}" size="0.003" rgba="0.1 0.1 0.1 1"/>')
    lines += [f'{ind + "  " * k}</body>' for k in range(2, -1, -1)]
    return lines


def write_models(directory: Path = MODELS_DIR) -> list[Path]:
    paths = []
    for side in ("left", "right"):
        path = Path(directory) / f"{side}_hand.xml"
        path.write_text(hand_xml(side))
        paths.append(path)
    return paths


if __name__ == "__main__":
    for path in write_models():
        print("wrote", path)
