"""The planner as a teacher (`EnvConfig.teacher`, `TrainConfig.teacher_weight`): its label of a state, and what the
label does to the actor."""
from types import SimpleNamespace

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from dexguitar import envs
from dexguitar.learn import networks as N
from dexguitar.learn.policy import distribution
from dexguitar.learn.trainer import Trainer, TrainConfig, TrainState
from dexguitar.music import cursor as CU
from dexguitar.music import timeline as TL
from test_envs import chord_song

TEACHER = envs.EnvConfig(shift_prob=0.0, tempo_prob=0.0, teacher=True, physics="jax")


@pytest.fixture(scope="module")
def env():
    return envs.make("left", [chord_song()], TEACHER).base


def _at(env, frame_offset: int, qpos, qvel=None):
    """A state of the env's first window, `frame_offset` frames into it, with the left hand's joints at `qpos` and
    `qvel` (zeros unless given): what `teacher` reads of a state (the cursor and the joints), without stepping MJX."""
    cursor = CU.start(env.sample_window(jax.random.PRNGKey(0)))
    for _ in range(frame_offset):
        cursor, _ = CU.advance(cursor)
    qvel = np.zeros_like(qpos) if qvel is None else qvel
    return SimpleNamespace(cursor=cursor, body=SimpleNamespace(data=SimpleNamespace(qpos=jnp.asarray(qpos),
                                                                                    qvel=jnp.asarray(qvel))))


def test_the_label_is_the_planned_action_on_the_plan_and_pulls_back_off_it(env):
    plan = env.songs.plan
    lo, hi = env.model.actuator_ctrlrange.T
    half = (hi - lo) / 2
    for offset in (0, 7):
        state = _at(env, offset, np.zeros(env.model.nq))
        f = int(CU.song_frame(state.cursor))
        planned_q, planned_a = np.asarray(plan.qpos[0, f]), np.asarray(plan.action[0, f])
        on_plan = np.asarray(env.teacher(_at(env, offset, planned_q)))
        np.testing.assert_allclose(on_plan, np.clip(planned_a, -1, 1), atol=1e-7)
        # 1 cm of the wrist's first slide and 0.1 rad of a finger joint off the plan, at gain 1
        off = planned_q.copy()
        off[0] += 0.01
        off[12] -= 0.1
        label = np.asarray(env.teacher(_at(env, offset, off)))
        expected = planned_a.copy()
        expected[0] -= 0.01 / half[0]
        expected[12] += 0.1 / half[12]
        np.testing.assert_allclose(label, np.clip(expected, -1, 1), atol=1e-6)
    # the plan only labels: nothing is added to the action
    assert np.all(np.asarray(env.feedforward(state.cursor)) == 0.0)


def test_the_gain_scales_the_pull_and_a_teacher_labels_one_hand(env):
    lo, hi = env.model.actuator_ctrlrange.T
    plan = env.songs.plan
    half_gain = envs.make("left", [chord_song()], TEACHER, teacher_gain=0.5).base
    state = _at(env, 3, np.zeros(env.model.nq))
    f = int(CU.song_frame(state.cursor))
    off = np.asarray(plan.qpos[0, f]).copy()
    off[20] += 0.05
    d = np.asarray(half_gain.teacher(_at(env, 3, off))) - np.asarray(env.teacher(_at(env, 3, off)))
    assert d[20] == pytest.approx(0.5 * 0.05 / ((hi[20] - lo[20]) / 2), rel=1e-5)
    assert np.count_nonzero(d) == 1
    # damping through the target: + c x (planned velocity - velocity) / half range, c 0.1 s on the wrist's joints
    # and 0.03 s on the fingers'; on the planned pose at the planned velocity, nothing
    damped = envs.make("left", [chord_song()], TEACHER, teacher_damping=0.1, teacher_finger_damping=0.03).base
    on = np.asarray(plan.qpos[0, f]), np.asarray(plan.qvel[0, f])
    np.testing.assert_allclose(np.asarray(damped.teacher(_at(env, 3, *on))), np.asarray(env.teacher(_at(env, 3, *on))),
                               atol=1e-7)
    slow = on[1].copy()
    slow[0] -= 0.1          # the wrist's first slide 0.1 m/s behind the plan, the fingers' joint 15 0.5 rad/s ahead
    slow[15] += 0.5
    d = np.asarray(damped.teacher(_at(env, 3, on[0], slow))) - np.asarray(env.teacher(_at(env, 3, on[0], slow)))
    half = (hi - lo) / 2
    np.testing.assert_allclose(d[[0, 15]], [0.1 * 0.1 / half[0], -0.03 * 0.5 / half[15]], rtol=1e-5)
    assert np.count_nonzero(d) == 2
    with pytest.raises(ValueError, match="not duet"):
        envs.make("duet", [chord_song()], TEACHER)
    with pytest.raises(ValueError, match="teacher=True"):
        Trainer(TrainConfig(num_envs=4, horizon=4, minibatch=8, teacher_weight=1.0), [TL.from_song(chord_song())], None,
                envs.EnvConfig(physics="jax"))


def test_the_right_env_is_labelled_by_the_right_planner():
    right = envs.make("right", [chord_song()], TEACHER).base
    lo, hi = right.model.actuator_ctrlrange.T
    plan, half = right.songs.plan_right, (hi - lo) / 2
    assert right.songs.plan is None                     # no left plan is made for a right-hand student
    j = np.asarray(right.hands[0].qpos)
    state = _at(right, 5, np.zeros(right.model.nq))
    f = int(CU.song_frame(state.cursor))
    q = np.zeros(right.model.nq, np.float32)
    q[j] = np.asarray(plan.qpos[0, f])
    planned = np.clip(np.asarray(plan.action[0, f]), -1, 1)
    np.testing.assert_allclose(np.asarray(right.teacher(_at(right, 5, q))), planned, atol=1e-7)
    q[j[1]] += 0.02                                     # 2 cm off the plan on the wrist's second slide
    expected = planned.copy()
    expected[1] = np.clip(plan.action[0, f][1] - 0.02 / half[1], -1, 1)
    np.testing.assert_allclose(np.asarray(right.teacher(_at(right, 5, q))), expected, atol=1e-6)
    assert np.all(np.asarray(right.feedforward(state.cursor)) == 0.0)


def test_the_planned_wrist_reward_is_one_on_the_planned_hand_position_and_needs_the_plans(env):
    plan = env.songs.plan
    state = _at(env, 4, np.zeros(env.model.nq))
    f = int(CU.song_frame(state.cursor)) + 1                   # the pose after this step: the next frame's
    q = np.asarray(plan.qpos[0, f]).copy()
    q[3:] += 0.3                                               # the wrist's hinges and the fingers do not count
    assert float(env.plan_wrist(state, SimpleNamespace(qpos=jnp.asarray(q)))) == pytest.approx(1.0, abs=1e-6)
    q[0] += 0.012                                              # 1.2 cm and 1.6 cm off on two slides: 2 cm
    q[2] -= 0.016
    assert float(env.plan_wrist(state, SimpleNamespace(qpos=jnp.asarray(q)))) == pytest.approx(np.exp(-1.0), rel=1e-4)
    with pytest.raises(ValueError, match="needs the left plans"):
        envs.make("left", [chord_song()], envs.EnvConfig(physics="jax", plan_wrist_reward=0.1))
    with pytest.raises(ValueError, match="needs the left plans"):
        envs.make("right", [chord_song()], TEACHER, plan_wrist_reward=0.1)


def _update(trainer, labels, batch_size=64):
    """update(iteration) -> (mean action before, after, log): one `ppo_update` (one compiled program) of a fresh actor
    on a batch whose advantages are all zero (PPO's own loss has no gradient), every sample labelled `labels`; the
    log's "moved" is the largest change of an actor weight."""
    key = jax.random.PRNGKey(0)
    layout = trainer.layout
    policy, obs_norm, _ = trainer.init_policy(key)
    critic = N.init_params(trainer.critic, key, (layout.history, layout.frame_size),
                           (layout.goal_size + layout.privileged,))
    params = {"policy": policy, "critic": critic}
    opt = trainer.optimizer_states(params)
    obs = jax.random.normal(key, (batch_size, layout.obs_size))
    mu0, log_std0 = distribution(trainer.spec, trainer.actor_params(params, obs_norm), obs)
    batch = {"obs": obs, "privileged": jnp.ones((batch_size, layout.privileged)), "action": mu0,
             "logp": N.gaussian_log_prob(mu0, log_std0, mu0), "adv": jnp.zeros(batch_size),
             "target": jnp.zeros((batch_size, len(trainer.columns))),
             "teacher": jnp.broadcast_to(labels, mu0.shape)}

    def update(iteration):
        ts = TrainState(params=params, opt=opt, obs_norm=obs_norm, disc_norm={}, popart={}, buffers={}, env=None,
                        key=key, iteration=iteration)
        new, _, log = trainer.ppo_update(ts, batch, key)
        moved = jnp.max(jnp.stack([jnp.max(jnp.abs(a - b)) for a, b in zip(jax.tree.leaves(new["policy"]),
                                                                            jax.tree.leaves(params["policy"]))]))
        return distribution(trainer.spec, trainer.actor_params(new, obs_norm), obs)[0], dict(log, moved=moved)
    # LLVM at -O2 rather than the suite's -O0 (tests/conftest.py): the 40 minibatch steps of the paper-sized networks
    # run in 0.8 s instead of 5.7 s, for 3-4 s more of compiling (AMD VM)
    update = jax.jit(update).lower(jnp.int32(0)).compile(compiler_options={"xla_backend_optimization_level": 2})
    return lambda iteration: (np.asarray(mu0),) + jax.tree.map(np.asarray, update(jnp.int32(iteration)))


def test_the_labels_pull_the_actor_and_nothing_once_faded():
    cfg = TrainConfig(num_envs=4, horizon=16, minibatch=16, epochs=10, actor_lr=1e-3, teacher_weight=1.0,
                      teacher_fade=10)
    trainer = Trainer(cfg, [TL.from_song(chord_song())], None, TEACHER)
    labels = jnp.zeros(27).at[0].set(0.3).at[12].set(-0.2)
    update = _update(trainer, labels)
    mu0, mu1, log = update(0)
    before, after = np.abs(mu0 - np.asarray(labels)).mean(), np.abs(mu1 - np.asarray(labels)).mean()
    assert after < 0.5 * before, (before, after)
    assert np.isfinite(float(log["teacher_nll"])) and float(log["teacher_rms"]) > 0
    # at the fade's end the teacher weighs nothing and zero advantages move nothing
    _, _, log = update(10)
    assert float(log["moved"]) == 0.0
