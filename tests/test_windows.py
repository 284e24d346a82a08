"""Training windows played by the IK planner's actions (`learn.windows`, behind experiments/planner_noise.py and
residual_noise.py): its rollout of the plans plays as the scripted player does, and the padding is what numpy says."""
import jax
import jax.numpy as jnp
import numpy as np

from dexguitar import envs
from dexguitar.learn import windows as D
from dexguitar.learn import policy as PO
from dexguitar.perform.scripted import ScriptedPlayer
from dexguitar.music import timeline as TL
from test_scripted import MELODY, melody


def test_plans_rolled_out_score_as_the_scripted_player():
    """The windows' planner rollout (its own window sampling, plan and scan) and `ScriptedPlayer` must agree on
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
