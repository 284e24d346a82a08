import re
from collections import Counter
from fractions import Fraction

import numpy as np

import pytest

from dexguitar.music import coverage as cov
from dexguitar.music.procedural import (CHORD_SHAPES, FAMILIES, GENERAL_KINDS, LINE_SCALES, SHAPES_BY_NAME,
                                        chord_positions, chord_voicings, coverage, draw_voicing, finger_groups,
                                        left_exercises, left_general, right_patterns, scale_positions, scale_run,
                                        shape_name)
from dexguitar.music.song import Effect, Song
from dexguitar.world.guitar import GUITAR

MUTE = -1
X = MUTE
MAJOR = (0, 2, 4, 5, 7, 9, 11)
BUCKETS = ((1, 5), (6, 10), (11, 15), (16, 22))


@pytest.fixture(scope="module")
def left():
    return left_exercises(7, 200)


@pytest.fixture(scope="module")
def right():
    return right_patterns(7, 200)


@pytest.fixture(scope="module")
def general():
    return left_general(7, 20 * len(GENERAL_KINDS))


def pressed_ok(frets):
    """Independent playability check of one hand shape."""
    assert len(frets) == 6
    assert all(-1 <= f <= 22 for f in frets), frets
    pressed = [f for f in frets if f >= 1]
    if pressed:
        assert max(pressed) - min(pressed) <= 3, frets
        assert len(set(pressed)) <= 4, frets


def bucket(fret):
    return next(i for i, (lo, hi) in enumerate(BUCKETS) if lo <= fret <= hi)


def test_deterministic_per_seed():
    assert left_exercises(3, 12) == left_exercises(3, 12)
    assert right_patterns(3, 12) == right_patterns(3, 12)
    assert left_exercises(3, 12) != left_exercises(4, 12)
    assert right_patterns(3, 12) != right_patterns(4, 12)
    assert left_exercises(3, 12)[:5] == left_exercises(3, 5)  # a longer call extends a shorter one


def test_songs_are_well_formed(left, right):
    for songs, (lo, hi), prefix in ((left, (60, 160), "left-exercise-"), (right, (60, 180), "right-pattern-")):
        assert len(songs) == 200
        for i, song in enumerate(songs):
            assert isinstance(song, Song) and len(song.notes) == 40
            assert lo <= song.tempo <= hi
            assert song.title.startswith(f"{prefix}{i} (")
            for note in song.notes:
                assert isinstance(note.duration, Fraction) and note.duration > 0
    kinds = {s.title.split("(")[1].split()[0].rstrip(")") for s in left}
    assert kinds == {"scale", "arpeggio", "chords", "jumps"}
    assert any(n.is_rest for s in left for n in s.notes)
    assert any(a == b and not a.is_rest for s in left for a, b in zip(s.notes, s.notes[1:]))


def test_every_note_is_playable(left, right):
    for song in left + right:
        for note in song.notes:
            pressed_ok(note.frets)
            if note.chord is not None:
                pressed_ok(note.chord)
                for f, c in zip(note.frets, note.chord):
                    if f != MUTE:
                        assert c == f, (note.frets, note.chord)


def test_right_hand_is_open_strings_without_effects(right):
    for song in right:
        for note in song.notes:
            assert set(note.frets) <= {MUTE, 0} and not note.is_rest
            assert all(e == Effect.NONE for e in note.effects)


def test_vocabulary():
    assert len(CHORD_SHAPES) >= 40
    names = [s.name for s in CHORD_SHAPES]
    assert len(set(names)) == len(names)
    for s in CHORD_SHAPES:
        positions = chord_positions(s)
        assert positions and len(set(positions)) == len(positions)
        assert len(positions) == (1 if not s.movable else 22 - max(f for f in s.frets if f >= 0))
        for p in positions:
            pressed_ok(p)
            assert shape_name(p) == s.name
            if s.movable:
                assert 0 not in p and min(f for f in p if f > 0) >= 1
    # A barre: >= 3 strings at the lowest fret, strings 1 and 6 among them.
    barres = [s for s in CHORD_SHAPES if s.movable and s.frets[0] == s.frets[5] == 0
              and sum(f == 0 for f in s.frets) >= 3]
    assert barres
    power = [s for s in CHORD_SHAPES if "power" in s.name]
    assert {len(s.strings) for s in power} == {2, 3}
    assert {max(s.strings) for s in power} == {4, 5, 6}
    for name in ("open C", "open G", "open D", "open A", "open Am", "open Em", "open Dm", "open E"):
        assert chord_positions(name) == [SHAPES_BY_NAME[name].frets]


def test_e_shape_positions():
    pos = chord_positions("E-shape major")
    assert pos[0] == (1, 1, 2, 3, 3, 1)   # F major
    assert pos[2] == (3, 3, 4, 5, 5, 3)   # G major
    pitch = GUITAR.pitch_table
    g = {int(pitch[s, f]) % 12 for s, f in enumerate(pos[2])}
    assert g == {7, 11, 2}  # G B D


def test_triads_sound_their_triads():
    pitch = GUITAR.pitch_table
    for s in CHORD_SHAPES:
        if s.name.startswith("triad"):
            p = chord_positions(s)[4]
            pitches = sorted(int(pitch[i, f]) for i, f in enumerate(p) if f != MUTE)
            third = 4 if "major" in s.name else 3
            assert [x - pitches[0] for x in pitches] == [0, third, 7], s.name


def test_major_scale_pitches(left):
    pitch = GUITAR.pitch_table
    names = ("C", "C#", "D", "D#", "E", "F", "F#", "G", "G#", "A", "A#", "B")
    majors = [s for s in left if re.search(r"\(scale \S+ major\)", s.title)]
    assert majors
    for song in majors:
        root = names.index(song.title.split()[2])
        played = [n for n in song.notes if not n.is_rest]
        pcs = set()
        for note in played:
            (string,) = note.played
            pcs.add(int(pitch[string - 1, note.frets[string - 1]] - root) % 12)
        assert pcs == set(MAJOR), song.title
        # Steps within a run move by a scale step (1 or 2 semitones) or restart in a new box.
        steps = [abs(b.pitches[0] - a.pitches[0]) for a, b in zip(played, played[1:])]
        assert sum(s in (0, 1, 2) for s in steps) >= 0.8 * len(steps)


def test_scale_runs_step_through_the_scale():
    pitch = GUITAR.pitch_table
    for root in range(12):
        starts = scale_positions(root, "major")
        assert min(starts) <= 5 and max(starts) >= 16  # the whole neck
        for start in starts:
            run = scale_run(start, root, "major")
            assert len(run) >= 7
            assert all(start <= f <= start + 3 for _, f in run)
            p = [int(pitch[s - 1, f]) for s, f in run]
            assert all(b - a in (1, 2) for a, b in zip(p, p[1:]))
            assert all((q - root) % 12 in MAJOR for q in p)


def test_arpeggio_notes_carry_chord_hint(left):
    arps = [s for s in left if s.title.endswith("(arpeggio)")]
    assert arps
    for song in arps:
        for note in song.notes:
            if not note.is_rest:
                assert note.chord is not None and len(note.played) == 1
                assert shape_name(note.chord) is not None


def test_balanced_chord_shapes_across_neck(left):
    seen = {s.name: set() for s in CHORD_SHAPES}
    for song in left:
        for note in song.notes:
            hand = note.chord if note.chord is not None else note.frets
            name = shape_name(hand)
            if name is not None:
                seen[name].add(bucket(min(f for f in hand if f > 0)))
    for s in CHORD_SHAPES:
        reachable = {bucket(min(f for f in p if f > 0)) for p in chord_positions(s)}
        assert len(seen[s.name]) >= min(3, len(reachable)), (s.name, seen[s.name])


def test_balanced_string_sets(right):
    counts = {}
    for song in right:
        for note in song.notes:
            strings = note.played
            assert list(strings) == list(range(strings[0], strings[-1] + 1))  # contiguous
            counts[strings] = counts.get(strings, 0) + 1
    assert len(counts) == 21
    assert max(counts.values()) < 2 * min(counts.values())
    cov = coverage(right)
    assert cov["string_sets"]["other"] == 0
    assert sorted(v for k, v in cov["string_sets"].items() if k != "other") == sorted(counts.values())


def test_runs_go_up_and_down(right):
    def runs(song, step):
        lows = [n.played[0] if len(n.played) == 1 else None for n in song.notes]
        return any(a is not None and b == a + step and c == a + 2 * step
                   for a, b, c in zip(lows, lows[1:], lows[2:]))
    assert any(runs(s, -1) for s in right)  # e.g. 6-5-4: ascending in pitch
    assert any(runs(s, +1) for s in right)  # e.g. 4-5-6: descending in pitch


def test_coverage_summary(left, right):
    cov = coverage(left)
    assert cov["songs"] == 200 and cov["notes"] + cov["rests"] == 200 * 40
    assert 0 < cov["chord_fraction"] < 1
    assert all(cov["positions"][k] > 0 for k in ("1-5", "6-10", "11-15", "16-22"))
    assert all(v > 0 for v in cov["shapes"].values())
    assert coverage(right)["chord_fraction"] > 0.5


def test_paper_right_patterns_follow_the_authors_distribution():
    """Reference §3.4: one of the 21 contiguous string sets per note, uniformly; U{5..44} frames per note."""
    from collections import Counter

    from dexguitar.music import timeline as TL
    from dexguitar.music.procedural import paper_right_patterns
    songs = paper_right_patterns(7, 30, 40)
    frames, sets = [], Counter()
    for song in songs:
        tl = TL.from_song(song)
        assert int(tl.n_frames) == sum(int(n.duration * 64) for n in song.notes)   # 1/64 note = 1 frame at 225
        for note in song.notes:
            frames.append(int(note.duration * 64))
            played = [i for i, f in enumerate(note.frets, start=1) if f != -1]
            assert all(note.frets[i - 1] == 0 for i in played)                      # open strings only
            assert played == list(range(played[0], played[-1] + 1))                 # contiguous
            sets[(played[0], played[-1])] += 1
    assert min(frames) == 5 and max(frames) == 44
    assert len(sets) == 21
    # 1200 notes over 21 sets: about 57 each; a uniform draw stays within +-50% with overwhelming probability
    assert min(sets.values()) > 28 and max(sets.values()) < 86


# ------------------------------------------------------------------------------------------------ left_general

def kind_of(song):
    """The kind in a title such as "left-general-4 (pedal 5)" or "left-general-6 (line C# major)"."""
    label = song.title.split("(")[1].rstrip(")")
    return next(k for k in GENERAL_KINDS if label == k or label.startswith(k + " "))


def frames(song, note):
    return note.duration * 14400 / Fraction(song.tempo)  # 4 beats of 60 s at 60 frames/s per whole note


def test_general_is_deterministic_per_seed():
    assert left_general(3, 9) == left_general(3, 9)
    assert left_general(3, 9) != left_general(4, 9)
    assert left_general(3, 9)[:4] == left_general(3, 4)


def test_general_songs_are_well_formed(general):
    kinds = list(GENERAL_KINDS)
    assert len(general) == 20 * len(kinds)
    for i, song in enumerate(general):
        assert len(song.notes) == 40 and song.title.startswith(f"left-general-{i} (")
        assert kind_of(song) == kinds[i % len(kinds)]            # the kinds take turns: each 20 songs
        assert 50 <= song.tempo <= 225
        assert all(frames(song, n) >= 4.5 for n in song.notes)    # >= 5 frames once rounded
    shortest = [round(min(frames(s, n) for n in s.notes if not n.is_rest)) for s in general]
    assert set(range(5, 16)) <= set(shortest)                     # the official songs' 5..15 frames, all of them
    assert sum(5 <= f <= 15 for f in shortest) >= 0.95 * len(shortest)
    tempos = [s.tempo for s in general]
    assert min(tempos) <= 60 and max(tempos) >= 200


def test_finger_groups_by_hand():
    assert finger_groups((1, 1, 2, 3, 3, 1)) == 3    # F barre: strings 1, 2, 6 under the index finger
    assert finger_groups((0, 1, 0, 2, 3, X)) == 3    # open C
    assert finger_groups((3, 0, 0, 0, 2, 3)) == 3    # open G: the open strings split the two frets 3
    assert finger_groups((1, 2, 1, 2, 1, X)) == 3    # 1s share a barre; the 2s are split by the 1 between
    assert finger_groups((1, 2, 3, 4, 2, 1)) == 4
    assert finger_groups((2, 1, 2, 3, 4, X)) == 5    # the 1 splits the two 2s
    assert finger_groups((X, 0, X, 0, X, X)) == 0


def test_chord_voicings():
    voicings = chord_voicings()
    names = {v.frets: v.name for v in voicings}
    assert len(names) == len(voicings) > 10000
    for frets, name in {(0, 1, 0, 2, 3, X): "C", (3, 0, 0, 0, 2, 3): "G", (2, 3, 2, 0, X, X): "D",
                        (0, 2, 2, 2, 0, X): "A", (0, 1, 2, 2, 0, X): "Am", (0, 0, 0, 2, 2, 0): "Em",
                        (0, 0, 1, 2, 2, 0): "E", (1, 3, 2, 0, X, X): "Dm", (1, 1, 2, 3, 3, 1): "F",
                        (2, 3, 4, 4, 2, X): "Bm", (X, X, X, 5, 5, 3): "G5", (2, 1, 2, 1, X, X): "Cdim7",
                        (15, 15, 16, 17, 17, 15): "G", (8, 8, 9, X, X, X): "C"}.items():
        assert names.get(frets) == name, frets                    # (8, 8, 9): C in first inversion, E G C
    pitch = GUITAR.pitch_table
    for v in voicings:
        strings = [i for i, f in enumerate(v.frets) if f != X]
        pressed = [f for f in v.frets if f > 0]
        assert len(strings) >= 3 and strings == list(range(strings[0], strings[-1] + 1)), v
        assert pressed and max(pressed) <= 22 and max(pressed) - min(pressed) <= 3, v
        assert finger_groups(v.frets) <= 4
    families = Counter(v.family for v in voicings)
    assert set(families) == set(FAMILIES) and min(families.values()) > 100
    by_name = {v.frets: v.family for v in voicings}
    assert [by_name[f] for f in ((X, X, X, 5, 5, 3), (3, 0, 0, 0, 2, 3), (X, X, 9, 0, 11, X), (8, 8, 9, X, X, X),
                                 (2, 1, 2, 1, X, X), (1, 1, 2, 3, 3, 1))] == list(FAMILIES)
    g7 = {int(pitch[i, f]) % 12 for i, f in enumerate((1, 0, 0, 0, 2, 3))}
    assert names[(1, 0, 0, 0, 2, 3)] == "G7" and g7 == {7, 11, 2, 5}


def test_general_is_playable(general):
    import jax
    import numpy as np

    from dexguitar.envs.rewards import finger_order
    goals = set()
    for song in general:
        for note in song.notes:
            pressed_ok(note.frets)
            if note.chord is not None:
                pressed_ok(note.chord)
                assert all(c == f for f, c in zip(note.frets, note.chord) if f != MUTE)
            tied = [i for i, e in enumerate(note.effects) if e != Effect.NONE]
            assert all(note.frets[i] != MUTE for i in tied)       # a tied string keeps sounding
            goals.add(cov.goal(note))
    goals = np.array(sorted(goals), dtype=np.int32)
    allowed = np.asarray(jax.jit(jax.vmap(finger_order))(goals))  # the reward's own rule: (goals, 6, 4)
    pressed = goals > 0
    assert np.all(allowed.any(axis=-1) == pressed)                # every pressed string has a finger
    assert len(goals) > 1000


def test_general_balance(general):
    rng = np.random.default_rng(0)
    cells = Counter((cov.bucket(v.position), v.family) for v in (draw_voicing(rng) for _ in range(4800)))
    # Neck regions uniform (1200 draws each), then the families found there: all 6 in frets 1-5 (200 each), all
    # but the open position higher up (240 each).
    assert len(cells) == 6 + 3 * 5
    for (region, _), c in cells.items():
        expect = 200 if region == "1-5" else 240
        assert 0.75 * expect <= c <= 1.25 * expect, cells
    goals = [g for s in general for g in cov.song_goals(s)]
    held = [g for g in goals if cov.pressed(g)]
    regions = Counter(cov.bucket(cov.position(g)) for g in held)
    assert all(0.18 <= regions[b] / len(held) <= 0.32 for b in ("1-5", "6-10", "11-15", "16-22")), regions
    assert 0.02 <= 1 - len(held) / len(goals) <= 0.15               # notes on open strings only
    chords = Counter(len(cov.pressed(g)) for g in goals if cov.is_chord(g))
    assert all(chords[k] >= 0.05 * sum(chords.values()) for k in range(2, 7)), chords
    jumps = [j for s in general for j in cov.jumps(cov.song_goals(s))]
    assert sum(j <= 2 for j in jumps) >= 0.5 * len(jumps)           # mostly small moves ...
    assert sum(j >= 7 for j in jumps) >= 0.05 * len(jumps)          # ... and long shifts


def test_general_lines_and_voices_stay_in_their_scale_across_the_neck(general):
    pitch = GUITAR.pitch_table
    names = ("C", "C#", "D", "D#", "E", "F", "F#", "G", "G#", "A", "A#", "B")
    frets = set()
    for song in (s for s in general if kind_of(s) in ("line", "voices")):
        kind, root, scale = re.match(r".*\((line|voices) (\S+) (.+)\)$", song.title).groups()
        for note in (n for n in song.notes if not n.is_rest):
            if kind == "line":
                assert len(note.played) == 1
            else:  # one or two melody notes on strings 1-3, at most one bass note on strings 4-6
                assert 1 <= sum(s <= 3 for s in note.played) <= 2 and sum(s >= 4 for s in note.played) <= 1
            for string in note.played:
                fret = note.frets[string - 1]
                frets.add(fret)
                assert (int(pitch[string - 1, fret]) - names.index(root)) % 12 in LINE_SCALES[scale], song.title
    assert 0 in frets and max(frets) >= 20


def test_general_pedal_stays_below_the_figure(general):
    for song in (s for s in general if kind_of(s) == "pedal"):
        pedal = int(song.title.rstrip(")").split()[-1])
        for note in song.notes:
            assert note.frets[pedal - 1] in (MUTE, 0)
            assert all(s <= pedal for s in note.played), (song.title, note.frets)
