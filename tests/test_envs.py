"""The env protocol on CPU with 4 envs: jit + vmap, determinism, auto-reset, windows, observation layout."""
import chex
import jax
import jax.extend
import jax.numpy as jnp
import numpy as np
import pytest

from dexguitar import envs
from dexguitar.envs import rewards as R
from dexguitar.music import timeline as TL
from dexguitar.music.song import Song, make_note

N_ENVS = 4


def scale_song():
    """Eight eighth notes on string 2 at 100 BPM (1/8 = 0.3 s = 18 frames)."""
    return Song(100, tuple(make_note("1/8", [-1, f, -1, -1, -1, -1]) for f in (1, 3, 5, 6, 8, 6, 5, 3)), "scale")


def chord_song():
    return Song(100, (make_note("1/4", [1, 1, 2, 3, 3, 1]), make_note("1/4", [0, 1, 0, 2, 3, -1]),
                      make_note("1/4", [-1] * 6)), "chords")


@pytest.fixture(scope="module")
def left():
    env = envs.make("left", [scale_song(), chord_song()], episode_frames=12)
    return env, jax.jit(jax.vmap(env.reset)), jax.jit(jax.vmap(env.step))


def rollout(reset, step, key, actions):
    state = reset(jax.random.split(key, N_ENVS))
    out = []
    for a in actions:
        state = step(state, a)
        out.append(state)
    return out


def test_same_key_same_trajectory_and_auto_reset(left):
    env, reset, step = left
    actions = 0.05 * jax.random.normal(jax.random.PRNGKey(1), (14, N_ENVS, env.action_size))
    a = rollout(reset, step, jax.random.PRNGKey(0), actions)
    b = rollout(reset, step, jax.random.PRNGKey(0), actions)
    c = rollout(reset, step, jax.random.PRNGKey(2), actions)
    for sa, sb in zip(a, b):
        np.testing.assert_array_equal(np.asarray(sa.obs), np.asarray(sb.obs))
        np.testing.assert_array_equal(np.asarray(sa.reward), np.asarray(sb.reward))
    assert not np.array_equal(np.asarray(a[3].obs), np.asarray(c[3].obs))
    assert a[0].obs.shape == (N_ENVS, env.obs_size) == (N_ENVS, 2 * 16 * 13 + 35)
    assert a[0].reward.shape == (N_ENVS, 6)
    # small actions around the home pose never fail, so every env times out at step 12 and starts over
    done = np.stack([np.asarray(s.done) for s in a])
    assert not done[:11].any() and done[11].all()
    assert np.all(np.asarray(a[11].lifetime) == 0) and np.all(np.asarray(a[12].lifetime) == 1)
    assert not np.asarray(a[11].terminated).any()
    assert all(np.isfinite(np.asarray(s.obs)).all() for s in a)


def test_non_finite_physics_terminates_and_resets_only_that_env(left):
    env, reset, step = left
    state = reset(jax.random.split(jax.random.PRNGKey(0), N_ENVS))
    state = step(state, jnp.zeros((N_ENVS, env.action_size)))
    action = jnp.zeros((N_ENVS, env.action_size)).at[1, 3].set(jnp.nan)   # one NaN number for env 1
    state = step(state, action)
    # during the grace frames nothing may terminate, except physics that is no longer finite
    assert np.asarray(state.info["nonfinite"]).tolist() == [False, True, False, False]
    assert np.asarray(state.terminated).tolist() == [False, True, False, False]
    np.testing.assert_array_equal(np.asarray(state.reward)[1], [-25.0] * 6)     # the terminal reward, not NaN
    assert np.asarray(state.lifetime).tolist() == [2, 0, 2, 2]                  # env 1 starts over
    assert np.isfinite(np.asarray(state.obs)).all() and np.isfinite(np.asarray(state.body.data.qpos)).all()


def test_margin_reward_adds_each_strings_press_margin(left):
    env, reset, _ = left
    paid = envs.make("left", [scale_song(), chord_song()], episode_frames=12, margin_reward=0.5)
    state = jax.tree.map(lambda x: x[1], reset(jax.random.split(jax.random.PRNGKey(0), N_ENVS)))
    goal = jnp.asarray([-1, 3, 2, 0, 5, -1], jnp.int32)
    plain, more = (jax.jit(lambda s, e=e: e.left_part(s, s.body, goal)[0])(state) for e in (env, paid))
    extra = 0.5 * R.margin_reward(env.segments(state.body.data, env.hands[0]), goal)
    assert np.abs(np.asarray(extra)).max() > 0.1
    np.testing.assert_allclose(np.asarray(more), np.asarray(plain + extra), atol=1e-6)


def test_training_window_is_a_rest_then_song_notes(left):
    env, _, _ = left
    sample = jax.jit(env.sample_window)             # one program for the 20 keys
    for seed in range(20):
        w = sample(jax.random.PRNGKey(seed))
        n, dur, lft = int(w.n), np.asarray(w.dur), np.asarray(w.left)
        assert int(dur[0]) == 5 and np.all(lft[0] == 0)                    # the grace rest
        assert 2 <= n <= 20 and np.all(dur[1:n] >= 5) and np.all(dur[1:n] <= 50) and np.all(dur[n:] == 0)
        song = [scale_song(), chord_song()][int(w.song)]
        code = TL.left_code([song.notes[int(w.first) + i].frets for i in range(n - 1)])
        pressed = code > 0
        offset = lft[1:n][pressed] - code[pressed]
        assert len(set(offset.tolist())) <= 1                             # one fret shift for the whole window
        np.testing.assert_array_equal(lft[1:n][~pressed], code[~pressed])  # open and mute strings stay


def test_even_notes_reaches_the_training_windows():
    keys = jax.random.split(jax.random.PRNGKey(5), 200)
    first, notes = {}, {}
    for even in (False, True):
        env = envs.make("left", [scale_song()], episode_frames=12, window_notes=(3, 5), even_notes=even)
        w = jax.jit(jax.vmap(env.sample_window))(keys)
        first[even], notes[even] = np.asarray(w.first), np.asarray(w.n) - 1
        assert (first[even] + notes[even] <= 8).all()
    # 2 or 3 of the song's 8 notes a window: the paper's windows are whole, so none starts at the last note; even
    # starts run to the last note (1/9 or 1/10 of the windows) and cut those windows to one note
    assert set(notes[False].tolist()) == {2, 3} and first[False].max() == 6
    assert first[True].max() == 7 and (notes[True][first[True] == 7] == 1).all()


def test_evaluation_plays_the_song_from_its_start_and_stops():
    from dexguitar.perform.scripted import ScriptedPlayer
    song = scale_song()
    env = envs.make("left", [song], envs.EnvConfig().evaluation())
    state = jax.jit(env.reset)(jax.random.PRNGKey(0), 0)
    w = state.cursor.window
    # the 15-frame count-in, then the song: 1/8 at 100 BPM = 18 frames
    assert int(w.n) == 9 and np.asarray(w.dur)[:9].tolist() == [15] + [18] * 8
    np.testing.assert_array_equal(np.asarray(w.left)[:9, 1], [0, 1, 3, 5, 6, 8, 6, 5, 3])
    goal = np.asarray(state.obs)[-35:].reshape(5, 7)
    # slot 0: the rest, timer 15 frames -> 15/20 - 1 = -0.25; slot 1: string 2 at fret 1 -> 1/22, 18 frames -> -0.1
    assert goal[0, 1] == 0.0 and goal[0, 6] == pytest.approx(-0.25)
    assert goal[1, 1] == pytest.approx(1 / 22) and goal[1, 6] == pytest.approx(-0.1)
    assert goal[2, 1] == pytest.approx(3 / 22) and goal[1, 0] == 0.0
    # the song played through with zero actions, step by step in the scripted player's program (the same reset)
    steps = 15 + 8 * 18
    info = ScriptedPlayer(env).rollout([0], np.zeros((1, steps, env.action_size), np.float32))
    note_end, song_note, done = (np.asarray(info[k])[0] for k in ("note_end", "song_note", "done"))
    assert song_note[note_end].tolist() == list(range(-1, 8))         # the count-in, then the 8 notes, once each
    assert note_end[15 + 17] and song_note[15 + 17] == 0                # the first song note is over at its end
    assert done[-1] and not done[:-1].any()                             # the song's end ends the episode


def test_right_step_under_jit_and_vmap():
    """The right hand's pure step, without the episode wrappers (auto-reset: the left hand's tests above; the duet's
    training step: tests/test_sync.py, inside the synchronizer's training iteration)."""
    hand, obs, columns, hands = "right", 2 * 16 * 13 + 35, 1, 1
    env = envs.make(hand, [chord_song()]).base
    state = jax.jit(jax.vmap(env.reset))(jax.random.split(jax.random.PRNGKey(0), N_ENVS))
    step = jax.jit(jax.vmap(env.step))
    for _ in range(3):
        state = step(state, jnp.zeros((N_ENVS, env.action_size)))
    chex.assert_shape(state.obs, (N_ENVS, obs))
    chex.assert_shape(state.reward, (N_ENVS, columns))
    chex.assert_shape(state.privileged, (N_ENVS, 6))
    chex.assert_tree_all_finite((state.obs, state.reward))
    assert env.layout.obs_size == obs and env.layout.hands == hands and env.layout.frame == 16 * 13
    # strum targets are contiguous: the C chord (strings 1-5) asks for strings 1-5, the F barre for all six
    w = state.cursor.window
    assert np.asarray(w.pick)[0, 1:3].tolist() in ([[True] * 6, [True] * 5 + [False]],
                                                  [[True] * 5 + [False], [False] * 6])


def _dots(jaxpr):
    """Every dot_general of a jaxpr, nested ones (jit, scan, while, cond) included."""
    for eqn in jaxpr.eqns:
        if eqn.primitive.name == "dot_general":
            yield eqn
        for sub in jax.extend.core.jaxprs_in_params(eqn.params):
            yield from _dots(sub)


@pytest.mark.parametrize("hand", ["left", "duet"])
def test_env_matmuls_are_full_float32(hand):
    """A GPU's default float32 matmul is TF32, which on an H100 cost the planned left hand 0.07 F1 on snow: every
    matmul of the world (physics, kinematics, detection, in reset and in step) asks for HIGHEST precision."""
    env = envs.make(hand, [chord_song()])
    state = jax.eval_shape(env.reset, jax.random.PRNGKey(0))
    for fn, args in ((env.reset, (jax.random.PRNGKey(0),)), (env.step, (state, jnp.zeros(env.action_size)))):
        dots = list(_dots(jax.make_jaxpr(fn)(*args).jaxpr))
        assert len(dots) > 10
        assert {eqn.params["precision"] for eqn in dots} == {(jax.lax.Precision.HIGHEST,) * 2}
    # what is outside an env keeps JAX's default
    plain = jax.make_jaxpr(jnp.dot)(jnp.ones((3, 3)), jnp.ones(3)).jaxpr
    assert [eqn.params["precision"] for eqn in _dots(plain)] == [None]
