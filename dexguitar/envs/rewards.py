"""Rewards of the paper as pure functions of guitar-frame geometry (Sec. 5, Eq. 3-16).

Every constant is written beside its equation. Where the authors' code and the paper differ (reference §12) we
follow the paper, except where the difference is needed to learn; those places say so.
"""
from __future__ import annotations

import jax.numpy as jnp

from dexguitar.world import detect
from dexguitar.world.geometry import LEN2_EPS, point_segment_distance
from dexguitar.world.guitar import GUITAR, N_STRINGS, PRESS_DISTANCE, Guitar
from dexguitar.world.hands import FINGERS

N_FINGERS = len(FINGERS)
SIN_5_DEG = 0.0871557         # lie-flat test: a proximal or middle part may press if it is within 5 deg of the board
OPEN_DISTANCE = 0.007         # Eq. 5 normalization (finger radius ~6 mm)
PICK_CLEARANCE = 0.003        # Eq. 13: the pick rests at least 3 mm from every string


# ----------------------------------------------------------------------------------------------- left hand

def lie_flat(segments):
    """bool (12,): which finger parts may press. The tip part always may; the others only when they lie within 5 deg
    of the fretboard plane (paper Sec. 5.1: |angle| < 5 deg; the authors' code tests one side only)."""
    d = segments[:, 1] - segments[:, 0]
    sin = jnp.abs(d[:, 2]) / jnp.maximum(jnp.linalg.norm(d, axis=-1), 1e-9)
    tip = (jnp.arange(segments.shape[0]) % 3) == 2
    return tip | (sin < SIN_5_DEG)


def finger_order(goal):
    """bool (6, 4): fingers (index..pinky) allowed to press each target string (Fig. 4, reference §5.1).

    Target strings at one fret form a group unless a string between them is open or pressed at a lower fret. Groups
    are ranked by fret (at one fret, the group nearer string 6 first). With G groups, the group of rank r may use
    fingers r .. r + 4 - G: fingers never cross and each presses one fret; more than 4 groups leaves none.
    """
    g = goal
    target = g > 0
    i = jnp.arange(N_STRINGS)
    lo, hi = jnp.minimum(i[:, None], i[None, :]), jnp.maximum(i[:, None], i[None, :])
    between = (i[None, None, :] > lo[:, :, None]) & (i[None, None, :] < hi[:, :, None])       # [a, b, m]
    blocker = (g[None, :] == -1) | ((g[None, :] > 0) & (g[None, :] < g[:, None]))           # [a, m]
    blocked = jnp.any(between & blocker[:, None, :], axis=-1)                                 # [a, b]
    same = target[:, None] & (g[:, None] == g[None, :]) & ~blocked                           # includes a == b
    rep = jnp.max(jnp.where(same, i[None, :], -1), axis=1)                  # group id: its string nearest string 6
    is_rep = target & (rep == i)
    n_groups = jnp.sum(is_rep)
    key = g * 8 + (N_STRINGS - 1 - i)                                       # fret first, then nearer string 6
    rank = jnp.sum(is_rep[None, :] & (key[None, :] < key[rep][:, None]), axis=1)
    f = jnp.arange(N_FINGERS)
    ok = (f[None, :] >= rank[:, None]) & (f[None, :] <= rank[:, None] + N_FINGERS - n_groups)
    return target[:, None] & ok & (n_groups <= N_FINGERS)


def left_reward(segments, goal, press, energy, guitar: Guitar = GUITAR):
    """Columns (6,) of Eq. 7 for one control step, plus r_correct.

    segments: (12, 2, 3) finger parts index..pinky (guitar frame); goal: int (6,) k>0 press fret k, -1 open, 0 mute;
    press: int (6,) detected frets; energy: Eq. 8 value in [0, 1].
    """
    targets = jnp.asarray(guitar.target_points, jnp.float32)[jnp.arange(N_STRINGS), jnp.clip(goal, 0, None)]
    d2, _ = point_segment_distance(targets[:, None, :], segments[None, :, 0], segments[None, :, 1])  # (6, 12)
    usable = finger_order(goal)[:, jnp.arange(12) // 3] & lie_flat(segments)[None, :]
    d2 = jnp.min(jnp.where(usable, d2, jnp.inf), axis=1)
    r_press = 0.8 * jnp.exp(-1000.0 * d2) + 0.2 * jnp.exp(-30.0 * d2)                  # Eq. 4
    r_open = jnp.minimum((detect.string_distances(segments, guitar) / OPEN_DISTANCE) ** 2, 1.0)  # Eq. 5 (code: ^4)
    r_mute = 0.9 + 0.1 * r_open                                                          # Eq. 6
    r_string = jnp.where(goal > 0, r_press, jnp.where(goal < 0, r_open, r_mute))        # Eq. 3
    ok = jnp.where(goal > 0, press == goal, jnp.where(goal < 0, press == 0, True))
    r_correct = jnp.all(ok).astype(jnp.float32)
    # Eq. 7. The paper writes "- 0.05 r_energy", which would reward motion since r_energy = 1 when still; the
    # authors' code adds it, which is what makes it an energy term (needed to learn).
    return 0.8 * r_string + 0.2 * r_correct + 0.05 * energy, r_correct


def press_margins(segments, goal, guitar: Guitar = GUITAR, threshold: float = PRESS_DISTANCE):
    """(6,) signed room (m) by which each string's detected fret is its goal's: positive when `pressed_frets` gives the
    goal and would still give it were any finger axis moved by less than this, negative by how far it is from it.

    Press fret k: the best segment's least of (threshold - its distance) and its distance inside fret space k, against
    every segment over a higher fret staying clear of the threshold (the highest fret wins). Open: every segment over
    the fretboard clear of the threshold. Mute: +inf (anything goes).
    """
    dist2, y = detect.string_contacts(segments, guitar)                   # (S, 6)
    dist = jnp.sqrt(jnp.maximum(dist2, LEN2_EPS))
    frets = detect.fret_at(y, guitar)                                     # (S, 6)
    wires = jnp.asarray(guitar.fret_y, y.dtype)                           # (n_frets + 1,), decreasing
    k = jnp.clip(goal, 1, guitar.n_frets)[None, :]                        # (1, 6)
    inside = jnp.minimum(wires[k - 1] - y, y - wires[k])                  # (S, 6) > 0 within fret space k
    press = jnp.max(jnp.minimum(threshold - dist, inside), axis=0)
    clear = dist - threshold
    higher = jnp.min(jnp.where(frets > k, clear, jnp.inf), axis=0)
    opened = jnp.min(jnp.where(frets > 0, clear, jnp.inf), axis=0)
    return jnp.where(goal > 0, jnp.minimum(press, higher), jnp.where(goal < 0, opened, jnp.inf))


MARGIN_SCALE = 0.003          # m: the margin reward is linear in a string's press margin up to 3 mm either way


def margin_reward(segments, goal, guitar: Guitar = GUITAR):
    """(6,) in [-1, 1]: each string's `press_margins` over MARGIN_SCALE, clipped; 1 for a muted string.

    Not in the paper. Eq. 4's press term is flat within millimetres of its target (exp(-1000 d^2) is 0.98 at 4 mm)
    and r_correct is a step, so nothing in Eq. 7 pays for playing a note with room to spare, where the IK planner
    leaves under 1 mm in 2-38 % of its held presses. It did not make PPO improve the planner (docs/results.md, "The
    learned hands")."""
    return jnp.clip(press_margins(segments, goal, guitar) / MARGIN_SCALE, -1.0, 1.0)


PLAN_WRIST_SCALE = 0.02       # m: the planned-wrist reward is exp(-1) at 2 cm from the planned hand position


def plan_wrist_reward(slides, planned_slides):
    """() in (0, 1]: exp(-(d / PLAN_WRIST_SCALE)^2), d the distance of the wrist's three slide joints (the hand's
    position) from the planner's.

    Not in the paper. A hand trained from its home pose by Eq. 7 alone learns last the notes far from home (frets
    1-3, docs/results.md); the planner's hand position says where on the neck each note is played, and unlike the
    planner's actions (a controller's output that a student cannot predict closely enough to play) it is a smooth
    function of the notes. The fingers, and with them the choice of finger, stay with Eq. 3-7."""
    return jnp.exp(-jnp.sum((slides - planned_slides) ** 2) / PLAN_WRIST_SCALE ** 2)


def hand_energy(wrist_velocity, tip_velocities):
    """Eq. 8: exp(-(|v_w| + 0.1 sum_f |v_f|)^2); fingertip velocities relative to the wrist, in its frame."""
    speed = jnp.linalg.norm(wrist_velocity) + 0.1 * jnp.sum(jnp.linalg.norm(tip_velocities, axis=-1))
    return jnp.exp(-speed ** 2)


# ----------------------------------------------------------------------------------------------- right hand

def r_distance(d):
    """Eq. 12: shaped by the pick's distance to a string, sensitive from millimetres to decimetres."""
    return 0.175 * jnp.exp(-1e4 * d ** 2) + 0.025 * jnp.exp(-2e3 * d ** 2)


def pick_distances(pick, guitar: Guitar = GUITAR):
    """(6,) distance from the pick point to every string."""
    s = jnp.asarray(guitar.strings, jnp.float32)
    d2, _ = point_segment_distance(pick[None, :], s[:, 0], s[:, 1])
    return jnp.sqrt(d2)


def pick_update(p_prev, p_now, targets, done, ok, ready, depth, guitar: Guitar = GUITAR):
    """Picking bookkeeping of one control step (Sec. 5.2).

    targets: strings to pick in this note; done: already picked (or skipped); ok: no error so far in the note (for
    the reward); ready: duet gate (all True for the right hand alone). A string is tackled wrongly when it is picked
    but was not a target still to pick (a non-target, a repeat, or too shallow: `depth` below the string, training
    only), or when it is a remaining target that the pick swept past while picking others (consistent order).
    A target picked before the left hand holds it (`ready` False) is `early`: wrong for the duet's cooperative
    reward, but not a picking error of the right hand: the paper's right-hand F1 judges the picking alone and
    both-hands F1 judges the timing (`scoring.close`).
    Returns picked, wrong, early, done, ok.
    """
    crossed = detect.pick_crossings(p_prev, p_now, guitar, 0.0).picked
    valid = detect.pick_crossings(p_prev, p_now, guitar, depth).picked
    correct = valid & targets & ~done
    wrong = crossed & ~correct
    early = correct & ~ready
    sweep = jnp.sign((p_now[0] - p_prev[0]) * guitar.sign)                 # +1 toward string 1 (down)
    x_at = guitar.sign * jnp.asarray(_string_x(guitar, p_now[1]))
    behind = (x_at - guitar.sign * p_now[0]) * sweep < 0                    # the pick has moved past the string
    skipped = targets & ~done & ~crossed & behind & jnp.any(crossed) & (sweep != 0)
    bad = wrong | skipped | early
    return crossed, wrong | skipped, early, done | correct | skipped | (crossed & targets), ok & ~bad


def _string_x(guitar: Guitar, y):
    s = jnp.asarray(guitar.strings, jnp.float32)
    t = (y - s[:, 0, 1]) / (s[:, 1, 1] - s[:, 0, 1])
    return s[:, 0, 0] + t * (s[:, 1, 0] - s[:, 0, 0])


def pick_reward(picked, wrong, targets, done, ok, ready, distances):
    """r_pick of Eq. 10 given the state after this step's `pick_update` (`wrong` includes early picks)."""
    r_plus = jnp.where(jnp.any(wrong), jnp.min(jnp.where(wrong, r_distance(distances), 1.0)), 1.0)   # Eq. 11
    remaining = targets & ~done & ready
    idx = jnp.arange(N_STRINGS)
    top = jnp.min(jnp.where(remaining, idx, N_STRINGS - 1))
    bottom = jnp.max(jnp.where(remaining, idx, 0))
    # Eq. 14 writes min over top and bottom, its prose "the nearest top or bottom-most target"; max is the prose
    # (and the authors' code): reward approaching either end of the strum.
    r_cross = 0.2 + 2.0 * jnp.maximum(r_distance(distances[top]), r_distance(distances[bottom]))
    clean = ok & (done | ~targets)                          # r_i of Eq. 13: picked correctly / left alone
    r_minus = (0.4 * jnp.minimum(jnp.min(distances) / PICK_CLEARANCE, 1.0)
               + 0.1 * jnp.sum(clean) + 0.5 * jnp.all(clean))                           # Eq. 13
    # A not-ready target (duet) counts as no target: the r- case of Eq. 10.
    return jnp.where(jnp.any(picked), r_plus, jnp.where(jnp.any(remaining), r_cross, r_minus))


def pick_energy(v_pick, a_pick):
    """Eq. 16: exp(-20 |v|^2) - 14 |0.05 a|^4. The acceleration term is capped at 1 (as in the authors' code):
    unbounded it reaches -400 for a 100 m/s^2 flick and swamps every other reward (needed to learn)."""
    return jnp.exp(-20.0 * jnp.sum(v_pick ** 2)) - 14.0 * jnp.minimum(jnp.sum((0.05 * a_pick) ** 2) ** 2, 1.0)


def right_reward(r_pick, contact, hand_energy_, pick_energy_):
    """Eq. 15: r_pick + 0.05 r_contact + 0.05 (r_energy + r_pick_energy)."""
    return r_pick + 0.05 * contact + 0.05 * (hand_energy_ + pick_energy_)


# ----------------------------------------------------------------------------------------------- termination

def left_failed(wrist, segments, thumb_tip, guitar: Guitar = GUITAR):
    """Reference §3.7: the wrist outside its box, a finger wrapped far behind the neck, a fingertip sunk into the
    neck, or the thumb over the treble side of the neck (guitar frame)."""
    x = wrist[0] * guitar.sign
    out_of_box = (x < -0.1) | (x > 0.3) | (wrist[1] < -0.3) | (wrist[1] > 0.3) | (wrist[2] < -0.2) | (wrist[2] > 0.05)
    deep = jnp.any(segments[..., 2] < -0.07)
    tips = segments[2::3, 1]
    sunk = jnp.any((jnp.abs(tips[:, 0]) < 0.024) & (tips[:, 2] < guitar.fretboard_z - 0.003) & (tips[:, 2] > -0.008))
    return out_of_box | deep | sunk | (thumb_tip[0] * guitar.sign > 0.07)


def right_failed(points, guitar: Guitar = GUITAR):
    """Reference §3.7: any link or fingertip of the picking hand outside its box (guitar frame)."""
    x = points[:, 0] * guitar.sign
    return jnp.any((x < -0.3) | (x > 0.3) | (points[:, 1] < -0.6) | (points[:, 1] > 0.0)
                   | (points[:, 2] < -0.1) | (points[:, 2] > 0.3))
