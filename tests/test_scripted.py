"""The scripted player through the envs: hand-made motions that put fingertips on the press targets and sweep the pick
across the target strings must score F1 ~ 1, or geometry, detection, bookkeeping and metrics disagree somewhere."""
import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from dexguitar import envs
from dexguitar.planner import plans as FF
from dexguitar.planner import Notes, ScriptedLeft, ScriptedRight
from dexguitar.planner.left import BARRE, BARRE_POSITIONS, FINGER_DOFS, PAIR, WRIST_THUMB
from dexguitar.perform.scripted import ScriptedPlayer
from dexguitar.music import timeline as TL
from dexguitar.music.song import Song, make_note
from dexguitar.world import detect

# (string, fret) single notes in first position: open strings, same-string steps up and down, string changes,
# strings 1 to 6. An open string first: from the home pose (hand at fret 5) the hand needs ~10 frames to get there.
MELODY = [(1, 0), (2, 1), (2, 3), (1, 0), (1, 1), (1, 3), (1, 1), (2, 0), (3, 2), (3, 0), (4, 3), (5, 3), (6, 1),
          (4, 2), (2, 1)]


def melody() -> Song:
    notes = []
    for j, (string, fret) in enumerate(MELODY):
        frets = [-1] * 6
        frets[string - 1] = fret
        notes.append(make_note("1/4" if j == 0 else "1/8", frets))   # eighths at 120 BPM: 15 frames
    return Song(tempo=120, notes=tuple(notes), title="scripted test melody")


@pytest.fixture(scope="module")
def timeline():
    return TL.from_song(melody())


def play(hand, timeline):
    env = envs.make(hand, [timeline], envs.EnvConfig().evaluation())
    result = ScriptedPlayer(env).play(0)
    assert result["closed"] == len(MELODY) == result["notes"]         # every note closed exactly once
    assert result["terminated_at"] is None
    return result[hand]


def test_scripted_left_hand_presses_every_note(timeline):
    score = play("left", timeline)
    assert score["f1"] >= 0.95, score["per_note"]
    assert score["precision"] >= 0.95                                 # open strings left alone


def test_scripted_right_hand_picks_every_note(timeline):
    score = play("right", timeline)
    assert score["f1"] >= 0.95, score["per_note"]


def test_a_longer_song_plays_the_program_compiled_for_the_first(timeline, monkeypatch):
    """The rollout's songs (re-batched to fixed capacities), actions (in a buffer of a power of two steps) and step
    count are its arguments: a song with more notes and frames plays the first song's compiled program."""
    from dexguitar.perform import scripted
    monkeypatch.setattr(scripted, "_ROLLOUTS", {})
    first = ScriptedPlayer(envs.make("left", [timeline], envs.EnvConfig().evaluation())).play(0)
    song = melody()
    longer = TL.from_song(dataclasses.replace(song, notes=song.notes + song.notes[1:6]))
    second = ScriptedPlayer(envs.make("left", [longer], envs.EnvConfig().evaluation())).play(0)
    assert (first["notes"], second["notes"]) == (15, 20) and second["frames"] == first["frames"] + 5 * 15
    (program,) = scripted._ROLLOUTS.values()
    assert program._cache_size() == 1                 # traced and compiled once, for both songs
    assert second["closed"] == 20 and second["left"]["f1"] >= 0.95


def test_fingering_one_finger_per_fret(timeline):
    left = ScriptedLeft()
    plan = left.fingering(Notes(np.asarray(timeline.left), np.asarray(timeline.pick), np.asarray(timeline.onset)))
    assert {p for p, _ in plan} == {1}                                 # frets 1-3: first position throughout
    for i, ((p, fingers), (string, fret)) in enumerate(zip(plan, MELODY)):
        rule = {fret - p: (string - 1, fret)} if fret > 0 else {}
        assert {f: v for f, v in fingers.items() if f in rule} == rule
        # in the trill 1-3-1 on string 1 (notes 4-6) the index stays down on fret 1 under the 3 (`anchored`)
        assert {f: v for f, v in fingers.items() if f not in rule} == ({0: (0, 1)} if i == 5 else {})


def test_pick_strokes_alternate_on_one_string(timeline):
    notes = Notes(np.asarray(timeline.left), np.asarray(timeline.pick), np.asarray(timeline.onset))
    way = [np.sign(s.end - s.start) for s in ScriptedRight().sweeps(notes)[0]]
    assert len(way) == len(MELODY)
    # notes 4-6 repeat string 1: down, up, down (or the reverse)
    assert way[4] == -way[5] == way[6]


def fast_lines() -> Song:
    """8-frame notes (sixteenths at 112.5 BPM): a string-crossing figure as in `capriccio_op59_no16`, a tremolo on
    one string, and an arpeggio from string 6 up to 2 and back to 4, as in `prelude1_in_c_major_chords`."""
    def single(string):
        frets = [-1] * 6
        frets[string - 1] = 0
        return make_note("1/16", frets)
    strings = [3, 2, 3, 1, 3, 2, 3, 4] * 2 + [2] * 8 + [6, 5, 4, 3, 2, 4, 3, 2]
    return Song(tempo=112.5, notes=tuple(single(s) for s in strings), title="fast lines")


def planned_crossings(right: ScriptedRight, tl) -> tuple[np.ndarray, Notes]:
    """(n, 6) times each string is crossed below string height (1 mm, as in training) by the planned pick path
    within each note, by the env's detection on the path's straight steps."""
    n = int(tl.n_notes)
    notes = Notes(np.asarray(tl.left)[:n], np.asarray(tl.pick)[:n], np.asarray(tl.onset)[:n + 1])
    path = jnp.asarray(right.pick_path(notes), jnp.float32)
    picked = np.asarray(jax.vmap(lambda a, b: detect.pick_crossings(a, b, depth=0.001).picked)(path[:-1], path[1:]))
    return np.stack([picked[a:b].sum(0) for a, b in zip(notes.onset[:-1], notes.onset[1:])]), notes


def test_the_pick_crosses_fast_lines_note_by_note():
    tl = TL.from_song(fast_lines())
    assert set(np.diff(np.asarray(tl.onset)[:int(tl.n_notes) + 1])) == {8}
    counts, notes = planned_crossings(ScriptedRight(), tl)
    np.testing.assert_array_equal(counts, notes.pick)          # each note's string once, and no other string
    env = envs.make("right", [tl], envs.EnvConfig().evaluation())
    assert ScriptedPlayer(env).play(0)["right"]["f1"] >= 0.95      # and the simulated hand follows it


def quick_strums() -> Song:
    """Strums over strings 1-3 in 12- and 6-frame notes (150 BPM) whose fret on string 1 changes at every note, the
    other two open, as in `spring_overture`: string 1 must be picked early in its note for its press to last 2/3 of
    the note from the pick (the duet's rule (3)), before the left hand moves on to the next fret."""
    def chord(fret, d):
        return make_note(d, [fret, 0, 0, -1, -1, -1])
    bar = [chord(3, "1/8"), chord(5, "1/16"), chord(3, "1/16"), chord(0, "1/16"), chord(5, "1/16"), chord(3, "1/16")]
    return Song(tempo=150, notes=(chord(0, "1/2"), *bar * 3, chord(3, "1/2")), title="quick strums")


def test_strums_so_that_the_left_hand_holds_each_string_long_enough():
    """In the duet each stroke is fitted to the planned left hand (`ScriptedRight.fit`): alternating strokes would
    pick string 1 last in every down-stroke, in a 6-frame note too late for its press to last 2/3 of the note from
    the pick; the fitted strokes pick at most one string too late, and both hands play the song in time."""
    tl = TL.from_song(quick_strums())
    env = envs.make("duet", [tl], envs.EnvConfig().evaluation())
    player = ScriptedPlayer(env)
    notes = Notes.from_window(env.sample_window(jax.random.PRNGKey(0), 0))
    (_, q), = FF.plan_all([(notes.left, notes.pick, notes.onset)], log=lambda m: None)
    timing = player.left.timing(notes, q)
    right = ScriptedRight()
    short = [right.short_holds(notes, timing, s.note, *np.flatnonzero(notes.pick[s.note])[[0, -1]], s.cross,
                               s.start > s.end, s.frames) for s in right.sweeps(notes, timing)[0]]
    assert sum(short) <= 1
    result = player.play(0)
    assert result["left"]["f1"] == result["right"]["f1"] == 1.0              # each hand plays every note ...
    assert result["both"]["f1"] >= 0.95                                      # ... and in time


def tracked_presses(hand, notes) -> np.ndarray:
    """(T + 1, 6) frets pressed, as the env detects them, along `hand`'s plan of `notes` tracked in MuJoCo C (row j:
    the state after control step j - 1)."""
    from dexguitar.planner import Tracker
    from dexguitar.planner.left import _pressed
    _, q = Tracker("left").track(hand.desired(notes))
    out = []
    for row in q:
        hand.kin.set(row)
        out.append(_pressed(hand.kin.segments()))
    return np.array(out)


def strings_held(press, goal, onset, i: int) -> int:
    """How many of note i's pressed strings stay at their fret for 2/3 of it in `press` (rows as `tracked_presses`)."""
    ok = 3 * np.sum(press[onset[i] + 1:onset[i + 1] + 1] == goal[i], axis=0) >= 2 * (onset[i + 1] - onset[i])
    return int(np.sum(ok[goal[i] > 0]))


def fingering_and_held(notes):
    """The planner's fingering of `notes` after the opening rest, and per note how many of its pressed strings the
    tracked motion holds for 2/3 of it (`strings_held`)."""
    hand = ScriptedLeft()
    press = tracked_presses(hand, notes)
    return hand.fingering(notes)[1:], [strings_held(press, notes.left, notes.onset, i) for i in range(1, notes.n)]


def test_a_chord_the_rule_cannot_hold_gets_another_fingering():
    """Strings 3 and 4 at fret 2 right after a note at fret 1 (come_as_you_are, note 51): the one-finger-per-fret
    rule keeps position 1 and sends the ring finger back from its own fret 3, where the middle finger is in its way,
    and the chord does not hold in the planner's trial; the middle finger across both strings does. Judged on the
    whole tracked motion in MuJoCo C (not the planner's own short trial): the chord's strings pressed at fret 2,
    string 5 open, for 2/3 of the note."""
    goal = np.array([[0, 0, 0, 0, 1, 0], [0, 0, 2, 2, -1, 0]])     # timeline goals: k press, -1 open, 0 free
    notes = Notes(goal, goal != 0, np.array([0, 30, 60]))
    hand = ScriptedLeft()
    plan = hand.fingering(notes)
    rule = hand.rule([(2, -3), (2, -2)], 1)
    assert rule == (1, {1: (3, 2), 2: (2, 2)}) and not hand.holds(*rule, goal[1], plan[0])
    assert plan[1] == (1, {1: (PAIR + 2, 2)})
    press = tracked_presses(hand, notes)[31:61]                     # the states during the chord's 30 frames
    assert np.mean((press[:, 2] == 2) & (press[:, 3] == 2) & (press[:, 4] == 0)) >= 2 / 3


def test_presses_each_note_by_its_onset(timeline):
    """Every change between two notes leads the onset by up to 2 frames, into the slack of the note before beyond
    its 2/3, so a right hand that picks at the onset finds the string pressed. Judged on the tracked MuJoCo C motion:
    the first frame, counted from each note's onset, at which its frets are all pressed."""
    notes = Notes(np.asarray(timeline.left), np.asarray(timeline.pick), np.asarray(timeline.onset))
    press = tracked_presses(ScriptedLeft(), notes)
    first = []
    for i in range(1, notes.n):
        goal = notes.left[i]
        if (goal > 0).any():
            frames = range(notes.onset[i] - 6, notes.onset[i + 1])
            first.append(next(j - notes.onset[i] for j in frames if np.all((press[j] == goal)[goal > 0])))
    assert len(first) == 11 and max(first) <= 0


def test_a_six_string_chord_is_held_with_two_pairs():
    """Four fingers cannot press six strings one each: snow's repeated chord 9 11 11 9 9 11 (strings 6..1, 9-frame
    notes) takes two fingers across two strings each (`PAIR`) and two single ones, and the tracked motion holds all
    six strings for 2/3 of the note."""
    goal = np.array([[0, 0, 0, 11, 11, 9]] + [[11, 9, 9, 11, 11, 9]] * 3)
    notes = Notes(goal, goal != 0, np.arange(5) * 9)
    hand = ScriptedLeft()
    assert hand.fingering(notes)[2] == (8, {0: (5, 9), 1: (PAIR + 1, 9), 2: (0, 11), 3: (PAIR + 3, 11)})
    press = tracked_presses(hand, notes)[19:28]                     # the third note's 9 states
    assert int(np.sum(3 * np.sum(press == goal[2], axis=0) >= 2 * 9)) == 6


def test_a_plan_does_not_depend_on_what_was_planned_before():
    """The hand positions' IK starts from a fixed chain (from the home position outwards), not from whichever
    position was solved last, so that a song's plan is the same alone and after another song in the same worker."""
    low = Notes(np.array([[0, 0, 2, 0, 0, 0], [0, 0, 0, 3, 0, 0]]), np.eye(6, dtype=bool)[[2, 3]],
                np.array([0, 20, 40]))
    high = Notes(np.array([[0, 0, 12, 0, 0, 0]]), np.eye(6, dtype=bool)[[2]], np.array([0, 20]))
    alone = ScriptedLeft().desired(low)
    after = ScriptedLeft()
    after.desired(high)
    np.testing.assert_array_equal(after.desired(low), alone)


def test_fingers_do_not_jump_between_short_notes():
    """Fret 3 on strings 2 and 4 in turn, 8-frame notes (capriccio_op59_no16, notes 26-28): the one-finger-per-fret
    rule gives both to the finger of fret 3, which would have to lift, cross two strings and land within the
    boundary, and the note would then be pressed for less than 2/3 of it. Another finger takes string 4, and both
    notes hold on the tracked motion in MuJoCo C."""
    s2, s4 = [0, 3, 0, 0, 0, 0], [0, 0, 0, 3, 0, 0]
    goal = np.array([[0, 0, 0, 2, 0, 0], s2, s4, s2, s4])
    onset = np.array([0, 20, 28, 36, 44, 52])
    notes = Notes(goal, goal != 0, onset)
    hand = ScriptedLeft()
    plan, held = fingering_and_held(notes)                   # notes 1-4
    before, (p, fingers) = plan[0], plan[1]                  # notes 1 (string 2) and 2 (string 4)
    assert hand.hurried(notes, 2) and hand.jumps(before, *hand.rule([(3, -3)], p))
    assert before[0] == p and [before[1], fingers] == [{1: (1, 3)}, {0: (3, 3)}]
    assert held[1:3] == [1, 1]


def test_a_double_stop_is_pressed_with_one_finger():
    """Strings 1 and 2 together at fret 5, then at fret 6, 8-frame notes (johnny_b_goodie's double stops). One
    finger's axis midway between two neighbouring strings is within the press distance of both (about 4 mm of 6), so
    each is played with one finger across the pair. Judged on the tracked motion in MuJoCo C: strings at their fret
    for 2/3 of a note."""
    goal = np.array([[0] * 6] + [[5, 5, 0, 0, 0, 0], [6, 6, 0, 0, 0, 0]] * 3)
    onset = np.concatenate([[0], 20 + np.arange(7) * 8])
    plan, held = fingering_and_held(Notes(goal, goal != 0, onset))
    assert [set(f.values()) for _, f in plan[:2]] == [{(PAIR, 5)}, {(PAIR, 6)}]
    assert held == [2] * 6


def test_hand_positions_are_planned_for_the_whole_line():
    """Frets 6, 7, 6, 8, 7 on strings 3 and 2, 5- and 10-frame notes (johnny_b_goodie's opening). Moving the hand only
    when a note leaves its position, by the least amount, would go through positions 3, 4 and 5, a slow wrist move at
    three of the notes. Positions are chosen for the whole song with as few moves as cover it: position 5 holds them
    all, and every note is held on the tracked motion."""
    goal = np.array([[0] * 6, [0, 0, 6, 0, 0, 0], [0, 0, 7, 0, 0, 0], [0, 6, 0, 0, 0, 0], [0, 8, 0, 0, 0, 0],
                     [0, 0, 7, 0, 0, 0]])
    onset = np.array([0, 20, 25, 30, 40, 50, 60])
    plan, held = fingering_and_held(Notes(goal, goal != 0, onset))
    assert [p for p, _ in plan] == [5] * 5 and held == [1] * 5


def test_the_fingerings_with_a_pair_are_searched():
    """Strings 2, 3 and 4 at fret 2 with string 5 open (come_as_you_are, note 52), in position 1. The rule puts the
    pair of strings 3 and 4 on the middle finger and string 2 on the ring finger, which does not hold in the trial;
    of the fingerings with the pair, cheapest first, the index across the pair and the middle finger on string 2
    hold all three strings on the tracked motion."""
    chord = [0, 2, 2, 2, -1, 0]
    goal = np.array([[0] * 6, chord, chord])
    onset = np.array([0, 20, 50, 80])
    notes = Notes(goal, goal > 0, onset)
    hand = ScriptedLeft()
    rule = hand.rule([(2, -(PAIR + 2)), (2, -1)], 1)
    assert rule == (1, {1: (PAIR + 2, 2), 2: (1, 2)}) and not hand.holds(*rule, goal[1])
    plan, held = fingering_and_held(notes)
    assert plan[0][1] == {0: (PAIR + 2, 2), 1: (1, 2)} and held == [3, 3]


def test_a_first_note_that_comes_at_once_is_reached():
    """beethoven_virus opens with fret 9 on string 3 for 12 frames right after the 5-frame rest, two frets above the
    home position: the first move from the home pose ends by the first onset (`first_frames`), not after
    `start_frames`, and the tracked motion holds every note."""
    goal = np.array([[0] * 6, [0, 0, 9, 0, 0, 0], [0, 10, 0, 0, 0, 0], [7, 0, 0, 0, 0, 0], [8, 0, 0, 0, 0, 0]])
    onset = np.array([0, 5, 17, 29, 41, 53])                      # beethoven_virus's first notes, as the env plans them
    notes = Notes(goal, goal > 0, onset)
    plan, held = fingering_and_held(notes)
    assert [p for p, _ in plan] == [7] * 4 and held == [1, 1, 1, 1]
    q = ScriptedLeft().desired(notes)               # the wrist and thumb: in position 7 by the first onset, and stay
    assert np.ptp(q[5:, WRIST_THUMB], axis=0).max() == 0 and np.abs(q[4, WRIST_THUMB] - q[5, WRIST_THUMB]).max() > 0


def test_the_hand_shifts_quickly_between_short_notes():
    """Two 9-frame notes at fret 3, then two at fret 10 and back, on string 2 (snow and beethoven_virus move the hand
    like this). A shift of `shift_frames` (10) would eat up to 6 frames of a 9-frame note beside it; between such
    notes it takes 2 * (9 - 6) + 2 = 8 frames, and every note holds on the tracked motion."""
    line = [3, 3, 10, 10, 3, 3]
    goal = np.array([[0] * 6] + [[0, k, 0, 0, 0, 0] for k in line])
    onset = np.r_[0, 20 + 9 * np.arange(len(line) + 1)]
    plan, held = fingering_and_held(Notes(goal, goal > 0, onset))
    assert [p for p, _ in plan] == [3, 3, 7, 7, 3, 3] and held == [1] * len(line)


def test_a_fret_is_barred_with_the_index():
    """Strings 1, 2 and 6 at fret 1 with string 3 at fret 2 (sonata_in_f_major_ms84_no14, notes 70-73), then two
    notes that keep string 6 at fret 1. One finger per string cannot play the chord: the index lies across all six
    strings at fret 1 in a hand pose of its own, the middle finger on string 3, the barre stays for the next two
    notes, and every string holds."""
    chord = [1, 1, 2, 0, 0, 1]
    goal = np.array([[0] * 6, chord, [0, 1, 0, 0, 0, 1], [0, 0, 2, 0, 0, 1], chord])
    onset = np.array([0, 20, 50, 65, 80, 110])
    plan, held = fingering_and_held(Notes(goal, goal > 0, onset))
    barre = BARRE_POSITIONS + 1
    assert plan == [(barre, {0: (BARRE, 1), 1: (2, 2)}), (barre, {0: (BARRE, 1)}),
                    (barre, {0: (BARRE, 1), 1: (2, 2)}), (barre, {0: (BARRE, 1), 1: (2, 2)})]
    assert held == [4, 2, 2, 4]


def test_a_chord_stays_down_over_its_partial_strum():
    """snow, notes 47-51: the chord 7 9 9 8 7 7 (strings 6..1) twice, then only its strings 6-4 twice, then the
    next chord. The chord's fingering already plays the partial strum, so it stays, as a guitarist keeps a chord
    down: no finger lifts and lands again at the boundary, and the tracked motion holds all 6 strings of the second
    chord and all 3 of the first partial one."""
    chord = [7, 7, 8, 9, 9, 7]                                   # strings 1..6
    part = [0, 0, 0, 9, 9, 7]
    goal = np.array([[0] * 6, chord, chord, part, part, [0, 11, 11, 11, 9, 0]])
    onset = np.array([0, 20, 29, 38, 47, 56, 65])
    plan, held = fingering_and_held(Notes(goal, goal > 0, onset))
    assert plan[0] == plan[1] == plan[2] == plan[3] and held == [6, 6, 3, 3, 3]


def test_a_fast_chromatic_run_glides():
    """Frets 1 to 9 on string 1 in 5-frame notes (flight_of_the_bumblebee1's run, notes 194-209, goes on to fret 17).
    As few moves as cover the line would be frets 1-4 in position 1, then a 4-fret jump to position 5, which the
    wrist (kp 10 on 0.2 kg) cannot make in the frame of slack a 5-frame note has. A move between two such short notes
    costs per fret beyond one: the little finger stays on the string and slides one fret a note while the hand
    follows, and every note holds on the tracked motion."""
    line = list(range(1, 10))
    goal = np.array([[0] * 6] + [[k, 0, 0, 0, 0, 0] for k in line])
    onset = np.r_[0, 20 + 5 * np.arange(len(line) + 1)]
    plan, held = fingering_and_held(Notes(goal, goal > 0, onset))
    assert plan == [(1, {0: (0, 1)}), (1, {1: (0, 2)}), (1, {2: (0, 3)})] + [(k - 3, {3: (0, k)}) for k in line[3:]]
    assert held == [1] * len(line)


SPRING = np.array([[0] * 6, [12, -1, -1, 0, 0, 0], [10, -1, -1, 0, 0, 0], [8, -1, -1, 0, 0, 0]])
SPRING_ONSET = np.array([0, 17, 23, 29, 53])


def test_a_shift_takes_its_frames_from_the_note_that_can_spare_them():
    """spring_overture, notes 2-4: frets 12 and 10 on string 1 for 6 frames each (strings 2-3 open), then fret 8 for
    24 frames, which moves the hand from position 9 to 8. The right hand strums strings 3, 2, 1 and reaches string 1
    at frame 3 (from 0) of a 6-frame note; the paper's rule (3) then wants fret 10 held for 4 frames from that pick,
    into the next note. The 6-frame shift takes its frames from the two notes in proportion to what each can spare
    (2 of 6 frames and 8 of 24): fret 10 lasts 4 frames or more from the pick, and every note holds its 2/3."""
    notes = Notes(SPRING, SPRING > 0, SPRING_ONSET)
    hand = ScriptedLeft()
    press = tracked_presses(hand, notes)
    rows = press[SPRING_ONSET[2] + 4:, 0]          # string 1 from the state after the pick's step (frame 3, from 0)
    assert [p for p, _ in hand.fingering(notes)[1:]] == [9, 9, 8]
    assert int(np.argmax(rows != 10)) >= 4
    assert [strings_held(press, SPRING, SPRING_ONSET, i) for i in (1, 2, 3)] == [1, 1, 1]


def test_a_string_no_hand_position_spans_is_dropped():
    """sonata_in_f_major_ms84_no14, notes 23-26: strings 1-2 at fret 6, the same with string 4 at fret 2, then strings
    1-2 at fret 8 with string 4 still at fret 2: seven frets, which no hand position spans. Where no fingering of all
    three strings exists, the partial search tries two of them: both frets 8 from position 5 (F1 0.8), instead of a
    stretch from position 2 to fret 8 that would hold none; the note before holds all three of its strings."""
    goal = np.array([[0] * 6, [6, 6, 0, -1, 0, 0], [6, 6, 0, 2, 0, 0], [8, 8, 0, 2, 0, 0], [0, 0, 0, 0, 8, 0]])
    onset = np.array([0, 20, 38, 56, 74, 83])
    plan, held = fingering_and_held(Notes(goal, goal > 0, onset))
    assert plan[2] == (5, {2: (1, 8), 3: (0, 8)}) and held == [2, 3, 1, 1]


def test_a_trill_keeps_the_lower_finger_down():
    """flight_of_the_bumblebee1's trills on string 3 (frets 7-6-7-6 in 5-frame notes, notes 115-118 and 179-182): the
    middle finger stays down on fret 6 under the ring finger's fret 7 (the highest fret sounds), so going back down
    is a pull-off, and the ring finger lifts at the boundary rather than ahead of it: its lift of 3 frames starts
    0.3 of them (`pull_lead`) before the boundary, within the last frame of the note. A line that goes on up the
    string (6, 7, 8) keeps no finger down."""
    trill = [6, 7, 6, 7, 6, 5]
    goal = np.array([[0] * 6] + [[0, 0, k, 0, 0, 0] for k in trill])
    onset = np.r_[0, 20 + 5 * np.arange(len(trill) + 1)]
    notes = Notes(goal, goal > 0, onset)
    hand = ScriptedLeft()
    assert [hand.fingering(notes)[i] for i in (2, 4)] == [(5, {2: (2, 7), 1: (2, 6)})] * 2
    q = hand.desired(notes)
    middle, ring = FINGER_DOFS[1], FINGER_DOFS[2]
    rows = slice(onset[2] + 1, onset[5] + 1)             # from the first 7 to the end of the second 7
    assert np.ptp(q[rows, middle], axis=0).max() < 1e-9
    np.testing.assert_array_equal(q[onset[3] - 1, ring], q[onset[3] - 2, ring])      # still pressing ...
    assert np.abs(q[onset[3], ring] - q[onset[3] - 1, ring]).max() > 0.01            # ... lifting by the boundary
    line = np.array([[0] * 6] + [[0, 0, k, 0, 0, 0] for k in (6, 7, 8)])
    climb = Notes(line, line > 0, np.r_[0, 20 + 5 * np.arange(4)])
    assert [len(f) for _, f in hand.fingering(climb)[1:]] == [1, 1, 1]


def test_a_shift_lifts_and_lands_clear_of_the_next_string():
    """spring_overture, notes 2-4 (`SPRING`): `10 0 0` then `8 0 0`, the hand moving from position 9 to 8. Joined
    straight in joint space while the wrist moves, the middle finger leaving fret 10 of string 1 and the index
    landing on its fret 8 would press string 2, which both notes want open: a pick of string 2 there would be
    "picked before the press". Both fingers pass 7 mm above the string they leave or land on (`shift_via`), and the
    tracked motion never presses string 2 around the change. Jumps of more than `via_shift` frets keep the straight
    path (vias there lost held-out songs of large jumps)."""
    notes = Notes(SPRING, SPRING > 0, SPRING_ONSET)
    hand = ScriptedLeft()
    press = tracked_presses(hand, notes)
    assert np.count_nonzero(press[SPRING_ONSET[3] - 3:SPRING_ONSET[3] + 8, 1]) == 0
    assert [strings_held(press, SPRING, SPRING_ONSET, i) for i in (1, 2, 3)] == [1, 1, 1]
    plan = hand.fingering(notes)
    assert plan[2][1] == {1: (0, 10)} and plan[3][1] == {0: (0, 8)}
    assert [hand.shift_via(f, plan[2], plan[3], SPRING[2], SPRING[3]) is None for f in range(4)] == [
        False, False, True, True]
    jump = SPRING.copy()                                  # a jump of 6 frets, fret 10 to 3: no detour
    jump[3, 0] = 3
    plan = hand.fingering(Notes(jump, jump > 0, SPRING_ONSET))
    assert abs(plan[3][0] - plan[2][0]) > hand.via_shift
    assert all(hand.shift_via(f, plan[2], plan[3], jump[2], jump[3]) is None for f in range(4))


SONATA_BASS = [1, 1, 2, 0, 0, 1]
# sonata_in_f_major_ms84_no14, notes 70-74 (`1 x x x x x`, `1 x x 2 1 1`, `1 x x 3 3 1`, `1 x 3 x x x`, `1 x x 2 1 1`)
# and 90-94 (`1 x x 2 1 1`, `1 x 3 x x x`, `1 x x 0 1 0`, `1 3 x x x x`, `x 3 2 3 1 0`), 18-frame notes over a bass
# held on string 6 at fret 1
_BARRE = np.array([[0] * 6, [0, 0, 0, 0, 0, 1], SONATA_BASS, [1, 3, 3, 0, 0, 1], [0, 0, 0, 3, 0, 1], SONATA_BASS])
_GUIDE = np.array([[0] * 6, SONATA_BASS, [0, 0, 0, 3, 0, 1], [-1, 1, -1, 0, 0, 1], [0, 0, 0, 0, 3, 1],
                   [-1, 1, 3, 2, 3, 0]])
SONATA_BARRE = Notes(_BARRE, _BARRE > 0, np.r_[0, 20 + 18 * np.arange(6)])
SONATA_GUIDE = Notes(_GUIDE, _GUIDE > 0, np.r_[0, 20 + 18 * np.arange(5), 20 + 18 * 4 + 36])


def test_a_barre_stays_and_a_guide_finger_keeps_its_place():
    """(a) `SONATA_BARRE`: under a barre at fret 1, `1 x x 3 3 1` with the ring and little fingers on strings 3 and 2
    at fret 3 does not hold (the short little finger lies flat on fret 1); with the ring finger across both strings
    (`PAIR` + 1) it does. So the barre stays over all five notes, and `1 x x 3 3 1` holds its four strings for 2/3
    of the note on the tracked motion, where leaving the barre for a fingering of its own and coming back held at
    most one. (b) `SONATA_GUIDE`: `1 x x 0 1 0` (strings 1 and 3 open) after the barre, then `1 3 x x x x`: the
    bass stays under the middle finger, which pressed it in the note before, and `1 x x 0 1 0` holds both strings;
    moved to the index, which must cross from string 2, it held at most one."""
    plan, held = fingering_and_held(SONATA_BARRE)
    assert [p for p, _ in plan] == [BARRE_POSITIONS + 1] * 5
    assert plan[2][1] == {0: (BARRE, 1), 2: (PAIR + 1, 3)} and held[2] == 4
    plan, held = fingering_and_held(SONATA_GUIDE)
    assert plan[2] == (1, {0: (1, 1), 1: (5, 1)}) and plan[3][1][1] == (5, 1)
    assert held[2] == 2


def test_a_double_stop_hammered_on_lands_a_frame_sooner():
    """johnny_b_goodie, notes 4-10: `x x x x 5 5` then `x x x x 6 6` in 5-frame notes (which must hold 4 frames),
    strings 1-2 under one finger each time (`PAIR`). The middle finger landing on fret 6 would change the note before,
    so it lands after the boundary, but a double stop hammered on (both strings pressed lower in the note before)
    lands a frame sooner, within what the note before can spare: every note holds both strings."""
    goal = np.array([[0] * 6, [0, 8, 0, 0, 0, 0], [5, 5, 0, 0, 0, 0], [6, 6, 0, 0, 0, 0], [6, 6, 0, 0, 0, 0],
                     [5, 5, 0, 0, 0, 0], [6, 6, 0, 0, 0, 0], [6, 6, 0, 0, 0, 0]])
    onset = np.cumsum([0, 20, 10, 5, 5, 10, 5, 5, 10])
    notes = Notes(goal, goal > 0, onset)
    plan, held = fingering_and_held(notes)
    assert plan[4:6] == [(5, {0: (PAIR, 5)}), (5, {1: (PAIR, 6)})]
    assert held == [1, 2, 2, 2, 2, 2, 2]
    # note 6's landing: 3 frames (5-frame notes), not led (the note before spares 1 frame: tb = onset + 0.5), from
    # tb + 1 - 0.6 * 3 - 1 = onset - 1.3 to onset + 1.7: pressing from row onset + 2 on (a frame later: onset + 3)
    q = ScriptedLeft().desired(notes)
    middle = FINGER_DOFS[1]
    pressing = q[onset[7], middle]                              # `6 6` again in note 7: the same press
    np.testing.assert_allclose(q[onset[6] + 2, middle], pressing, rtol=0, atol=1e-12)
    assert np.abs(q[onset[6] + 1, middle] - pressing).max() > 1e-3


def test_a_finger_hovers_clear_of_a_string_its_note_wants_open():
    """prelude1_in_c_major_chords, notes 93-105 in 9-frame notes over the bass on string 5 at fret 3 (from hand
    position 2 to 1): ... string 2 open, at fret 3, fret 1 on string 1, at fret 3, open, at fret 3. In position 1 the
    middle finger presses string 2 at fret 3, a fret beyond its own; for the open note between two such presses,
    over that place it cannot lift its tip more than 6.7 mm above the strings, and in physics it would stay within
    the press distance and sound string 2 at fret 3 (the song's note 103). It hovers over its own fret there, 10 mm
    up, and on the tracked motion every note has its strings as it asks for 2/3 of itself (6 of 9 frames)."""
    from dexguitar.world import scoring
    goal = np.array([[0] * 6, [0, 0, 0, 3, 5, 0], [0, 0, 0, 0, 3, 0], [0, -1, 0, 0, 3, 0], [0, 3, 0, 0, 3, 0],
                     [1, 0, 0, 0, 3, 0], [0, 3, 0, 0, 3, 0], [0, -1, 0, 0, 3, 0], [0, 3, 0, 0, 3, 0],
                     [0, -1, 0, 0, 0, 0]])
    onset = np.r_[0, 20 + 9 * np.arange(len(goal))]
    notes = Notes(goal, goal != 0, onset)
    hand = ScriptedLeft()
    press = tracked_presses(hand, notes)
    right = [int(np.sum(np.all(np.asarray(scoring.left_ok(press[onset[i] + 1:onset[i + 1] + 1], goal[i])), axis=1)))
             for i in range(1, len(goal))]
    assert min(right) >= 6, right
    plan = hand.plans(notes)[0]
    assert plan[6:9] == [(1, {1: (1, 3), 2: (4, 3)}), (1, {2: (4, 3)}), (1, {1: (1, 3), 2: (4, 3)})]
    assert hand.tip_height(hand.configs(notes, plan)[7][0], 1) >= hand.open_clear


def test_an_early_crossing_leaves_the_stroke_before_its_time():
    """flight_of_the_bumblebee1's line down string 3 (frets 8 to 4) and on to string 2 at fret 5, 5-frame notes. The
    left hand lets go of string 2's fret a step early, so crossing string 2 in step 0 of its note would hold more of
    it (`fit`); but that is 4 steps after the crossing before, which would leave the stroke over string 3 before it
    3.4 frames, and in the song the simulated pick then missed such notes. A crossing moves into step 0 only
    `early_gap` (4.5) steps or more after the one before: every crossing stays in step 1 (at 1.5), and the stroke
    over string 3 before string 2 keeps more than 4 frames."""
    frets = [(3, 8), (3, 7), (3, 6), (3, 5), (3, 4), (2, 5)] * 2
    goal = np.zeros((len(frets) + 1, 6), int)
    for i, (s, k) in enumerate(frets):
        goal[i + 1, s - 1] = k
    notes = Notes(goal, goal != 0, np.r_[0, 20 + 5 * np.arange(len(frets) + 1)])
    (_, q), = FF.plan_all([(notes.left, notes.pick, notes.onset)], log=lambda m: None)
    timing = ScriptedLeft().timing(notes, q)
    strokes = ScriptedRight().sweeps(notes, timing)[0]
    assert [s.cross - notes.onset[s.note] for s in strokes] == [1.5] * len(frets)
    assert strokes[4].frames > 4.0


def test_the_count_in_gives_the_hand_time_to_reach_a_far_first_note():
    """`flight_of_the_bumblebee1` opens with fret 12 on string 1 in 5-frame notes (1/16 at 180 BPM). From the home pose
    (the index finger over fret 5) the planned hand moves about 0.15 m along the neck to press it: after the training
    windows' 5-frame rest it arrives after the first two notes, after the evaluation's 15-frame count-in in time
    (the plan tracked in MuJoCo C, presses as the env detects them: `tracked_presses`)."""
    notes = [make_note("1/16", [f, -1, -1, -1, -1, -1]) for f in (12, 11, 10, 9, 10, 9, 8, 7)]
    timeline = TL.from_song(Song(tempo=180, notes=tuple(notes), title="bumblebee's opening"))
    held = {}
    for count_in in (5, envs.EnvConfig().count_in):
        config = dataclasses.replace(envs.EnvConfig(), count_in=count_in).evaluation()
        assert config.rest_frames == count_in
        window = Notes.from_window(envs.make("left", [timeline], config).sample_window(jax.random.PRNGKey(0), 0))
        assert window.onset[1] == count_in
        press = tracked_presses(ScriptedLeft(), window)
        held[count_in] = [strings_held(press, window.left, window.onset, i) for i in (1, 2)]   # the first two notes
    assert held == {5: [0, 0], 15: [1, 1]}, held
