"""Behaviour cloning from the IK planner (`learn.distill`): its rollout of the plans plays as the scripted player does,
the padding and statistics are what numpy says, and `dexguitar distill` writes a policy that loads and acts."""
import jax
import jax.numpy as jnp
import numpy as np

from dexguitar import envs
from dexguitar.cli import main
from dexguitar.learn import distill as D
from dexguitar.learn import policy as PO
from dexguitar.perform.scripted import ScriptedPlayer
from dexguitar.music import timeline as TL
from test_scripted import MELODY, melody


def test_plans_rolled_out_score_as_the_scripted_player():
    """The distiller's planner rollout (its own window sampling, plan and scan) and `ScriptedPlayer` must agree on
    every note of the test melody played whole from the home pose."""
    tl = TL.from_song(melody())
    cfg = envs.EnvConfig().evaluation()
    reference = ScriptedPlayer(envs.make("left", [tl], cfg)).play(0)["left"]
    env = envs.ENVS["left"](TL.stack([tl]), cfg)
    keys = D.window_keys(jax.random.PRNGKey(3), 1)
    plans = D.plan_windows(env, keys, workers=1, log=lambda m: None)
    acts, valid = D.pad_plans(plans, len(plans[0]))
    spec = PO.PolicySpec("policy", "left", env.action_size, env.layout)
    obs, alive, scores, closed = D.chunked(D.rollout_fn(env, spec), PO.template(spec), keys, jnp.asarray(acts), False,
                                       jnp.float32(0.0), jax.random.PRNGKey(0))
    assert alive.all()
    per_note = scores[closed & valid][:, 2]
    assert len(per_note) == len(MELODY)
    np.testing.assert_allclose(per_note, reference["per_note"][:, 2], atol=1e-6)
    assert per_note.mean() >= 0.95
    assert obs.shape == (1, len(plans[0]), env.obs_size)


def test_pad_plans_repeats_the_last_action_and_clips():
    a = np.array([[0.5, -2.0], [0.1, 0.2]], np.float32)
    b = np.array([[3.0, 0.0], [0.0, 0.0], [0.3, -0.4], [0.7, 0.7]], np.float32)
    acts, valid = D.pad_plans([a, b], 3)
    np.testing.assert_allclose(acts[0], [[0.5, -1.0], [0.1, 0.2], [0.1, 0.2]], rtol=1e-6)
    np.testing.assert_allclose(acts[1], [[1.0, 0.0], [0.0, 0.0], [0.3, -0.4]], rtol=1e-6)
    np.testing.assert_array_equal(valid, [[True, True, False], [True, True, True]])


def test_frame_stats_are_the_mean_and_variance_of_every_history_frame():
    layout = envs.ObsLayout(("left",), 2, 3, 2, 6)
    spec = PO.PolicySpec("policy", "left", 27, layout)
    obs = np.array([[1, 2, 3, 5, 6, 7, 0, 0], [3, 2, 1, 7, 6, 5, 9, 9]], np.float32)   # 2 frames of 3, goal of 2
    frames = np.array([[1, 2, 3], [5, 6, 7], [3, 2, 1], [7, 6, 5]], np.float64)
    stats = D.frame_stats(spec, obs)
    np.testing.assert_allclose(stats["mean"], [4, 4, 4])
    np.testing.assert_allclose(stats["var"], frames.var(0), rtol=1e-6)
    assert float(stats["count"]) == 4


def test_distill_command_exports_a_policy_that_acts(tmp_path):
    out = tmp_path / "bc"
    assert main(["distill", "--hand", "left", "--song", "c_major_scale", "--windows", "2", "--rounds", "2",
                 "--steps", "3", "--batch", "16", "--workers", "1", "--out", str(out)]) == 0
    params, meta = PO.load(out / "policy")
    spec = PO.PolicySpec.from_meta(meta)
    history = meta["distilled"]["history"]
    assert [h["rolled_out"] for h in history] == ["planner", "student", "student"]    # 2 rounds + the final check
    assert history[1]["samples"] > history[0]["samples"]                          # DAgger aggregates the data
    obs = jax.random.normal(jax.random.PRNGKey(0), (5, spec.layout.obs_size))
    mu, log_std = PO.distribution(spec, params, obs)
    assert mu.shape == (5, 27) and np.isfinite(np.asarray(mu)).all()
    np.testing.assert_allclose(log_std, D.DistillConfig.log_std, atol=1e-2)          # float16 on disk
