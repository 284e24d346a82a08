"""Rewards in hand-made poses and F1 on hand-made press/pick sequences, values worked out by hand."""
import jax.numpy as jnp
import numpy as np
import pytest

from dexguitar.envs import rewards as R
from dexguitar.world import scoring as M
from dexguitar.world.guitar import GUITAR

MUTE_ALL = jnp.zeros(6, jnp.int32)


def hovering_hand(z=0.05):
    """12 finger parts far above the strings, each 1 cm long along y, lying flat (usable by the lie-flat test)."""
    seg = np.zeros((12, 2, 3), np.float32)
    seg[:, 0] = [0.0, 0.0, z]
    seg[:, 1] = [0.0, -0.01, z]
    return seg


def test_fingertip_on_the_target_point_scores_one():
    goal = jnp.array([0, 0, 5, 0, 0, 0])            # string 3 at fret 5, the rest muted
    seg = hovering_hand()
    p = GUITAR.target_points[2, 5]
    seg[2] = [p + [0, 0, 0.02], p]                  # index tip part ending exactly on p_{3,5}
    press = jnp.array([0, 0, 5, 0, 0, 0])
    cols, correct = R.left_reward(jnp.asarray(seg), goal, press, energy=1.0)
    # Eq. 4: d = 0 -> 0.8 + 0.2 = 1; Eq. 7: 0.8 * 1 + 0.2 * r_correct(1) + 0.05 * 1 = 1.05
    assert float(correct) == 1.0
    assert float(cols[2]) == pytest.approx(1.05, abs=1e-5)
    # muted strings: 0.8 * (0.9 + 0.1 * r_open) + 0.2 + 0.05, and the tip sits ~7 mm from strings 2 and 4
    assert 0.97 < float(cols[1]) < 1.05


def test_target_reward_falls_with_distance():
    goal = jnp.array([0, 0, 5, 0, 0, 0])
    seg = hovering_hand()
    p = GUITAR.target_points[2, 5]
    seg[2] = [p + [0, 0.03, 0.02], p + [0, 0.03, 0.0]]  # 3 cm along the neck from the target
    cols, correct = R.left_reward(jnp.asarray(seg), goal, MUTE_ALL, energy=0.0)
    # d = 0.03: 0.8 exp(-0.9) + 0.2 exp(-0.027) = 0.3253 + 0.1947 = 0.5200; r_correct = 0 -> 0.8 * 0.52 = 0.416
    assert float(correct) == 0.0
    assert float(cols[2]) == pytest.approx(0.8 * 0.5200, abs=2e-3)


def test_finger_resting_on_an_open_string_scores_zero():
    goal = jnp.array([0, 0, -1, 0, 0, 0])            # string 3 must ring open
    seg = hovering_hand()
    a, b = GUITAR.strings[2]
    seg[5] = [a + 0.3 * (b - a), a + 0.35 * (b - a)]  # a middle-finger part lying on string 3
    cols, _ = R.left_reward(jnp.asarray(seg), goal, jnp.array([0, 0, 3, 0, 0, 0]), energy=0.0)
    # Eq. 5: d = 0 -> r_open = 0; pressed where it must be open -> r_correct = 0; column = 0
    assert float(cols[2]) == pytest.approx(0.0, abs=1e-6)


def test_finger_order_examples_of_the_reference():
    def fingers(goal):
        return np.asarray(R.finger_order(jnp.array(goal))).astype(int).tolist()
    # C major (tab 0 1 0 2 3 x, high E first): fret 1 -> index/middle, fret 2 -> middle/ring, fret 3 -> ring/pinky
    c = fingers([-1, 1, -1, 2, 3, 0])
    assert c[1] == [1, 1, 0, 0] and c[3] == [0, 1, 1, 0] and c[4] == [0, 0, 1, 1] and c[0] == [0] * 4
    # F barre 1 1 2 3 3 1: strings 1, 2, 6 are one group at fret 1 -> index/middle
    f = fingers([1, 1, 2, 3, 3, 1])
    assert f[0] == f[1] == f[5] == [1, 1, 0, 0] and f[2] == [0, 1, 1, 0] and f[3] == f[4] == [0, 0, 1, 1]
    # 3 2 3 x x x: the fret-2 string splits the fret-3 strings: string 3 before string 1 (nearer string 6)
    s = fingers([3, 2, 3, 0, 0, 0])
    assert s[1] == [1, 1, 0, 0] and s[2] == [0, 1, 1, 0] and s[0] == [0, 0, 1, 1]
    # five frets cannot be fingered
    assert sum(map(sum, fingers([1, 2, 3, 4, 5, 0]))) == 0


def test_lie_flat_allows_tips_always_and_other_parts_only_when_flat():
    seg = hovering_hand()
    seg[0, 1] = seg[0, 0] + [0, -0.01, 0.002]       # proximal part rising 11 deg: not usable
    seg[2, 1] = seg[2, 0] + [0, -0.01, 0.01]        # tip part at 45 deg: usable (tips always are)
    flat = np.asarray(R.lie_flat(jnp.asarray(seg)))
    assert not flat[0] and flat[1] and flat[2]


def _x_at(string, y):
    return float(GUITAR.string_x(string, y))


# One fingertip lying along x, 3 mm above string 3, in the middle of fret space 5 (the geometry of
# tests/test_detect.py): x = 0.003973, y = 0.074473 between wires 5 (0.060633) and 4 (0.088313); string 2 is
# 7.266 mm from its axis and string 4 7.566 mm.
FRET5_TIP = np.asarray([[[0.003973 - 0.001, 0.074473, 0.0153], [0.003973 + 0.001, 0.074473, 0.0153]]], np.float32)


def margins(goal, seg=FRET5_TIP):
    return np.asarray(R.press_margins(jnp.asarray(seg), jnp.asarray(goal, jnp.int32)))


def test_press_margin_is_the_room_left_to_the_press_distance_and_the_fret_wires():
    # String 3 at fret 5: min(6 - 3 mm, 13.84 mm to either wire) = 3 mm. Strings 2 and 4 open: 7.266 - 6 and
    # 7.566 - 6 mm of clearance. Muted strings: anything goes.
    m = margins([0, -1, 5, -1, 0, 0])
    np.testing.assert_allclose(m[1:4], [0.001266, 0.003, 0.001566], atol=2e-5)
    assert np.isinf(m[[0, 4, 5]]).all()
    # Fret 4 asked: the tip lies 13.84 mm beyond wire 4, over a higher fret (and presses it: 3 mm into the press
    # distance); fret 6 asked: 13.84 mm short of wire 5.
    np.testing.assert_allclose(margins([0, 0, 4, 0, 0, 0])[2], -0.01384, atol=2e-5)
    np.testing.assert_allclose(margins([0, 0, 6, 0, 0, 0])[2], -0.01384, atol=2e-5)
    # 8 mm above the string it presses nothing: 2 mm short of the press distance.
    high = FRET5_TIP.copy()
    high[..., 2] = 0.0123 + 0.008
    np.testing.assert_allclose(margins([0, 0, 5, 0, 0, 0], high)[2], -0.002, atol=2e-5)


def test_margin_reward_is_the_margin_over_3_mm_clipped():
    r = np.asarray(R.margin_reward(jnp.asarray(FRET5_TIP), jnp.asarray([0, -1, 5, -1, 0, 4], jnp.int32)))
    # 1.266 / 3, 3 / 3, 1.566 / 3; muted string 1: 1; string 6 asked at fret 4 with no finger near it: -1.
    np.testing.assert_allclose(r, [1.0, 0.422, 1.0, 0.522, 1.0, -1.0], atol=1e-2)


def test_downward_sweep_over_the_target_strings_succeeds():
    y, z = -0.33, GUITAR.string_z - 0.003
    p0 = jnp.array([_x_at(6, y) - 0.005, y, z])
    p1 = jnp.array([_x_at(4, y) + 0.003, y, z])
    targets = jnp.array([False, False, False, True, True, True])
    none = jnp.zeros(6, bool)
    ready = jnp.ones(6, bool)
    picked, wrong, early, done, ok = R.pick_update(p0, p1, targets, none, jnp.ones(6, bool), ready, 0.001)
    assert np.asarray(picked).tolist() == [False, False, False, True, True, True]
    assert not np.any(np.asarray(wrong)) and np.all(np.asarray(done) == np.asarray(targets))
    assert not np.any(np.asarray(early))
    r = R.pick_reward(picked, wrong, targets, done, ok, ready, R.pick_distances(p1))
    assert float(r) == 1.0                                                    # Eq. 11: r_succ


def test_a_pick_before_the_left_hand_is_ready_is_early_not_a_picking_error():
    # the same stroke in the duet while the left hand does not hold strings 4-6 yet (the strict gate)
    y, z = -0.33, GUITAR.string_z - 0.003
    p0 = jnp.array([_x_at(6, y) - 0.005, y, z])
    p1 = jnp.array([_x_at(4, y) + 0.003, y, z])
    targets = jnp.array([False, False, False, True, True, True])
    picked, wrong, early, done, ok = R.pick_update(p0, p1, targets, jnp.zeros(6, bool), jnp.ones(6, bool),
                                                   jnp.zeros(6, bool), 0.001)
    assert not np.any(np.asarray(wrong))                                      # the right hand picked right ...
    assert np.asarray(early).tolist() == [False, False, False, True, True, True]   # ... before the left hand
    assert np.asarray(ok).tolist() == [True, True, True, False, False, False]  # the reward's clean bits drop
    # the reward treats the early strings as wrong: r_plus = min over them of r_d(distance) < 1
    r = R.pick_reward(picked, wrong | early, targets, done, ok, jnp.zeros(6, bool), R.pick_distances(p1))
    assert float(r) < 0.25


def test_picking_a_non_target_and_skipping_a_target_are_wrong():
    y, z = -0.33, GUITAR.string_z - 0.003
    targets = jnp.array([False, False, False, True, True, True])
    # starting between strings 5 and 4 and sweeping down picks 4, skips 6 and 5 (behind) and also hits 3
    p0 = jnp.array([(_x_at(5, y) + _x_at(4, y)) / 2, y, z])
    p1 = jnp.array([(_x_at(3, y) + _x_at(2, y)) / 2, y, z])
    picked, wrong, early, done, ok = R.pick_update(p0, p1, targets, jnp.zeros(6, bool), jnp.ones(6, bool),
                                                   jnp.ones(6, bool), 0.0)
    assert np.asarray(picked).tolist() == [False, False, True, True, False, False]
    assert np.asarray(wrong).tolist() == [False, False, True, False, True, True]
    r = R.pick_reward(picked, wrong, targets, done, ok, jnp.ones(6, bool), R.pick_distances(p1))
    assert 0.0 < float(r) <= 0.2                                              # Eq. 11-12: min_i r_d <= 0.2


def test_waiting_between_notes_is_r_minus():
    # no target left, pick 1 cm above the strings, all clean: 0.4 * 1 + 0.1 * 6 + 0.5 = 1.5 (Eq. 13)
    p = jnp.array([0.0, -0.33, GUITAR.string_z + 0.01])
    none = jnp.zeros(6, bool)
    r = R.pick_reward(none, none, none, none, jnp.ones(6, bool), jnp.ones(6, bool), R.pick_distances(p))
    assert float(r) == pytest.approx(1.5, abs=1e-5)


def test_energy_terms():
    assert float(R.hand_energy(jnp.zeros(3), jnp.zeros((4, 3)))) == 1.0
    # |v_w| = 0.5, four tips at 1 m/s -> (0.5 + 0.4)^2 = 0.81 -> exp(-0.81)
    v = jnp.array([[1.0, 0, 0]] * 4)
    assert float(R.hand_energy(jnp.array([0.5, 0, 0]), v)) == pytest.approx(np.exp(-0.81), rel=1e-5)
    # pick: v = 0.1 m/s -> exp(-0.2); a = 20 m/s^2 -> 14 * (0.05 * 20)^4 = 14 (cap at 1 is exactly reached)
    assert float(R.pick_energy(jnp.array([0.1, 0, 0]), jnp.zeros(3))) == pytest.approx(np.exp(-0.2), rel=1e-5)
    assert float(R.pick_energy(jnp.zeros(3), jnp.array([40.0, 0, 0]))) == pytest.approx(1 - 14, rel=1e-5)


# ------------------------------------------------------------------------------------------------ metrics

def run_note(goal, presses, picks=None, errors=None, targets=None, tally=None, both="both_now"):
    """The scores of one note ("both" is this note judged within itself unless both="both"), or with
    `tally=True` (scores, the next note's tally)."""
    want_tally, carry = tally is True, tally is not None and tally is not True
    tally = tally if carry else M.empty_tally()
    goal = jnp.asarray(goal)
    for t, press in enumerate(presses):
        pk = None if picks is None else jnp.asarray(picks[t], bool)
        er = None if errors is None else jnp.asarray(errors[t], bool)
        tally = M.update(tally, jnp.asarray(press), goal, pk, er)
    scores, fresh = M.close(tally, len(presses), goal, None if targets is None else jnp.asarray(targets))
    scores = {k: np.asarray(v) for k, v in scores.items()}
    if "both" in scores:
        scores = dict(scores, both=scores[both], previous=scores["both"])
    return (scores, fresh) if carry or want_tally else scores


def test_left_needs_two_thirds_continuous():
    goal = [0, 0, 5, 0, 0, 0]
    on, off = [0, 0, 5, 0, 0, 0], [0, 0, 0, 0, 0, 0]
    # 9 frames: pressed for frames 0-5 (6 >= 2/3 * 9) -> TP, P = R = F1 = 1
    s = run_note(goal, [on] * 6 + [off] * 3)["left"]
    assert s[:3].tolist() == [1.0, 1.0, 1.0]
    # pressed 5 frames, gap, 3 frames: longest run 5 < 6 -> not pressed: P = 0/0 = 1, R = 0 -> F1 = 0
    s = run_note(goal, [on] * 5 + [off] + [on] * 3)["left"]
    assert s[:3].tolist() == [1.0, 0.0, 0.0]


def test_left_wrong_fret_and_extra_string():
    goal = [0, 3, 2, 0, 0, 0]
    # string 2 at fret 3 correct, string 3 at fret 4 (wrong), string 1 (mute, not counted) pressed
    s = run_note(goal, [[7, 3, 4, 0, 0, 0]] * 9)["left"]
    # TP = 1, predicted = non-mute strings pressed = 2, targets = 2 -> P = R = F1 = 0.5
    assert s[:3].tolist() == [0.5, 0.5, 0.5]


def test_right_once_and_only_once():
    goal = [0, 0, -1, -1, -1, 0]
    targets = [False, False, True, True, True, False]
    press = [[0] * 6] * 6
    picks = [[0, 0, 0, 0, 1, 0], [0, 0, 0, 1, 0, 0], [0, 0, 1, 0, 0, 0], [0] * 6, [0, 0, 1, 0, 0, 0], [0] * 6]
    errors = [[0] * 6] * 4 + [[0, 0, 1, 0, 0, 0], [0] * 6]              # string 3 picked twice -> wrong
    s = run_note(goal, press, picks, errors, targets)
    # TP = strings 4, 5; predicted = 3 strings picked; targets 3 -> P = R = F1 = 2/3
    np.testing.assert_allclose(s["right"][:3], [2 / 3, 2 / 3, 2 / 3], rtol=1e-6)


def test_both_hands_need_the_press_at_the_pick_and_after():
    goal = [0, 5, 0, 0, 0, 0]
    targets = [False, True, False, False, False, False]
    pick = [[0, 1, 0, 0, 0, 0]]
    on, off = [0, 5, 0, 0, 0, 0], [0] * 6
    # picked at frame 0 while pressed, held 6 of 9 frames -> correct
    s = run_note(goal, [on] * 6 + [off] * 3, pick + [[0] * 6] * 8, None, targets)
    assert s["both"][2] == 1.0 and s["right"][2] == 1.0
    # picked at frame 0 before the press arrives (frame 1 on): right hand fine, both hands wrong
    s = run_note(goal, [off] + [on] * 8, pick + [[0] * 6] * 8, None, targets)
    assert s["right"][2] == 1.0 and s["both"][2] == 0.0
    # pressed at the pick but released after 4 frames: 4 < 6 -> wrong
    s = run_note(goal, [on] * 4 + [off] * 5, pick + [[0] * 6] * 8, None, targets)
    assert s["both"][2] == 0.0


def test_a_rest_played_as_a_rest_is_perfect():
    s = run_note([0] * 6, [[0] * 6] * 5, [[0] * 6] * 5, None, [False] * 6)
    assert s["left"][2] == s["right"][2] == s["both"][2] == 1.0


def test_the_hold_after_a_late_pick_runs_on_into_the_next_note():
    """Rule (3): the press must be kept for 2/3 of the note's duration after the pick, wherever the note ends. A
    9-frame note of string 2 at fret 5 (need 6 frames), picked at its frame 5: 4 frames of hold inside it."""
    goal, targets = [0, 5, 0, 0, 0, 0], [False, True, False, False, False, False]
    on, off, idle = [0, 5, 0, 0, 0, 0], [0] * 6, [[0] * 6]
    picks = idle * 5 + [[0, 1, 0, 0, 0, 0]] + idle * 3
    first, tally = run_note(goal, [on] * 9, picks, None, targets, tally=True)
    assert first["right"][2] == 1.0 and first["both"][2] == 0.0        # within the note: 4 < 6
    assert np.asarray(tally.prev_need).tolist() == [0, 2, 0, 0, 0, 0]     # 6 - 4 frames still to hold
    # the same chord again: still pressed for its first 2 frames -> the first note was right after all
    second = run_note(goal, [on] * 9, idle * 9, None, [False] * 6, tally=tally, both="both")[0]
    assert second["previous"][:3].tolist() == [1.0, 1.0, 1.0]
    # released after 1 frame of the next note: 5 < 6 frames after the pick -> wrong
    second = run_note(goal, [on] + [off] * 8, idle * 9, None, [False] * 6, tally=tally)[0]
    assert second["previous"][:3].tolist() == [0.0, 0.0, 0.0]
    # the next note asks for another fret on that string: keeping fret 5 for 2 more frames still counts
    second = run_note([0, 7, 0, 0, 0, 0], [on] * 2 + [[0, 7, 0, 0, 0, 0]] * 7, idle * 9, None, [False] * 6,
                      tally=tally)[0]
    assert second["previous"][2] == 1.0 and second["left"][2] == 1.0       # fret 7 held 7 of 9 frames


def test_a_note_with_nothing_open_is_final_at_its_end_and_the_first_note_has_no_previous():
    goal, targets = [0, 5, 0, 0, 0, 0], [False, True, False, False, False, False]
    on, idle = [0, 5, 0, 0, 0, 0], [[0] * 6]
    s, tally = run_note(goal, [on] * 9, [[0, 1, 0, 0, 0, 0]] + idle * 8, None, targets, tally=True)
    assert s["both"][2] == 1.0 and s["previous"][3:].tolist() == [0, 0, 0]   # no note before: no counts
    assert np.asarray(tally.prev_need).sum() == 0 and np.asarray(tally.prev_tp).tolist()[1]
    nxt = run_note(goal, [[0] * 6] * 9, idle * 9, None, [False] * 6, tally=tally)[0]
    assert nxt["previous"][:3].tolist() == [1.0, 1.0, 1.0]                   # released at once: already final


def test_per_note_both_shifts_the_verdicts_to_their_notes():
    both = np.array([[9.0], [1.0], [2.0]])        # at the ends of notes 0, 1, 2: the verdicts of -, 0, 1
    now = np.array([[7.0], [8.0], [3.0]])         # note 2 is the last: its own verdict
    assert M.per_note_both(both, now)[:, 0].tolist() == [1.0, 2.0, 3.0]


def _completions(goal, presses, picks, targets, frames, tally=None):
    """The steps (indices) at which `holds_completed` fires, string by string, over one note; and the next tally."""
    tally = M.empty_tally() if tally is None else tally
    fired = []
    for t, (press, pick) in enumerate(zip(presses, picks)):
        after = M.update(tally, jnp.asarray(press), jnp.asarray(goal), jnp.asarray(pick, bool), None)
        done = np.asarray(M.holds_completed(tally, after, frames, jnp.asarray(targets)))
        fired += [(t, s) for s in np.flatnonzero(done)]
        tally = after
    return fired, M.close(tally, frames, jnp.asarray(goal), jnp.asarray(targets))[1]


def test_hold_completions_fire_once_when_the_both_hands_verdict_becomes_right():
    """The duet's hold reward counts the strings whose rule-(3) hold completes in a step: once per string."""
    goal, targets = [0, 5, 0, 0, 0, 0], [False, True, False, False, False, False]
    on, off, idle, pick = [0, 5, 0, 0, 0, 0], [0] * 6, [0] * 6, [0, 1, 0, 0, 0, 0]
    # 9 frames (need 6): picked at frame 0 while pressed -> held frames 0..5 -> fires at step 5, string 2 (index 1)
    assert _completions(goal, [on] * 9, [pick] + [idle] * 8, targets, 9)[0] == [(5, 1)]
    # released after 4 frames: never
    assert _completions(goal, [on] * 4 + [off] * 5, [pick] + [idle] * 8, targets, 9)[0] == []
    # picked before the press: never
    assert _completions(goal, [off] + [on] * 8, [pick] + [idle] * 8, targets, 9)[0] == []
    # a pick of a string that is no target: never
    assert _completions(goal, [on] * 9, [[1, 0, 0, 0, 0, 0]] + [idle] * 8, targets, 9)[0] == []
    # picked at frame 5: 4 frames inside the note, then 2 of the next -> fires at the next note's step 1
    fired, tally = _completions(goal, [on] * 9, [idle] * 5 + [pick] + [idle] * 3, targets, 9)
    assert fired == []
    assert _completions(goal, [on] * 9, [idle] * 9, [False] * 6, 9, tally)[0] == [(1, 1)]
    assert _completions(goal, [on] + [off] * 8, [idle] * 9, [False] * 6, 9, tally)[0] == []


# ----------------------------------------------------------------------------------------------- r_contact (Eq. 15)

# joint offsets from the home pose (rad, right-hand convention) and whether MuJoCo C's collision detection then reports
# a thumb3-index contact: home leaves a 0.98 mm gap to index3; thumb3 flexed 0.3 sinks it ~1.9 mm into index3; thumb2
# flexed 0.3 into both index2 and index3; thumb1_z opened 0.3 takes it ~3 cm away
GRIP_POSES = {"home": ({}, False), "thumb3 bent in": ({"thumb3": -0.3}, True),
              "thumb2 bent in": ({"thumb2": -0.3}, True), "thumb opened": ({"thumb1_z": 0.3}, False)}


@pytest.mark.parametrize("scene, mirror", [("right", False), ("duet", True)])
def test_thumb_index_contact_agrees_with_mujoco_collision_detection(scene, mirror):
    import mujoco

    from dexguitar import mjx as quiet_mjx
    from dexguitar.envs import EnvConfig
    from dexguitar.envs.core import CONTACT_TOL
    from dexguitar.envs.duet import DuetEnv
    from dexguitar.envs.right import RightEnv
    from dexguitar.music import timeline as TL
    from dexguitar.music.song import Song, make_note
    from dexguitar.world import hands as H

    mjx = quiet_mjx()
    song = TL.from_song(Song(100, (make_note("1/4", [-1, 0, -1, -1, -1, -1]),), "one"))
    env = (RightEnv if scene == "right" else DuetEnv)(song, EnvConfig(physics="jax", mirror=mirror))
    m, d = env.model, mujoco.MjData(env.model)
    thumb, index2, index3 = (int(g) for g in env._grip_geoms)
    assert [m.geom(g).name for g in (thumb, index2, index3)] == ["rh_thumb3", "rh_index2", "rh_index3"]
    names = [j.name for j in H.joints("right")]
    qadr = np.asarray(env.hands[env.roles.index("right")].qpos)
    for pose, (offsets, touching) in GRIP_POSES.items():
        delta = np.zeros(len(names))
        for joint, v in offsets.items():
            delta[names.index(joint)] = v
        if mirror:
            delta = H.mirror_qpos(delta, side_from="right")
        d.qpos[:] = m.key_qpos[0]
        d.qpos[qadr] += delta
        mujoco.mj_forward(m, d)
        # the oracle: MuJoCo C's own collision detection, and its own geom distances
        c_contact = any({int(c.geom1), int(c.geom2)} in ({thumb, index2}, {thumb, index3})
                        for c in d.contact[:d.ncon])
        c_gaps = [mujoco.mj_geomDistance(m, d, thumb, g, 0.1, None) for g in (index2, index3)]
        assert c_contact == touching, pose                                 # the pose does what it says
        data = mjx.put_data(m, d)
        gaps = np.asarray(env.thumb_index_gaps(data))
        np.testing.assert_allclose(gaps, c_gaps, atol=2e-5, err_msg=pose)
        assert min(c_gaps) < -5e-4 if touching else min(c_gaps) > 3 * CONTACT_TOL, pose  # clear of the tolerance
        assert float(env.thumb_index_contact(data)) == float(touching), pose
