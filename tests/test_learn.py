"""The learner: GAE, the PPO loss and PopArt against hand-computed values; a discriminator that separates reference
from random motion; and the whole scanned training iteration on CPU (4 envs): finite losses, parameters that change,
and save -> restore -> continue equal to an uninterrupted run."""
import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

from dexguitar.learn import checkpoint as C
from dexguitar.learn import imitation as IM
from dexguitar.learn import networks as N
from dexguitar.learn import ppo as P


def test_gae_by_hand():
    r = jnp.ones((3, 1, 1))
    v = jnp.full((3, 1, 1), 0.5)
    no = jnp.zeros((3, 1), bool)
    adv, ret = P.gae(r, v, v, no, no, gamma=0.9, lam=0.8)
    # delta = 1 + 0.9 * 0.5 - 0.5 = 0.95; A2 = 0.95, A1 = 0.95 + 0.72 * 0.95 = 1.634, A0 = 0.95 + 0.72 * 1.634
    np.testing.assert_allclose(adv[:, 0, 0], [2.12648, 1.634, 0.95], rtol=1e-5)
    np.testing.assert_allclose(ret, adv + v)
    # transition 1 terminates: delta1 = 1 - 0.5 = 0.5 with no future, A0 = 0.95 + 0.72 * 0.5 = 1.31
    term = jnp.array([[False], [True], [False]])
    adv, _ = P.gae(r, v, v, term, term, gamma=0.9, lam=0.8)
    np.testing.assert_allclose(adv[:, 0, 0], [1.31, 0.5, 0.95], rtol=1e-5)
    # a time-out (done, not terminated) keeps the bootstrap V(s') but stops the recursion: A1 = 0.95
    adv, _ = P.gae(r, v, v, no, term, gamma=0.9, lam=0.8)
    np.testing.assert_allclose(adv[:, 0, 0], [0.95 + 0.72 * 0.95, 0.95, 0.95], rtol=1e-5)


def test_standardized_weighted_advantages():
    adv = jnp.array([[[1.0, 10.0]], [[3.0, 30.0]]])              # 2 samples, 2 columns
    out = P.standardize_advantages(adv, jnp.array([0.5, 2.0]))
    # each column: mean 2 / 20, unbiased std sqrt(2) / sqrt(200) -> (-1/sqrt2, +1/sqrt2) times the weight
    s = 1 / np.sqrt(2)
    np.testing.assert_allclose(out[:, 0], [[-0.5 * s, -2 * s], [0.5 * s, 2 * s]], rtol=1e-5)


def test_clipped_surrogate_by_hand():
    old = jnp.zeros(2)
    new = jnp.log(jnp.array([1.5, 1.5]))                       # ratio 1.5, clip 0.2
    adv = jnp.array([[1.0], [-1.0]])
    loss, frac = P.policy_loss(new, old, adv, 0.2)
    # A = +1: min(1.5, 1.2) = 1.2; A = -1: min(-1.5, -1.2) = -1.5; loss = -mean(1.2, -1.5) = 0.15
    assert float(loss) == pytest.approx(0.15, abs=1e-6) and float(frac) == 1.0


def test_approx_kl_estimates_the_kl_of_two_gaussians():
    # samples of the old policy N(0, 1); the new one N(0.1, 1): KL(old || new) = 0.1^2 / 2 = 0.005
    x = np.random.default_rng(0).normal(size=400_000)
    old = -0.5 * x ** 2
    new = -0.5 * (x - 0.1) ** 2
    assert abs(float(P.approx_kl(jnp.asarray(new), jnp.asarray(old))) - 0.005) < 2.5e-4
    assert float(P.approx_kl(jnp.asarray(old), jnp.asarray(old))) == 0.0


def test_adaptive_learning_rate_steps_and_bounds():
    from dexguitar.learn.trainer import KL_LR_BOUNDS, TrainConfig, adapt_lr
    steps = [float(adapt_lr(jnp.float32(1e-3), kl, 0.01)) for kl in (0.05, 0.02, 0.01, 0.005, 0.001)]
    np.testing.assert_allclose(steps, [1e-3 / 1.5, 1e-3, 1e-3, 1e-3, 1.5e-3], rtol=1e-6)
    assert float(adapt_lr(jnp.float32(KL_LR_BOUNDS[1]), 0.0, 0.01)) == pytest.approx(KL_LR_BOUNDS[1])
    assert float(adapt_lr(jnp.float32(KL_LR_BOUNDS[0]), 1.0, 0.01)) == pytest.approx(KL_LR_BOUNDS[0])
    with pytest.raises(ValueError, match="kl_target"):
        TrainConfig(kl_target=-0.01).check()


def test_popart_statistics_and_preserved_outputs():
    stats = P.popart_init(1)
    # identity before any update
    assert float(P.popart_denormalize(stats, jnp.array([2.0]))[0]) == 2.0
    kernel = jnp.array([[0.5], [-1.0]])
    bias = jnp.array([0.25])
    x = jnp.array([[1.0, 2.0], [0.0, -3.0]])
    before = P.popart_denormalize(stats, x @ kernel + bias)
    stats, kernel, bias = P.popart_update(stats, jnp.array([[2.0], [4.0]]), kernel, bias)
    # beta 0.1: m = 0.3, v = 0.1 * (4 + 16) / 2 = 1.0, debias 0.1 -> mean 3, E[r^2] 10, var 1, std 1
    mean, std = P.popart_moments(stats)
    assert float(mean[0]) == pytest.approx(3.0) and float(std[0]) == pytest.approx(1.0)
    after = P.popart_denormalize(stats, x @ kernel + bias)
    np.testing.assert_allclose(after, before, rtol=1e-5)


def test_gaussian_log_prob():
    # N(0.5; 0, 1) in 1-D: -0.125 - 0.9189385
    assert float(N.gaussian_log_prob(jnp.zeros(1), jnp.zeros(1), jnp.array([0.5]))) == pytest.approx(-1.0439385)


def test_normalizer_merges_batches_exactly():
    x = np.random.default_rng(0).normal(3.0, 2.0, (1000, 4))
    stats = N.normalizer_init(4)
    stats = N.normalizer_update(N.normalizer_update(stats, jnp.asarray(x[:300])), jnp.asarray(x[300:]))
    # the prior (mean 0, var 1, count 1) weighs 1 / 1001
    all_ = np.concatenate([np.zeros((1, 4)), x])
    np.testing.assert_allclose(stats["mean"], x.sum(0) / 1001, rtol=1e-4)
    assert float(stats["count"]) == 1001.0
    assert np.all(np.abs(np.asarray(stats["var"]) - 4.0) < 0.5) and all_.shape == (1001, 4)


def test_gru_is_flax_gru_cell_over_the_frames():
    """networks.GRU joins the cell's six gate kernels into two products: the same parameters (names, shapes and initial
    values) as `nn.GRUCell` and the same output as the cell stepped over the frames from a zero state."""
    import flax.linen as nn

    class Cell(nn.Module):
        @nn.compact
        def __call__(self, frames):
            cell = nn.GRUCell(N.LATENT, name="gru")
            h = jnp.zeros(frames.shape[:-2] + (N.LATENT,))
            for t in range(frames.shape[-2]):
                h, _ = cell(h, frames[..., t, :])
            return h

    class Joined(nn.Module):
        @nn.compact
        def __call__(self, frames):
            return N.GRU(name="gru")(frames)

    x = jax.random.normal(jax.random.PRNGKey(1), (6, IM.FRAMES, 28))
    p_cell, p_joined = Cell().init(jax.random.PRNGKey(0), x), Joined().init(jax.random.PRNGKey(0), x)
    assert jax.tree.structure(p_cell) == jax.tree.structure(p_joined)
    jax.tree.map(np.testing.assert_array_equal, p_cell, p_joined)
    leaves, tree = jax.tree.flatten(p_cell)      # biases are zero at init: perturb every leaf to check them too
    keys = jax.random.split(jax.random.PRNGKey(2), len(leaves))
    params = jax.tree.unflatten(tree, [w + 0.3 * jax.random.normal(k, w.shape) for w, k in zip(leaves, keys)])
    np.testing.assert_allclose(Joined().apply(params, x), Cell().apply(params, x), rtol=1e-5, atol=1e-6)


def test_hinge_loss_and_its_gradient_by_separate_passes():
    """The loss as its formula reads, with the penalty's gradient taken on the mixtures alone, against hinge_loss's one
    batch of real, fake and mixed samples: the same value and the same parameter gradient."""
    disc = N.Discriminator()
    real = jax.random.normal(jax.random.PRNGKey(3), (16, IM.FRAMES, 5))
    fake = 2.0 * jax.random.normal(jax.random.PRNGKey(4), (16, IM.FRAMES, 5))
    params = disc.init(jax.random.PRNGKey(0), real)
    key = jax.random.PRNGKey(5)

    def by_formula(p):
        alpha = jax.random.uniform(key, (16, 1, 1))
        mixed = alpha * real + (1 - alpha) * fake
        grad = jax.grad(lambda x: jnp.sum(disc.apply(p, x)))(mixed)
        norm = jnp.sqrt(jnp.sum(grad.reshape(16, -1) ** 2, -1) + 1e-12)
        return (jnp.mean(jax.nn.relu(1 - disc.apply(p, real))) + jnp.mean(jax.nn.relu(1 + disc.apply(p, fake)))
                + 10.0 * jnp.mean((norm - 1) ** 2))

    want, g_want = jax.value_and_grad(by_formula)(params)
    (got, log), g_got = jax.value_and_grad(IM.hinge_loss, argnums=1, has_aux=True)(disc.apply, params, real, fake,
                                                                                    key, 10.0)
    np.testing.assert_allclose(got, want, rtol=1e-5)
    assert float(log["grad_penalty"]) > 0.01            # the penalty is part of what is compared
    jax.tree.map(lambda a, b: np.testing.assert_allclose(a, b, rtol=1e-4, atol=1e-6), g_got, g_want)


def test_discriminator_separates_reference_from_random_motion():
    rng = np.random.default_rng(0)
    t = np.linspace(0, 1, IM.FRAMES)
    # reference: smooth motions (a point moving on a circle of radius 10); fake: random jitter of the same size.
    # The gradient penalty on the sum of the 32 outputs bounds each output's slope near 1/32, so the toy data are
    # spread out enough for the mean output to separate by a visible margin.
    real = 10 * np.stack([np.stack([np.sin(a + t), np.cos(a + t)], -1) for a in rng.uniform(0, 6, 128)])
    fake = rng.uniform(-10, 10, (128, IM.FRAMES, 2))
    disc = N.Discriminator()
    params = disc.init(jax.random.PRNGKey(0), jnp.zeros((IM.FRAMES, 2)))
    opt = optax.adam(1e-3)
    state = opt.init(params)

    @jax.jit
    def step(params, state, key):
        (loss, _), g = jax.value_and_grad(IM.hinge_loss, argnums=1, has_aux=True)(
            disc.apply, params, jnp.asarray(real, jnp.float32), jnp.asarray(fake, jnp.float32), key)
        updates, state = opt.update(g, state)
        return optax.apply_updates(params, updates), state, loss
    for i in range(100):
        params, state, loss = step(params, state, jax.random.PRNGKey(i))
    r_real = N.disc_reward(disc.apply(params, jnp.asarray(real, jnp.float32)))
    r_fake = N.disc_reward(disc.apply(params, jnp.asarray(fake, jnp.float32)))
    assert float(jnp.mean(r_real)) - float(jnp.mean(r_fake)) > 0.1
    assert float(jnp.mean(r_real[:, None] > r_fake[None, :])) > 0.85      # ranks reference above random


def test_reference_features_are_computed_per_frame():
    """The training data hold each discriminator's features of every reference frame; a window of them is the
    features of the window of link poses, for the guitar-relative and the wrist-relative discriminator."""
    from dexguitar.learn.trainer import reference_data
    rng = np.random.default_rng(2)
    frames = np.zeros((20, 16, 7), np.float32)
    frames[..., :3] = rng.normal(0, 0.05, (20, 16, 3))
    q = rng.normal(size=(20, 16, 4))
    frames[..., 3:] = q / np.linalg.norm(q, axis=-1, keepdims=True)
    feats, n = reference_data(frames, IM.DISCRIMINATORS["left"])
    assert int(n) == 20 and set(feats) == {"wrist", "fingers"}
    key = jax.random.PRNGKey(7)
    windows = IM.sample_reference(key, jnp.asarray(frames), 20, 8)              # (8, 3, 16, 7)
    for name, d in IM.DISCRIMINATORS["left"].items():
        assert feats[name].shape == (1024, d.features)                          # padded to the capacity
        assert not np.any(np.asarray(feats[name][20:]))
        np.testing.assert_allclose(IM.sample_reference(key, feats[name], n, 8), IM.features(windows, d.links, d.parent),
                                   atol=1e-6)


def test_wrist_relative_features_ignore_the_wrist_pose():
    """The left fingers' discriminator sees the fingers relative to the wrist: moving and turning the whole hand
    leaves its input unchanged."""
    from dexguitar.world.geometry import quat_mul, quat_to_mat
    rng = np.random.default_rng(1)
    links = np.zeros((IM.FRAMES, 16, 7), np.float32)
    links[..., :3] = rng.normal(0, 0.05, (IM.FRAMES, 16, 3))
    q = rng.normal(size=(IM.FRAMES, 16, 4))
    links[..., 3:] = q / np.linalg.norm(q, axis=-1, keepdims=True)
    turn = np.array([np.cos(0.3), 0.0, np.sin(0.3), 0.0], np.float32)   # 0.6 rad about y
    rot = np.asarray(quat_to_mat(jnp.asarray(turn)))
    moved = links.copy()
    moved[..., :3] = links[..., :3] @ rot.T + np.array([0.1, -0.2, 0.05])
    moved[..., 3:] = np.asarray(quat_mul(jnp.asarray(turn), jnp.asarray(links[..., 3:])))
    a = IM.features(jnp.asarray(links), tuple(range(4, 16)), "wrist")
    b = IM.features(jnp.asarray(moved), tuple(range(4, 16)), "wrist")
    np.testing.assert_allclose(a, b, atol=1e-5)


@pytest.fixture
def trainer(left_trainer):
    return left_trainer


def test_first_state_is_one_program_s_wherever_the_networks_are_drawn(trainer):
    """`init` draws the networks in a program of their own on the CPU and the rest of the first state on the
    default device; from one key that is the state `initial_state` makes in one program, leaf for leaf."""
    key = jax.random.PRNGKey(5)
    split = trainer.init(key)
    whole = jax.jit(trainer.initial_state)(key, trainer.init_inputs())
    assert jax.tree.structure(split) == jax.tree.structure(whole)
    jax.tree.map(lambda a, b: np.testing.assert_array_equal(np.asarray(a), np.asarray(b)), split, whole)
    assert not np.array_equal(split.params["critic"]["params"]["trunk"]["fc1"]["kernel"],
                              trainer.init(jax.random.PRNGKey(6)).params["critic"]["params"]["trunk"]["fc1"]["kernel"])


def test_training_iterations_and_exact_resume(trainer, tmp_path, compiled_chunk):
    chunk, start, data, put = compiled_chunk(trainer, trainer.init())
    p0 = jax.device_get(start.params)
    first, metrics = chunk(start, data)
    assert all(np.isfinite(float(v)) for k, v in metrics.items() if not k.startswith("f1/"))
    assert all(float(v) == 0.0 for k, v in metrics.items() if k.startswith("nonfinite/"))
    changed = jax.tree.map(lambda a, b: float(np.abs(np.asarray(a) - b).max()), jax.device_get(first.params), p0)
    for net in ("policy", "critic", "disc"):
        assert max(jax.tree.leaves(changed[net])) > 0, net
    C.save(tmp_path / "ckpt", int(first.iteration), first)
    template = jax.tree.map(jnp.zeros_like, first)          # a fresh process's structure, without building it
    uninterrupted, _ = chunk(first, data)
    restored, step = C.restore(tmp_path / "ckpt", template)
    assert int(restored.iteration) == 1 == step
    resumed, _ = chunk(put(restored), data)
    same = jax.tree.map(lambda a, b: np.array_equal(np.asarray(a), np.asarray(b)), resumed, uninterrupted)
    assert all(jax.tree.leaves(same)) and int(resumed.iteration) == 2


def test_the_stages_as_programs_train_as_one_scanned_program(trainer, compiled_chunk):
    """By default an iteration's three stages are programs of their own (`learn.stages`); `one_program` scans whole
    iterations in one program. From one state both make the same next state and metrics, up to the order of float
    sums."""
    from dexguitar.learn.trainer import Trainer
    from dexguitar.motion import load_motion
    from dexguitar.motion.kinematics import reference_frames
    one = Trainer(dataclasses.replace(trainer.config, one_program=True), trainer.env.songs,
                  reference_frames(load_motion("left")))
    start = jax.device_get(trainer.init())
    staged, state, data, _ = compiled_chunk(trainer, start)
    scanned, state_one, data_one, _ = compiled_chunk(one, start)
    assert len(staged.programs) == 3 and len(scanned.programs) == 1
    (a, metrics), (b, metrics_one) = staged(state, data), scanned(state_one, data_one)
    assert int(a.iteration) == int(b.iteration) == 1 and metrics.keys() == metrics_one.keys()

    def same(x, y):
        x, y = np.asarray(x), np.asarray(y)
        if np.issubdtype(x.dtype, np.inexact):
            np.testing.assert_allclose(x, y, rtol=1e-5, atol=1e-6)
        else:
            np.testing.assert_array_equal(x, y)
    jax.tree.map(same, jax.device_get(a), jax.device_get(b))
    jax.tree.map(same, metrics, metrics_one)
    moved = jax.tree.map(lambda x, y: float(np.abs(np.asarray(x) - y).max()), jax.device_get(a.params["policy"]),
                         start.params["policy"])
    assert max(jax.tree.leaves(moved)) > 0                     # an iteration that learned, not two that did nothing


def kl_update(trainer, iteration=0, adv=1.0, **config):
    """(config, parameters before, after, optimizer state after, log) of one jitted PPO update of a KL-target
    trainer (rate 1e-3) on a random batch whose log-probabilities are the acting policy's (so its first KL is 0),
    every advantage `adv`, the mean action's bias raised by `mu_bias`."""
    from types import SimpleNamespace
    from dexguitar.learn.policy import distribution
    from dexguitar.learn.trainer import Trainer
    mu_bias = config.pop("mu_bias", 0.0)
    cfg = dataclasses.replace(trainer.config, **{"kl_target": 1e-9, "actor_lr": 1e-3, **config})
    tr = Trainer(cfg, trainer.env.songs, None)
    k = jax.random.split(jax.random.PRNGKey(3), 4)
    policy, obs_norm, _ = tr.init_policy(k[0])
    mu = policy["params"]["mu"]
    policy = {**policy, "params": {**policy["params"], "mu": dict(mu, bias=mu["bias"] + mu_bias)}}
    lay = tr.layout
    critic = N.init_params(tr.critic, k[1], (lay.history, lay.frame_size), (lay.goal_size + lay.privileged,))
    params = {"policy": policy, "critic": critic}
    opt = tr.optimizer_states(params)                                  # with the rate, 1e-3
    n = cfg.batch
    obs = jax.random.normal(k[2], (n, lay.obs_size))
    action = jax.random.normal(k[3], (n, tr.env.action_size)) * 0.1
    mu, log_std = distribution(tr.spec, tr.actor_params(params, obs_norm), obs)
    batch = {"obs": obs, "privileged": jnp.zeros((n, lay.privileged)), "action": action,
             "logp": N.gaussian_log_prob(mu, log_std, action),          # the acting policy's: the first KL is 0
             "adv": jnp.full((n, len(tr.columns)), adv), "target": jnp.zeros((n, len(tr.columns)))}
    if cfg not in _KL_UPDATES:      # the iteration is an argument: one program per config
        _KL_UPDATES[cfg] = jax.jit(lambda p, o, b, i: tr.ppo_update(
            SimpleNamespace(params=p, opt=o, obs_norm=obs_norm, iteration=i), b, jax.random.PRNGKey(0)))
    return (cfg, params) + tuple(_KL_UPDATES[cfg](params, opt, batch, jnp.int32(iteration)))


_KL_UPDATES = {}


def test_kl_target_adapts_the_actor_rate_inside_the_update(trainer):
    # after a warm-up of one iteration (the warm-up test's program, compiled once)
    cfg, params, new_params, new_opt, log = kl_update(trainer, iteration=1, actor_warmup=1)
    n = cfg.batch
    updates = cfg.epochs * (n // cfg.minibatch)                              # 2 x 2 = 4 minibatch steps
    moved = max(jax.tree.leaves(jax.tree.map(lambda a, b: float(jnp.abs(a - b).max()),
                                             new_params["policy"], params["policy"])))
    # the first step (KL 0) raises the rate by 1.5, every later one (KL > 2e-9 once the actor moved) lowers it
    assert moved > 0.0
    np.testing.assert_allclose(float(new_opt["lr"]), 1e-3 * 1.5 / 1.5 ** (updates - 1), rtol=1e-5)
    assert float(log["kl"]) >= 0.0 and "actor_lr" in log


def test_kl_target_rate_holds_through_the_actor_warm_up(trainer):
    # In a warm-up the actor stands still, so its KL is 0; adapting to that would have multiplied the rate by 1.5
    # at each of the 4 minibatch steps (1e-3 -> 5.06e-3) and thrown the first real step far.
    _, params, new_params, new_opt, _ = kl_update(trainer, iteration=0, actor_warmup=1)
    assert float(new_opt["lr"]) == pytest.approx(1e-3, rel=1e-6)
    assert jax.tree.all(jax.tree.map(np.array_equal, new_params["policy"], params["policy"]))
    # one iteration later the warm-up is over: the same update moves the actor and adapts the rate
    _, params, new_params, new_opt, _ = kl_update(trainer, iteration=1, actor_warmup=1)
    assert float(new_opt["lr"]) != pytest.approx(1e-3, rel=1e-6)
    assert not jax.tree.all(jax.tree.map(np.array_equal, new_params["policy"], params["policy"]))


def test_the_prior_pulls_the_mean_action_back_to_zero_where_the_advantages_say_nothing(trainer):
    from dexguitar.learn import ppo
    from dexguitar.learn.policy import distribution
    # KL(N(mu, s) || N(0, s)) = sum mu^2 / 2 s^2: (0.3^2 + 0.4^2) / (2 x 0.1^2) = 12.5
    assert float(ppo.prior_kl(jnp.array([[0.3, -0.4]]), jnp.log(jnp.full((1, 2), 0.1)))) == pytest.approx(12.5)

    def mean_square(params):
        obs = jax.random.normal(jax.random.PRNGKey(5), (64, trainer.layout.obs_size))
        mu, _ = distribution(trainer.spec, {"policy": params["policy"],
                                            "obs_norm": N.normalizer_init(trainer.layout.frame_size)}, obs)
        return float(jnp.mean(jnp.sum(mu ** 2, -1)))
    # zero advantages: the surrogate's gradient is 0, so without the prior the actor stands still ...
    cfg, params, new_params, _, log = kl_update(trainer, adv=0.0, kl_target=0.0)
    assert jax.tree.all(jax.tree.map(np.array_equal, new_params["policy"], params["policy"]))
    assert "prior_kl" not in log
    # ... and with it the update shrinks the mean action. Adam steps every weight by about its rate whatever the
    # gradient, so the rate is small here: at 1e-3 the mean of 0.05 an action overshoots zero many times over.
    cfg, params, new_params, _, log = kl_update(trainer, adv=0.0, kl_target=0.0, prior_kl=1.0, actor_lr=1e-5,
                                                mu_bias=0.05)
    before, after = mean_square(params), mean_square(new_params)
    assert 0.0 < after < 0.9 * before and float(log["prior_kl"]) > 0.0
    with pytest.raises(ValueError, match="prior_kl"):
        dataclasses.replace(cfg, prior_kl=-1.0).check()


def test_weights_follow_the_paper(trainer):
    np.testing.assert_allclose(trainer.weights, [0.15] * 6 + [0.05] * 2)     # Eq. 9, Sec. 5.1 (reference §8)
    from dexguitar.envs import RightEnv
    from dexguitar.learn.imitation import DISCRIMINATORS
    assert RightEnv.reward_weights == (0.5,) and DISCRIMINATORS["right"]["hand"].weight == 0.5   # Sec. 5.2
    from dexguitar.learn.trainer import TrainConfig
    assert dataclasses.asdict(TrainConfig())["actor_lr"] == 5e-6                            # Table S1


def test_actor_warmup_holds_the_actor_still_for_whole_iterations():
    from dexguitar.learn.trainer import TrainConfig, actor_schedule
    cfg = TrainConfig(num_envs=4, horizon=4, minibatch=8, epochs=2, actor_lr=1e-3, actor_warmup=3)
    lr = actor_schedule(cfg)                          # 4 x 4 / 8 = 2 minibatches x 2 epochs = 4 updates an iteration
    np.testing.assert_allclose([float(lr(c)) for c in (0, 11, 12, 13)], [0.0, 0.0, 1e-3, 1e-3], rtol=1e-6)
    np.testing.assert_allclose(float(actor_schedule(TrainConfig(actor_lr=1e-3))(0)), 1e-3, rtol=1e-6)  # default: none
    with pytest.raises(ValueError, match="actor_warmup"):
        TrainConfig(actor_warmup=-1).check()

