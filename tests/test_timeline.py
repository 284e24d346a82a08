"""Timeline: frame rounding, goal encodings, augmentation, batching and jit. Expected numbers are worked by hand."""
from fractions import Fraction as F

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from dexguitar.music import timeline as tlm
from dexguitar.music.song import MUTE as M, Effect, Song, make_note
from dexguitar.music.timeline import (
    from_song, frames_left, frames_per_whole, left_goal, note_at, random_shift, random_tempo, retime, right_goal,
    shift, shift_range, stack)

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
    nof = np_(tl.note_of_frame)
    assert nof.shape == (108,)
    assert (nof[:9] == 0).all() and (nof[9:27] == 1).all() and (nof[27:36] == 2).all() and (nof[36:] == 3).all()
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


def test_capacities():
    tl = from_song(song_a(), note_capacity=6, frame_capacity=120)
    assert tl.left.shape == (6, 6) and tl.onset.shape == (7,) and tl.note_of_frame.shape == (120,)
    assert np_(tl.onset).tolist() == [0, 9, 27, 36, 108, 108, 108]
    assert (np_(tl.note_of_frame)[108:] == 4).all()
    assert (np_(tl.frets)[4:] == -1).all() and (np_(tl.left)[4:] == 0).all() and not np_(tl.pick)[4:].any()
    with pytest.raises(ValueError):
        from_song(song_a(), note_capacity=3)
    with pytest.raises(ValueError):
        from_song(song_a(), frame_capacity=107)


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


def test_note_at_and_frames_left():
    tl = from_song(song_a())
    assert [int(note_at(tl, f)) for f in (0, 8, 9, 26, 27, 36, 107, 108, 500)] == [0, 0, 1, 1, 2, 3, 3, 4, 4]
    assert [int(frames_left(tl, f)) for f in (0, 8, 9, 12, 107, 108)] == [9, 1, 18, 15, 1, 0]


def test_left_goal_by_hand():
    tl = from_song(song_a())
    # frame 0: notes 0..3 and one past the end. Timers: 9 left -> 9/20-1 = -0.55; 18 -> -0.1; 9 -> -0.55;
    # 72 -> clipped to +1; past the end -> 0 frames -> -1 with all-zero frets.
    g = np_(left_goal(tl, 0)).reshape(5, 7)
    np.testing.assert_allclose(g, [
        [3 / 22, 0, -1, 0, 0, 0, -0.55],
        [0, 5 / 22, 0, 0, 0, 0, -0.1],
        [0, 0, 0, 7 / 22, 0, 0, -0.55],
        [0, 0, 0, 0, 0, 0, 1.0],
        [0, 0, 0, 0, 0, 0, -1.0],
    ], atol=1e-6)
    # frame 12, inside note 1 (frames 9..26): 27-12 = 15 left -> -0.25; then notes 2, 3 and two past the end
    g = np_(left_goal(tl, 12)).reshape(5, 7)
    np.testing.assert_allclose(g, [
        [0, 5 / 22, 0, 0, 0, 0, -0.25],
        [0, 0, 0, 7 / 22, 0, 0, -0.55],
        [0, 0, 0, 0, 0, 0, 1.0],
        [0, 0, 0, 0, 0, 0, -1.0],
        [0, 0, 0, 0, 0, 0, -1.0],
    ], atol=1e-6)
    # past the end: everything padding
    np.testing.assert_allclose(np_(left_goal(tl, 108)).reshape(5, 7)[:, 6], -1.0)
    assert not np_(left_goal(tl, 108)).reshape(5, 7)[:, :6].any()


def test_right_goal_with_done():
    tl = from_song(song_a())
    g = np_(right_goal(tl, 3)).reshape(5, 7)
    # frame 3: 6 frames left -> 6/20-1 = -0.7; note 0 picks strings 1 and 3, note 1 string 2, note 2 is a hammer-on
    np.testing.assert_allclose(g[:, :6], [[1, 0, 1, 0, 0, 0], [0, 1, 0, 0, 0, 0]] + [[0] * 6] * 3)
    np.testing.assert_allclose(g[:, 6], [-0.7, -0.1, -0.55, 1.0, -1.0], atol=1e-6)
    done = jnp.array([True, False, False, False, False, False])
    g = np_(right_goal(tl, 3, done)).reshape(5, 7)
    np.testing.assert_allclose(g[0, :6], [0, 0, 1, 0, 0, 0])     # string 1 already picked in this note
    np.testing.assert_allclose(g[1, :6], [0, 1, 0, 0, 0, 0])     # later notes are not masked


# ------------------------------------------------------------------------------------------------------ augmentation

def song_3_to_7():
    return Song(100, [
        make_note(F(1, 8), (3, 0, X, X, X, X)),
        make_note(F(1, 8), (X, X, X, X, 4, X), chord=(X, X, 5, 7, 4, 0)),   # chord frets 4..7, open string 6
        make_note(F(1, 4), (7, X, X, X, X, 0)),
    ])


def test_shift_and_range():
    tl = from_song(song_3_to_7())
    lo, hi = shift_range(tl)
    assert (int(lo), int(hi)) == (-2, 15)          # 3 - 2 = 1 and 7 + 15 = 22
    up = shift(tl, 2)
    assert np_(up.left).tolist() == [[5, -1, 0, 0, 0, 0], [0, 0, 7, 9, 6, -1], [9, 0, 0, 0, 0, -1]]
    assert np_(up.frets).tolist() == [[5, 0, X, X, X, X], [X, X, X, X, 6, X], [9, X, X, X, X, 0]]
    assert (np_(up.pick) == np_(tl.pick)).all()
    assert tuple(int(v) for v in shift_range(up)) == (-4, 13)
    top = shift(tl, 15)
    assert int(np_(top.left).max()) == 22 and tuple(int(v) for v in shift_range(top)) == (-17, 0)
    open_only = from_song(Song(100, [make_note(F(1, 4), (0, X, X, X, X, X))]))
    assert tuple(int(v) for v in shift_range(open_only)) == (0, 0)


def test_random_shift_stays_on_the_neck():
    tl = from_song(song_3_to_7())
    f = jax.jit(random_shift)
    seen = set()
    for k in jax.random.split(jax.random.PRNGKey(0), 40):
        s = f(k, tl)
        pressed = np_(s.left)[np_(s.left) > 0]
        assert pressed.min() >= 1 and pressed.max() <= 22
        seen.add(int(np_(s.left)[0, 0]) - 3)
    assert len(seen) > 5 and all(-2 <= o <= 15 for o in seen)


def assert_same(a, b):
    for (path, x), y in zip(jax.tree_util.tree_leaves_with_path(a), jax.tree_util.tree_leaves(b)):
        np.testing.assert_array_equal(np_(x), np_(y), err_msg=jax.tree_util.keystr(path))


def test_retime_faster_equals_from_song():
    tl = from_song(song_a())
    # 120 BPM: 1/16 = 900/120 = 7.5 -> 8 (half-to-even) -> 128 per whole, 112.5 BPM effective;
    # onsets 0, 8, 24, 32 and end 12/16 * 128 = 96
    fast = retime(tl, 120.0)
    assert np_(fast.onset).tolist() == [0, 8, 24, 32, 96]
    assert int(fast.n_frames) == 96 and float(fast.tempo) == 112.5
    assert (np_(fast.note_of_frame)[96:] == 4).all() and np_(fast.note_of_frame)[24] == 2
    assert_same(fast, from_song(song_a(120), frame_capacity=108))
    # 150 BPM: 900/150 = 6 frames -> 96 per whole -> onsets 0, 6, 18, 24, end 72
    assert np_(retime(tl, 150).onset).tolist() == [0, 6, 18, 24, 72]
    assert_same(jax.jit(retime)(tl, jnp.float32(150)), from_song(song_a(150), frame_capacity=108))
    # triplets at 105 through retime from 100 BPM give the hand-worked onsets above
    e, t = F(1, 8), F(1, 12)
    trip = Song(100, [make_note(d, (0, X, X, X, X, X)) for d in (e, e, e, t, t, t, e)])
    assert np_(jax.jit(retime)(from_song(trip, frame_capacity=200), 105).onset).tolist() == \
        [0, 16, 33, 50, 60, 72, 82, 99]


def test_retime_slower_truncates_and_recovers():
    song = Song(100, list(song_a().notes) + [make_note(F(1, 16), (0, X, X, X, X, X))])
    tl = from_song(song)                       # onsets 0, 9, 27, 36, 108, 117
    assert tl.frame_capacity == 117
    # 60 BPM: 900/60 = 15 frames -> onsets 0, 15, 45, 60, 180, 195: note 4 starts past T = 117 and is dropped,
    # note 3 is cut at frame 117
    slow = retime(tl, 60)
    assert int(slow.n_notes) == 4 and int(slow.n_frames) == 117
    assert np_(slow.onset).tolist() == [0, 15, 45, 60, 117, 117]
    assert int(note_at(slow, 116)) == 3 and int(note_at(slow, 117)) == 4
    assert np_(left_goal(slow, 60)).reshape(5, 7)[1, 6] == -1.0   # dropped note reads as padding
    assert_same(retime(slow, 100), tl)


def test_random_tempo():
    tl = from_song(song_a(), frame_capacity=300)
    f = jax.jit(random_tempo)
    tempos = {float(f(k, tl).base_tempo) for k in jax.random.split(jax.random.PRNGKey(1), 30)}
    assert all(80 <= t <= 120 and t == int(t) for t in tempos) and len(tempos) > 5
    slow = from_song(Song(35, song_a().notes), frame_capacity=1000)
    assert min(float(f(k, slow).base_tempo) for k in jax.random.split(jax.random.PRNGKey(2), 30)) >= 30


# ------------------------------------------------------------------------------------------------------ batching, jit

def test_stack_and_vmap():
    a = from_song(song_a())                                    # 4 notes, 108 frames
    b = from_song(song_3_to_7())                               # 1/8 = 18 frames: onsets 0, 18, 36, 72
    assert np_(b.onset).tolist() == [0, 18, 36, 72]
    batch = stack([a, b])
    assert batch.left.shape == (2, 4, 6) and batch.note_of_frame.shape == (2, 108) and batch.n_notes.shape == (2,)
    assert np_(batch.onset[1]).tolist() == [0, 18, 36, 72, 72]
    assert np_(batch.frets[1, 3]).tolist() == [-1] * 6 and np_(batch.whole[1, 3]) == 0
    assert (np_(batch.note_of_frame[1, 72:]) == 3).all()
    frames = jnp.array([12, 40])
    got = jax.jit(jax.vmap(left_goal))(batch, frames)
    np.testing.assert_allclose(np_(got[0]), np_(left_goal(a, 12)))
    np.testing.assert_allclose(np_(got[1]), np_(left_goal(b, 40)))
    done = jnp.zeros((2, 6), bool).at[1, 0].set(True)
    r = jax.vmap(right_goal)(batch, frames, done)
    np.testing.assert_allclose(np_(r[1]), np_(right_goal(b, 40, done[1])))
    # per-song augmentation inside vmap
    fast = jax.vmap(retime)(batch, jnp.array([150.0, 120.0]))
    assert np_(fast.onset[0]).tolist() == [0, 6, 18, 24, 72]
    assert np_(fast.onset[1]).tolist()[:4] == [0, 15, 30, 60]    # 1/8 at 120 BPM = 15 frames
    lo, hi = jax.vmap(shift_range)(batch)
    assert np_(lo).tolist() == [-2, -2] and np_(hi).tolist() == [15, 15]


def test_jit_with_traced_inputs():
    tl = from_song(song_a())
    lg = jax.jit(left_goal)
    for f in (0, 12, 50, 108):
        np.testing.assert_allclose(np_(lg(tl, jnp.int32(f))), np_(left_goal(tl, f)))
    rg = jax.jit(right_goal)
    np.testing.assert_allclose(np_(rg(tl, jnp.int32(3), jnp.ones(6, bool))).reshape(5, 7)[0, :6], 0)
    sh = jax.jit(shift)(tl, jnp.int32(4))
    assert np_(sh.left)[0, 0] == 7 and np_(sh.left)[0, 2] == -1
    assert_same(jax.jit(retime)(tl, jnp.float32(120)), retime(tl, 120.0))
    assert jax.jit(frames_left)(tl, jnp.int32(12)) == 15 and jax.jit(note_at)(tl, jnp.int32(12)) == 1
