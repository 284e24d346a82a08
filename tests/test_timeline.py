"""Timeline: frame rounding, timing limits, goal codes, padding and batching. Expected numbers are worked by hand.
The song cursor (windows, re-timing, fret shift, goals, jit) is tested in test_cursor.py."""
from fractions import Fraction as F

import jax
import numpy as np
import pytest

from dexguitar.music import timeline as tlm
from dexguitar.music.song import MUTE as M, Effect, Song, SongError, make_note
from dexguitar.music.timeline import batch, fret_code, from_song, frames_per_whole, goal_vector, pad, stack, timer_code

X = M  # shorthand in fret tuples: string not played


def song_a(tempo=100):
    """1/16, 1/8, 1/16, 1/2 at 100 BPM: 1/16 = 900/100 = 9 frames, 144 frames per whole.

    cumulative wholes 0, 1/16, 3/16, 4/16, 12/16 -> onsets 0, 9, 27, 36, 108 (durations 9, 18, 9, 72).
    """
    return Song(tempo, [
        make_note(F(1, 16), (3, X, 0, X, X, X)),            # string 1 fret 3, string 3 open
        make_note(F(1, 8), (X, 5, X, X, X, X)),
        make_note(F(1, 16), (X, X, X, 7, X, X), effects=(0, 0, 0, Effect.HAMMER, 0, 0)),
        make_note(F(1, 2), (X, X, X, X, X, X)),             # rest
    ])


def np_(x):
    return np.asarray(x)


# ------------------------------------------------------------------------------------------------------ rounding

def test_frames_per_whole_rounds_tempo():
    # 1/16 at 105 BPM: 1/16 * 14400 / 105 = 8.571 -> 9 frames -> 144 frames per whole -> 14400 / 144 = 100 BPM
    assert frames_per_whole(105, F(1, 16)) == 144
    assert tlm.effective_tempo(144) == 100
    tl = from_song(Song(105, [make_note(F(1, 16), (0,) * 6)] * 3))
    assert float(tl.tempo) == 100 and float(tl.base_tempo) == 105
    assert np_(tl.onset).tolist() == [0, 9, 18, 27]
    # 1/32 at 120 BPM: 450 / 120 = 3.75 -> 4 -> raised to min_frames 5 -> 160 per whole -> 90 BPM
    assert frames_per_whole(120, F(1, 32)) == 160
    assert frames_per_whole(120, F(1, 32), min_frames=1) == 128
    # a tie rounds half-to-even like numpy: 1/16 at 120 BPM = 7.5 -> 8; 1/8 at 80 BPM = 22.5 -> 22
    assert frames_per_whole(120, F(1, 16)) == 128
    assert frames_per_whole(80, F(1, 8)) == 176


def test_onsets_sixteenths_and_eighths():
    tl = from_song(song_a())
    assert np_(tl.onset).tolist() == [0, 9, 27, 36, 108]
    assert int(tl.n_frames) == 108 and int(tl.n_notes) == 4
    assert float(tl.tempo) == 100
    np.testing.assert_allclose(np_(tl.whole), [1 / 16, 1 / 8, 1 / 16, 1 / 2])


def test_triplets_cumulative_rounding():
    # shortest = triplet eighth = 1/12 whole; at 105 BPM 1/12 * 14400 / 105 = 11.43 -> 11 frames -> 132 per whole,
    # effective tempo 14400 / 132 = 109.09. An eighth is 132 / 8 = 16.5 frames, so the cumulative positions
    #   0, 1/8, 2/8, 3/8, 3/8+1/12, 3/8+2/12, 5/8, 6/8 (x 132) = 0, 16.5, 33, 49.5, 60.5, 71.5, 82.5, 99
    # round half-to-even to 0, 16, 33, 50, 60, 72, 82, 99 (durations 16, 17, 17, 10, 12, 10, 17; sum 99 = 6/8 * 132)
    e, t = F(1, 8), F(1, 12)
    song = Song(105, [make_note(d, (0, X, X, X, X, X)) for d in (e, e, e, t, t, t, e)])
    tl = from_song(song)
    assert np_(tl.onset).tolist() == [0, 16, 33, 50, 60, 72, 82, 99]
    assert float(tl.tempo) == pytest.approx(14400 / 132)
    assert int(tl.ticks_per_whole) == 24 and np_(tl.ticks).tolist() == [3, 3, 3, 2, 2, 2, 3]


def test_notes_longer_than_a_bar():
    # 2, 2 and 4 whole notes at 120 BPM: a whole note is 4 beats of 0.5 s = 120 frames; the shortest note (2 whole)
    # is 240 frames exactly, so the tempo stays 120. One tick = 1 whole note.
    song = Song(120, [make_note(d, (0, X, X, X, X, X)) for d in (2, 2, 4)])
    tl = from_song(song)
    assert np_(tl.onset).tolist() == [0, 240, 480, 960] and float(tl.tempo) == 120
    assert int(tl.ticks_per_whole) == 1 and np_(tl.ticks).tolist() == [2, 2, 4]
    # at 100 BPM the 2 whole notes last 2 * 14400 / 100 = 288 frames: onsets 0, 288, 576, 1152
    assert np_(from_song(Song(100, song.notes)).onset).tolist() == [0, 288, 576, 1152]


def test_dotted_notes_keep_their_length():
    # Dotted quarter, dotted quarter, dotted half at 120 BPM: a quarter is 0.5 s = 30 frames, so 45, 45 and 90
    # frames and the tempo stays 120. One tick = 1/8 (3, 3 and 6 ticks).
    song = Song(120, [make_note(d, (0, X, X, X, X, X)) for d in (F(3, 8), F(3, 8), F(3, 4))])
    tl = from_song(song)
    assert np_(tl.onset).tolist() == [0, 45, 90, 180] and float(tl.tempo) == 120
    assert int(tl.ticks_per_whole) == 8 and np_(tl.ticks).tolist() == [3, 3, 6]


def test_timing_limits():
    quarter = make_note(F(1, 4), (0, X, X, X, X, X))
    # tempo range 20..400: a quarter at 20 BPM is 3 s = 180 frames, at 400 BPM 0.15 s = 9 frames
    assert int(from_song(Song(20, [quarter])).n_frames) == 180
    assert int(from_song(Song(400, [quarter])).n_frames) == 9
    for tempo, text in ((19.9, "19.9"), (400.5, "400.5"), (1e9, "1e+09")):
        with pytest.raises(SongError) as info:
            from_song(Song(tempo, [quarter]))
        assert str(info.value) == f"<input>: tempo {text} BPM is outside 20..400 (quarter-note beats per minute)"
    # one frame at 120 BPM is 120 / 14400 = 1/120 of a whole note: a 1/120 note is the shortest allowed (stretched to
    # 5 frames: 5 * 120 = 600 frames per whole, tempo 24), a 1/121 note is refused
    tl = from_song(Song(120, [make_note(F(1, 120), (0, X, X, X, X, X))]))
    assert int(tl.n_frames) == 5 and float(tl.tempo) == 24
    with pytest.raises(SongError, match=r"^<input>:note 1: this note \(duration 1/121\) lasts 0\.99 frames"):
        from_song(Song(120, [quarter, make_note(F(1, 121), (0, X, X, X, X, X))]))
    # length: 900 whole notes at 120 BPM are 900 * 120 = 108000 frames = 30 min, the most a song may last
    assert int(from_song(Song(120, [make_note(900, (0, X, X, X, X, X))])).n_frames) == 108000
    with pytest.raises(SongError, match=r"^<input>:note 1: this note \(duration 900\) ends at frame 108030, past"):
        from_song(Song(120, [quarter, make_note(900, (0, X, X, X, X, X))]))
    # 1/7, 1/11, 1/13, 1/17, 1/19, 1/23 at 60 BPM (shortest 14400 / 60 / 23 = 10.4 frames) need a tick of
    # 1/(7 * 11 * 13 * 17 * 19 * 23) = 1/7436429 whole note: 1/23 is 323323 ticks, and 323323 * 14400 > 2**24
    odd = Song(60, [make_note(F(1, d), (0, X, X, X, X, X)) for d in (7, 11, 13, 17, 19, 23)])
    with pytest.raises(SongError, match=r"^<input>:note 5: durations too fine .*1/23.* tick of 1/7436429 whole"):
        from_song(odd)
    # a note whose ticks overflow int32 when a training window holds only it, re-timed at 30 BPM: at 45 BPM with
    # 1/64 notes (14400 / 64 / 45 = 5 frames, no stretch) a note of 265 whole notes is 265 * 64 = 16960 ticks and
    # 265 * 14400 / 30 = 127200 frames at 30 BPM: 16960 * 127200 = 2.157e9 >= 2**31 = 2.147e9; 264 wholes:
    # 16896 * 126720 = 2.141e9 fits
    sixty_fourth = make_note(F(1, 64), (0, X, X, X, X, X))
    assert int(from_song(Song(45, [sixty_fourth, make_note(264, (0, X, X, X, X, X))])).n_frames) == 5 + 264 * 320
    with pytest.raises(SongError, match=r"^<input>:note 1: this note \(duration 265\) is 16960 ticks of 1/64"):
        from_song(Song(45, [sixty_fourth, make_note(265, (0, X, X, X, X, X))]))


def test_capacity():
    tl = from_song(song_a(), note_capacity=6)
    assert tl.left.shape == (6, 6) and tl.onset.shape == (7,) and tl.note_capacity == 6
    assert np_(tl.onset).tolist() == [0, 9, 27, 36, 108, 108, 108]
    assert (np_(tl.frets)[4:] == -1).all() and (np_(tl.left)[4:] == 0).all() and not np_(tl.pick)[4:].any()
    assert not np_(tl.ticks)[4:].any() and not np_(tl.whole)[4:].any()
    assert_same(pad(from_song(song_a()), 6), tl)                  # padding later is the same as building padded
    with pytest.raises(ValueError):
        from_song(song_a(), note_capacity=3)
    with pytest.raises(ValueError):
        pad(tl, 5)


# ------------------------------------------------------------------------------------------------------ encodings

def test_left_flips_open_mute_and_fills_chord_hint():
    c_major = (0, 1, 0, 2, 3, X)
    song = Song(100, [
        make_note(F(1, 4), (X, 1, 0, 2, 3, X)),
        make_note(F(1, 4), (X, X, X, X, 3, X), chord=c_major),   # arpeggio: pick string 5, hold the C shape
        make_note(F(1, 4), (5, 7, 0, X, X, X), effects=(Effect.TIE, Effect.HAMMER, 0, 0, 0, 0)),
    ])
    tl = from_song(song)
    assert np_(tl.left).tolist() == [
        [0, 1, -1, 2, 3, 0],     # MUTE -> 0, OPEN -> -1
        [-1, 1, -1, 2, 3, 0],    # muted strings take the chord: open -> -1, fret -> k, chord mute -> 0
        [5, 7, -1, 0, 0, 0],
    ]
    assert np_(tl.frets).tolist()[1] == [X, X, X, X, 3, X]   # what sounds is unchanged
    assert np_(tl.pick).tolist() == [
        [False, True, True, True, True, False],
        [False, False, False, False, True, False],   # chord-only strings are not picked
        [False, False, True, False, False, False],   # tied and hammered strings are not picked
    ]
    assert np_(tl.effects)[2].tolist() == [1, 2, 0, 0, 0, 0]


def test_goal_codes():
    # frets: k/22, open -1, don't care 0; timers: clip(frames / 20, 0, 2) - 1
    np.testing.assert_allclose(np_(fret_code([5, 22, -1, 0])), [5 / 22, 1, -1, 0])
    np.testing.assert_allclose(np_(timer_code([0, 10, 20, 40, 100])), [-1, -0.5, 0, 1, 1])
    values = np.arange(30, dtype=np.float32).reshape(5, 6)
    g = np_(goal_vector(values, np.array([True, True, False, True, False]), np.full(5, 0.5))).reshape(5, 7)
    np.testing.assert_array_equal(g[:, :6], values * np.array([1, 1, 0, 1, 0])[:, None])   # invalid notes: zeros
    np.testing.assert_array_equal(g[:, 6], 0.5)                                             # timers kept


def assert_same(a, b):
    for (path, x), y in zip(jax.tree_util.tree_leaves_with_path(a), jax.tree_util.tree_leaves(b)):
        np.testing.assert_array_equal(np_(x), np_(y), err_msg=jax.tree_util.keystr(path))


# ------------------------------------------------------------------------------------------------------ batching

def song_3_to_7():
    """1/8, 1/8, 1/4 at 100 BPM: 1/8 = 1800/100 = 18 frames, so onsets 0, 18, 36, 72."""
    return Song(100, [
        make_note(F(1, 8), (3, 0, X, X, X, X)),
        make_note(F(1, 8), (X, X, X, X, 4, X), chord=(X, X, 5, 7, 4, 0)),
        make_note(F(1, 4), (7, X, X, X, X, 0)),
    ])


def test_stack():
    a, b = from_song(song_a()), from_song(song_3_to_7())            # 4 notes, 108 frames; 3 notes, 72 frames
    both = stack([a, b])
    assert both.left.shape == (2, 4, 6) and both.onset.shape == (2, 5) and both.n_notes.shape == (2,)
    assert np_(both.onset[1]).tolist() == [0, 18, 36, 72, 72]
    assert np_(both.frets[1, 3]).tolist() == [-1] * 6 and np_(both.whole[1, 3]) == 0 and np_(both.ticks[1, 3]) == 0
    assert np_(both.n_notes).tolist() == [4, 3] and np_(both.n_frames).tolist() == [108, 72]
    assert_same(jax.tree.map(lambda x: x[0], both), a)


def test_batch_has_fixed_capacities():
    a, b = from_song(song_a()), from_song(song_3_to_7())
    assert [tlm.capacity(n, 1) for n in (1, 2, 3, 5, 8)] == [1, 2, 4, 8, 8] and tlm.capacity(3, 256) == 256
    full = batch([a, b, a])                                       # 3 songs -> 4, 4 notes -> at least 512
    assert full.left.shape == (4, 512, 6) and full.onset.shape == (4, 513)
    assert np_(full.n_notes).tolist() == [4, 3, 4, 0]             # the fourth song is empty
    assert int(full.ticks_per_whole[3]) == 1 and not np_(full.ticks[3]).any()
    small = batch([a, b], songs=2, notes=8)
    assert small.left.shape == (2, 8, 6) and np_(small.onset[0]).tolist() == [0, 9, 27, 36] + [108] * 5
    with pytest.raises(ValueError):
        batch([a, b, a], songs=2)


def test_one_batch_shape_for_short_and_long_songs():
    """A 4-note song and one of 337 notes (the authors' longest) batch to the same shapes, so one compiled program
    serves both; 600 notes need the next size."""
    long = Song(tempo=120, notes=tuple(make_note(F(1, 8), [M, M, M, M, M, 3 + i % 5]) for i in range(337)))
    longer = Song(tempo=120, notes=long.notes * 2)
    a, b, c = batch([from_song(song_a())]), batch([from_song(long)]), batch([from_song(longer)])
    assert a.left.shape == b.left.shape == (1, 512, 6) and a.onset.shape == b.onset.shape == (1, 513)
    assert c.left.shape == (1, 1024, 6) and int(b.n_notes[0]) == 337
