"""How large is a residual policy's mean action where the planner goes? The zero residual (`left_general`) plays 16
windows of held-out general material (seed 1); the policy's mean action on those states, in half ranges.

    JAX_PLATFORMS=cpu .venv/bin/python experiments/residual_size.py runs/anchored/policy
"""
import sys

import jax
import jax.numpy as jnp
import numpy as np

from dexguitar import envs
from dexguitar.learn import windows as D
from dexguitar.learn import policy as PO
from dexguitar.motion import feedforward as FF
from dexguitar.music import procedural
from dexguitar.music import timeline as TL

if __name__ == "__main__":
    params, meta = PO.load(sys.argv[1])
    spec = PO.PolicySpec.from_meta(meta)
    planner, planner_meta = PO.load("models/policies/left_general")
    config = envs.EnvConfig(shift_prob=0.0, tempo_prob=0.0, feedforward=spec.feedforward)
    songs = procedural.material("left", "general", 1, 8)
    env = envs.make("left", FF.prepare([TL.from_song(s) for s in songs], config), config)
    keys = jax.random.split(jax.random.PRNGKey(0), 16)
    no_plan = jnp.zeros((16, env.config.episode_frames, env.action_size))
    rollout = D.rollout_fn(env, PO.PolicySpec.from_meta(planner_meta))
    obs, alive, _, _ = D.chunked(rollout, planner, keys, no_plan, True, jnp.float32(0), jax.random.PRNGKey(1))
    mu, log_std = PO.distribution(spec, params, jnp.asarray(obs[alive]))
    mu, std = np.asarray(mu), np.exp(np.asarray(log_std))
    print(f"{mu.shape[0]} states: mean action rms {np.sqrt((mu ** 2).mean()):.2g}, max {np.abs(mu).max():.2g} of a "
          f"half range; std {std.mean():.2g}; KL to the zero residual {(0.5 * (mu / std) ** 2).sum(-1).mean():.3g}")
