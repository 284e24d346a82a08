"""The song cursor: windows (sequential and training), re-timing, fret shift, goals, advancing, vmap and jit.
Expected numbers are worked out by hand."""
from fractions import Fraction as F
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from dexguitar.music import cursor as CU
from dexguitar.music import timeline as TL
from dexguitar.music.song import MUTE as X, Effect, Song, make_note


def song_a(tempo=100):
    """1/16, 1/8, 1/16, 1/2 at 100 BPM: 1/16 = 900/100 = 9 frames, so 9, 18, 9 and 72 frames."""
    return Song(tempo, [
        make_note(F(1, 16), (3, X, 0, X, X, X)),            # string 1 fret 3, string 3 open
        make_note(F(1, 8), (X, 5, X, X, X, X)),
        make_note(F(1, 16), (X, X, X, 7, X, X), effects=(0, 0, 0, Effect.HAMMER, 0, 0)),
        make_note(F(1, 2), (X, X, X, X, X, X)),             # rest
    ])


def song_3_to_7():
    """Pressed frets 3..7 (with a chord hint), open strings 2 and 6; 1/8 = 18 and 1/4 = 36 frames at 100 BPM."""
    return Song(100, [
        make_note(F(1, 8), (3, 0, X, X, X, X)),
        make_note(F(1, 8), (X, X, X, X, 4, X), chord=(X, X, 5, 7, 4, 0)),
        make_note(F(1, 4), (7, X, X, X, X, 0)),
    ])


def long_song():
    """30 notes at 100 BPM alternating 1/16 (9 frames) and 1/2 (72 frames); note i presses string 1 at fret
    3 + i % 5 and plays string 3 open when i % 3 == 0."""
    return Song(100, [make_note(F(1, 16) if i % 2 == 0 else F(1, 2), (3 + i % 5, X, 0 if i % 3 == 0 else X, X, X, X))
                      for i in range(30)])


def np_(x):
    return np.asarray(x)


def songs_of(*songs):
    return TL.stack([TL.from_song(s) for s in songs])


def sequential(songs, song=0, capacity=8, **kw):
    return CU.sample_window(songs, jax.random.PRNGKey(0), capacity, sequential=True, song=song, **kw)


def at(window, note, frame):
    return CU.Cursor(window, jnp.int32(note), jnp.int32(frame))


# ------------------------------------------------------------------------------------------------------ windows

def test_sequential_window_is_a_rest_then_the_whole_song():
    w = sequential(songs_of(song_a()), fill_strum_gaps=False)
    assert int(w.n) == 5 and int(w.song) == 0 and int(w.first) == 0
    assert np_(w.dur).tolist() == [5, 9, 18, 9, 72, 0, 0, 0]
    assert np_(w.left).tolist() == [[0] * 6, [3, 0, -1, 0, 0, 0], [0, 5, 0, 0, 0, 0], [0, 0, 0, 7, 0, 0]] + \
        [[0] * 6] * 4
    assert np_(w.frets).tolist() == [[X] * 6, [3, X, 0, X, X, X], [X, 5, X, X, X, X], [X, X, X, 7, X, X]] + \
        [[X] * 6] * 4
    assert np_(w.pick).tolist() == [[False] * 6, [True, False, True, False, False, False],
                                    [False, True, False, False, False, False]] + [[False] * 6] * 5   # hammer: no pick
    # strings between the outer targets of a strum are targets too
    assert np_(sequential(songs_of(song_a())).pick)[1].tolist() == [True, True, True, False, False, False]
    # the durations are from_song's: onsets 0, 9, 27, 36, 108
    assert np_(w.dur)[1:5].tolist() == np.diff(np_(TL.from_song(song_a()).onset)).tolist()


def test_sequential_window_is_never_augmented():
    w = sequential(songs_of(song_a()), shift_prob=1.0, tempo_prob=1.0, max_note_frames=50)
    assert np_(w.dur)[:5].tolist() == [5, 9, 18, 9, 72]          # not re-timed, the half note not capped at 50
    assert np_(w.left)[1].tolist() == [3, 0, -1, 0, 0, 0]        # not shifted


def test_training_windows():
    songs = songs_of(long_song())
    song_left = np_(songs.left[0])
    sample = jax.jit(partial(CU.sample_window, capacity=16, sequential=False, window_notes=(4, 8)))
    lengths = set()
    for key in jax.random.split(jax.random.PRNGKey(0), 20):
        w = sample(songs, key)
        n, first = int(w.n), int(w.first)
        lengths.add(n)
        assert 4 <= n <= 7 and 0 <= first <= 30 - (n - 1)          # a rest + 3..6 notes, U{4..7}
        assert np_(w.dur)[0] == 5 and not np_(w.left)[0].any() and not np_(w.pick)[0].any()
        np.testing.assert_array_equal(np_(w.left)[1:n], song_left[first:first + n - 1])     # consecutive notes
        # 1/16 = 9 frames; 1/2 = 72 frames, capped at max_note_frames = 50
        assert np_(w.dur)[1:n].tolist() == [9 if (first + r) % 2 == 0 else 50 for r in range(n - 1)]
        assert not np_(w.dur)[n:].any() and not np_(w.left)[n:].any() and (np_(w.frets)[n:] == X).all()
    assert lengths == {4, 5, 6, 7}


def test_training_windows_are_augmented_as_a_whole():
    songs = songs_of(long_song())
    song_left = np_(songs.left[0])
    sample = jax.jit(partial(CU.sample_window, capacity=16, sequential=False, window_notes=(4, 8), shift_prob=1.0,
                             tempo_prob=1.0, tempo_delta=20))
    offsets, sixteenths = set(), set()
    for key in jax.random.split(jax.random.PRNGKey(1), 40):
        w = sample(songs, key)
        n, first = int(w.n), int(w.first)
        left, orig = np_(w.left)[1:n], song_left[first:first + n - 1]
        offset = set((left - orig)[orig > 0].tolist())
        assert len(offset) == 1                                   # one fret offset for the whole window
        offsets |= offset
        assert (left[orig <= 0] == orig[orig <= 0]).all()          # open and don't-care strings stay
        assert left[left > 0].min() >= 1 and left[left > 0].max() <= 22
        assert (np_(w.frets)[1:n, 0] == left[:, 0]).all()          # what sounds moves with the goal
        # one tempo for the window: 100 +- 20 BPM makes a 1/16 round(900 / 120) = 8 .. round(900 / 80) = 11 frames
        # (7.5 rounds to 8); a 1/2 note is then 64..88 frames, capped at 50
        short = {int(d) for r, d in enumerate(np_(w.dur)[1:n]) if (first + r) % 2 == 0}
        assert len(short) == 1 and 8 <= min(short) <= 11
        assert all(d == 50 for r, d in enumerate(np_(w.dur)[1:n]) if (first + r) % 2 == 1)
        sixteenths |= short
    # the window's frets bound its offset: 3 consecutive notes press at least 3..5 and at most 3..7, so -2..17
    assert len(offsets) > 5 and all(-2 <= o <= 17 for o in offsets)
    assert len(sixteenths) >= 3


def note_coverage(even_notes, keys=4000):
    """The share of training windows (U{4..7}: 3..6 notes) of `long_song` (30 notes) that hold each note."""
    songs = songs_of(long_song())
    draw = jax.jit(jax.vmap(lambda k: CU.sample_window(songs, k, 16, sequential=False, window_notes=(4, 8),
                                                       even_notes=even_notes)))
    w = draw(jax.random.split(jax.random.PRNGKey(4), keys))
    first, notes = np_(w.first), np_(w.n) - 1
    song_left = np_(songs.left[0])
    for i in range(0, keys, 97):                                  # consecutive notes of the song, a rest before them
        assert notes[i] >= 1 and first[i] >= 0 and first[i] + notes[i] <= 30
        np.testing.assert_array_equal(np_(w.left)[i, 1:notes[i] + 1], song_left[first[i]:first[i] + notes[i]])
        assert not np_(w.left)[i, 0].any() and not np_(w.left)[i, notes[i] + 1:].any()
    held = (np.arange(30)[None, :] >= first[:, None]) & (np.arange(30)[None, :] < (first + notes)[:, None])
    return held.mean(axis=0)


def test_training_windows_hold_the_first_and_last_notes_less_unless_even():
    # m notes a window, m ~ U{3..6}. The paper's start ~ U{0..30-m}: note 0 lies in 1 of 31-m windows, a middle note
    # in m of them: means over m 0.0378 and 0.1719. Even: start ~ U{1-m..29}, every note in m of 29+m: 0.1334.
    paper = note_coverage(False)
    np.testing.assert_allclose(paper[[0, 29]], 0.0378, atol=0.01)
    np.testing.assert_allclose(paper[6:24], 0.1719, atol=0.02)
    np.testing.assert_allclose(note_coverage(True), 0.1334, atol=0.02)


def test_tempo_change_never_below_30_bpm():
    # 1/16 notes at 35 BPM: 900 / 35 = 25.7 -> 26 frames; 35 - 20 = 15 BPM is raised to 30: at most 900 / 30 = 30
    songs = songs_of(Song(35, [make_note(F(1, 16), (0, X, X, X, X, X))] * 12))
    sample = jax.jit(jax.vmap(lambda k: CU.sample_window(songs, k, 16, sequential=False, tempo_prob=1.0,
                                                         max_note_frames=100).dur[1]))
    sixteenth = np_(sample(jax.random.split(jax.random.PRNGKey(2), 200)))
    assert sixteenth.max() == 30 and sixteenth.min() >= 16           # 55 BPM: 900 / 55 = 16.4 -> 16
    # tempos 15..30 (bumps -20..-5, 16 of 41) all play at 30 BPM: without the floor only 30 itself (1 of 41) would
    assert 0.3 < np.mean(sixteenth == 30) < 0.5


def test_training_window_of_a_short_song_holds_the_whole_song():
    w = CU.sample_window(songs_of(song_3_to_7()), jax.random.PRNGKey(3), 24, sequential=False)
    assert int(w.n) == 4 and int(w.first) == 0                    # U{10..19} notes asked, 3 in the song
    assert np_(w.dur).tolist()[:5] == [5, 18, 18, 36, 0]


def test_songs_are_drawn_by_their_notes_and_padding_never():
    songs = TL.batch([TL.from_song(song_a()), TL.from_song(song_3_to_7())], songs=4, notes=8)
    np.testing.assert_allclose(np_(CU.song_weights(songs)), [np.log(4), np.log(3), -np.inf, -np.inf])
    draw = jax.jit(jax.vmap(lambda k: CU.sample_window(songs, k, 8, sequential=False).song))
    drawn = np_(draw(jax.random.split(jax.random.PRNGKey(0), 700)))
    assert set(drawn.tolist()) == {0, 1}
    assert 0.5 < np.mean(drawn == 0) < 0.65                       # 4/7 = 0.57


# ------------------------------------------------------------------------------------------------------ re-timing

def frames(song, tempo, min_frames=5):
    tl = TL.from_song(song)
    return np_(jax.jit(CU.note_frames, static_argnums=4)(tl.ticks, tl.ticks > 0, tl.ticks_per_whole,
                                                         jnp.float32(tempo), min_frames)).tolist()


def from_song_frames(song, tempo):
    return np.diff(np_(TL.from_song(Song(tempo, song.notes)).onset)).tolist()


def test_note_frames_at_another_tempo():
    sixteenths = Song(100, [make_note(F(1, 16), (0,) * 6)] * 3)
    assert frames(sixteenths, 105) == [9, 9, 9]                   # 900 / 105 = 8.57 -> 9
    assert frames(song_a(), 120) == [8, 16, 8, 64]                # 900 / 120 = 7.5 -> 8 (half-to-even)
    assert frames(song_a(), 150) == [6, 12, 6, 48]                # 900 / 150 = 6
    assert frames(song_a(), 60) == [15, 30, 15, 120]              # 900 / 60 = 15
    # triplets written at 100, played at 105: 1/12 -> 11.43 -> 11 frames, 132 per whole; an eighth is 16.5 frames,
    # cumulative 0, 16.5, 33, 49.5, 60.5, 71.5, 82.5, 99 round half-to-even to 0, 16, 33, 50, 60, 72, 82, 99
    e, t = F(1, 8), F(1, 12)
    assert frames(Song(100, [make_note(d, (0, X, X, X, X, X)) for d in (e, e, e, t, t, t, e)]), 105) == \
        [16, 17, 17, 10, 12, 10, 17]
    # 2, 2 and 4 whole notes written at 120, played at 100: a whole note is 144 frames -> 288, 288, 576
    assert frames(Song(120, [make_note(d, (0, X, X, X, X, X)) for d in (2, 2, 4)]), 100) == [288, 288, 576]
    # 1/32 at 120 BPM: 450 / 120 = 3.75 -> 4 frames, raised to min_frames 5
    thirty_seconds = Song(120, [make_note(F(1, 32), (0,) * 6)] * 2)
    assert frames(thirty_seconds, 120) == [5, 5] and frames(thirty_seconds, 120, min_frames=1) == [4, 4]


def test_note_frames_round_the_shortest_valid_note():
    # song_a without its 1/16 notes at 105 BPM: the 1/8 note is the shortest, 1800 / 105 = 17.14 -> 17 frames,
    # and the half note 4 x 17 = 68; the rows left out get 0
    tl = TL.from_song(song_a())
    got = CU.note_frames(tl.ticks, jnp.array([False, True, False, True]), tl.ticks_per_whole, 105.0, 5)
    assert np_(got).tolist() == [0, 17, 0, 68]


def test_retiming_slower_and_faster_agrees_with_from_song():
    e, t = F(1, 8), F(1, 12)
    songs = [song_a(), song_3_to_7(),
             Song(100, [make_note(d, (0, X, X, X, X, X)) for d in (e, e, e, t, t, t, e)]),
             Song(120, [make_note(d, (0, X, X, X, X, X)) for d in (F(3, 8), F(3, 8), F(3, 4), 2)])]
    for song in songs:
        for tempo in (30, 47, 80, 99, 105, 120, 133, 150, 222, 400):
            assert frames(song, tempo) == from_song_frames(song, tempo), (song, tempo)


# ------------------------------------------------------------------------------------------------------ fret shift

def test_shift_frets_keeps_the_shape_on_the_neck():
    tl = TL.from_song(song_3_to_7())
    left, frets, valid = tl.left, tl.frets, jnp.ones(3, bool)
    assert np_(left).tolist() == [[3, -1, 0, 0, 0, 0], [0, 0, 5, 7, 4, -1], [7, 0, 0, 0, 0, -1]]
    shift = jax.jit(jax.vmap(CU.shift_frets, in_axes=(None, None, None, 0, None)))
    lefts, fretss = shift(left, frets, valid, jax.random.split(jax.random.PRNGKey(0), 300), 1.0)
    offsets = set()
    for l_, f_ in zip(np_(lefts), np_(fretss)):
        o = int(l_[0, 0]) - 3
        offsets.add(o)
        assert l_.tolist() == [[3 + o, -1, 0, 0, 0, 0], [0, 0, 5 + o, 7 + o, 4 + o, -1], [7 + o, 0, 0, 0, 0, -1]]
        assert f_.tolist() == [[3 + o, 0, X, X, X, X], [X, X, X, X, 4 + o, X], [7 + o, X, X, X, X, 0]]
    assert offsets == set(range(-2, 16))                          # 3 - 2 = 1 .. 7 + 15 = 22, both ends included
    same = shift(left, frets, valid, jax.random.split(jax.random.PRNGKey(0), 10), 0.0)
    assert (np_(same[0]) == np_(left)).all() and (np_(same[1]) == np_(frets)).all()
    # only the valid rows bound the offset: row 0 alone (fret 3) allows -2 .. 19
    l_, _ = shift(left, frets, jnp.array([True, False, False]), jax.random.split(jax.random.PRNGKey(1), 300), 1.0)
    assert {int(x) - 3 for x in np_(l_)[:, 0, 0]} == set(range(-2, 20))
    # nothing pressed: nothing moves
    open_only = TL.from_song(Song(100, [make_note(F(1, 4), (0, X, X, X, X, X))]))
    l_, f_ = CU.shift_frets(open_only.left, open_only.frets, jnp.ones(1, bool), jax.random.PRNGKey(0), 1.0)
    assert np_(l_).tolist() == [[-1, 0, 0, 0, 0, 0]] and np_(f_).tolist() == [[0, X, X, X, X, X]]


# ------------------------------------------------------------------------------------------------------ goals

def test_left_goal_by_hand():
    w = sequential(songs_of(song_a()))                            # rows: rest 5, then 9, 18, 9, 72 frames
    # row 0 (the rest), frame 0: timers 5 -> 5/20-1 = -0.75; 9 -> -0.55; 18 -> -0.1; 9 -> -0.55; 72 -> clipped +1
    np.testing.assert_allclose(np_(CU.left_goal(at(w, 0, 0))).reshape(5, 7), [
        [0, 0, 0, 0, 0, 0, -0.75],
        [3 / 22, 0, -1, 0, 0, 0, -0.55],
        [0, 5 / 22, 0, 0, 0, 0, -0.1],
        [0, 0, 0, 7 / 22, 0, 0, -0.55],
        [0, 0, 0, 0, 0, 0, 1.0],
    ], atol=1e-6)
    # row 2 (the 1/8 note), 3 frames in: 18 - 3 = 15 left -> -0.25; then rows 3, 4 and two past the end (0 -> -1)
    np.testing.assert_allclose(np_(CU.left_goal(at(w, 2, 3))).reshape(5, 7), [
        [0, 5 / 22, 0, 0, 0, 0, -0.25],
        [0, 0, 0, 7 / 22, 0, 0, -0.55],
        [0, 0, 0, 0, 0, 0, 1.0],
        [0, 0, 0, 0, 0, 0, -1.0],
        [0, 0, 0, 0, 0, 0, -1.0],
    ], atol=1e-6)
    over = np_(CU.left_goal(at(w, 5, 0))).reshape(5, 7)           # past the end: everything padding
    assert not over[:, :6].any() and (over[:, 6] == -1).all()


def test_right_goal_with_done():
    w = sequential(songs_of(song_a()), fill_strum_gaps=False)
    # row 1, 3 frames in: 9 - 3 = 6 left -> 6/20-1 = -0.7; row 1 picks strings 1 and 3, row 2 string 2, row 3 is a
    # hammer-on, row 4 a rest, row 5 past the end
    g = np_(CU.right_goal(at(w, 1, 3), jnp.zeros(6, bool))).reshape(5, 7)
    np.testing.assert_allclose(g[:, :6], [[1, 0, 1, 0, 0, 0], [0, 1, 0, 0, 0, 0]] + [[0] * 6] * 3)
    np.testing.assert_allclose(g[:, 6], [-0.7, -0.1, -0.55, 1.0, -1.0], atol=1e-6)
    done = jnp.array([True, False, False, False, False, False])
    g = np_(CU.right_goal(at(w, 1, 3), done)).reshape(5, 7)
    np.testing.assert_allclose(g[0, :6], [0, 0, 1, 0, 0, 0])     # string 1 already picked in this note
    np.testing.assert_allclose(g[1, :6], [0, 1, 0, 0, 0, 0])     # later notes are not masked


# ------------------------------------------------------------------------------------------------------ advancing

def test_advance_and_current():
    w = sequential(songs_of(song_a()), fill_strum_gaps=False)     # rows of 5, 9, 18, 9, 72 frames: 113 in all
    left, pick, dur = CU.current(CU.start(w))
    assert not np_(left).any() and not np_(pick).any() and int(dur) == 5

    def step(cursor, _):
        cursor, end = CU.advance(cursor)
        return cursor, (end, cursor.note, cursor.over)
    cursor, (end, note, over) = jax.jit(lambda c: jax.lax.scan(step, c, None, length=113))(CU.start(w))
    # each row ends after exactly its frames: at the 5th, 14th, 32nd, 41st and 113th frame
    assert np.flatnonzero(np_(end)).tolist() == [4, 13, 31, 40, 112]
    assert np_(note)[[3, 4, 12, 13]].tolist() == [0, 1, 1, 2]
    assert not np_(over)[:112].any() and bool(np_(over)[112]) and bool(cursor.over)
    left, pick, _ = CU.current(at(w, 1, 4))
    assert np_(left).tolist() == [3, 0, -1, 0, 0, 0] and np_(pick).tolist() == [True, False, True, False, False, False]
    # past the end nothing is asked, even where the last row (rows rest, 18, 18, 36 frames) picks strings 1 and 6
    full = sequential(songs_of(song_3_to_7()), capacity=4, fill_strum_gaps=False)
    assert np_(CU.current(at(full, 3, 0))[1]).tolist() == [True, False, False, False, False, True]
    assert not np_(CU.current(at(full, 4, 0))[1]).any()


# ------------------------------------------------------------------------------------------------------ batches, jit

def test_batch_vmap_and_jit_with_traced_inputs():
    a, b = TL.from_song(song_a()), TL.from_song(song_3_to_7())
    songs = TL.batch([a, b], notes=8)
    sample = jax.jit(lambda songs, key, song: CU.sample_window(songs, key, 8, sequential=True, song=song))
    windows = jax.vmap(sample, in_axes=(None, 0, 0))(songs, jax.random.split(jax.random.PRNGKey(0), 2),
                                                     jnp.array([0, 1]))
    assert np_(windows.n).tolist() == [5, 4]
    assert np_(windows.dur).tolist() == [[5, 9, 18, 9, 72, 0, 0, 0], [5, 18, 18, 36, 0, 0, 0, 0]]
    cursors = CU.Cursor(windows, jnp.array([2, 1]), jnp.array([3, 4]))
    got = np_(jax.jit(jax.vmap(CU.left_goal))(cursors)).reshape(2, 5, 7)
    np.testing.assert_allclose(got[0], np_(CU.left_goal(at(sequential(songs_of(song_a())), 2, 3))).reshape(5, 7))
    # song 2, row 1, 4 frames in: 18 - 4 = 14 left -> -0.3; then 18 -> -0.1, 36 -> 0.8 and two past the end
    np.testing.assert_allclose(got[1], [
        [3 / 22, -1, 0, 0, 0, 0, -0.3],
        [0, 0, 5 / 22, 7 / 22, 4 / 22, -1, -0.1],
        [7 / 22, 0, 0, 0, 0, -1, 0.8],
        [0, 0, 0, 0, 0, 0, -1.0],
        [0, 0, 0, 0, 0, 0, -1.0],
    ], atol=1e-6)
    done = jnp.ones((2, 6), bool)
    r = np_(jax.jit(jax.vmap(CU.right_goal))(cursors, done)).reshape(2, 5, 7)
    assert not r[:, 0, :6].any()                                  # the current rows' strings are all done
    # row 2 picks string 5; row 3 strums strings 1 and 6, so every string between them too
    assert r[1, 1, :6].tolist() == [0, 0, 0, 0, 1, 0] and r[1, 2, :6].tolist() == [1] * 6
    # a traced song index gives the same window as a constant one
    w = sample(songs, jax.random.PRNGKey(5), jnp.int32(1))
    assert np_(w.dur).tolist() == np_(windows.dur[1]).tolist() and int(w.song) == 1
    cursor, end = jax.jit(CU.advance)(at(w, 1, 17))
    assert bool(end) and int(cursor.note) == 2 and int(cursor.note_frame) == 0
