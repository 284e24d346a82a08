"""How much of a first run's compile any training program on MJX pays (issue 10, "compile once"): the GSync
training chunk of a song against the parts it is built of, each compiled from nothing in one process (no persistent
cache), in this order:

- `physics`: `horizon` control steps of the vmapped duet (`world.physics.control_step`: 4 MJX steps), nothing else;
- `env`: `horizon` steps of the vmapped training env (physics, detection, rewards, scoring, the auto-reset) with zero
  actions, no policy;
- `rollout`: the trainer's rollout (env and the frozen pair with the synchronizer);
- `chunk`: the whole training chunk (`iterations_per_call` iterations of rollout, GAE, discriminator and PPO updates).

Each is a `lax.scan` as in the chunk, so it shows the floor under the 30-second goal: what the physics alone costs to
compile, before a single network or update is in the program. Prints one JSON line per program: seconds, and its size
as jaxpr equations (those of loop bodies counted once, as XLA compiles them) and HLO text.

    XLA_FLAGS=--xla_gpu_enable_triton_gemm=false python experiments/compile_floor.py SONG.json [ENVS]
"""
import dataclasses
import json
import sys
import time

import jax
import jax.numpy as jnp
from jax.extend import core as jcore

from dexguitar.cli import load_config, load_motion, load_song, reference_frames
from dexguitar.learn import policy as PO
from dexguitar.learn.devices import Placement
from dexguitar.learn.sync import SyncTrainer
from dexguitar.music import timeline as TL
from dexguitar.world.physics import control_step, mjx


def equations(jaxpr) -> int:
    """The primitive equations of `jaxpr`, those of every sub-jaxpr (loop bodies, branches, inner jits) included."""
    n = 0
    for eqn in jaxpr.eqns:
        subs = list(jcore.jaxprs_in_params(eqn.params))
        n += sum(map(equations, subs)) if subs else 1
    return n


def timed_compile(name: str, fn, *args) -> dict:
    """Trace, lower and compile `fn(*args)` apart; one JSON line."""
    t0 = time.perf_counter()
    traced = jax.jit(fn).trace(*args) if not hasattr(fn, "trace") else fn.trace(*args)
    t1 = time.perf_counter()
    lowered = traced.lower()
    t2 = time.perf_counter()
    lowered.compile()
    t3 = time.perf_counter()
    row = {"program": name, "trace_s": round(t1 - t0, 1), "lower_s": round(t2 - t1, 1),
           "compile_s": round(t3 - t2, 1), "equations": equations(traced.jaxpr.jaxpr),
           "hlo_mb": round(len(lowered.as_text()) / 1e6, 2), "device": jax.devices()[0].device_kind}
    print(json.dumps(row), flush=True)
    return row


def main(song_file: str, envs: int = 0) -> list:
    jax.config.update("jax_enable_compilation_cache", False)
    cfg, env_cfg = load_config("sync_hold", hand="duet", num_envs=envs or None)
    if envs:
        cfg = dataclasses.replace(cfg, minibatch=min(cfg.minibatch, envs * cfg.horizon))
    pair = PO.load_pair("models/policies/left_general", "models/policies/right_mixed")
    trainer = SyncTrainer(cfg, [TL.from_song(load_song(song_file))], reference_frames(load_motion("left")),
                          *pair, env_cfg)
    state = jax.block_until_ready(trainer.init())
    env, steps = trainer.env, cfg.horizon
    one = jax.tree.map(lambda x: x[0], state.env.body.data)
    for name, fn in (("mjx.kinematics", mjx.kinematics), ("mjx.step", mjx.step)):    # sizes only: half is kinematics
        print(json.dumps({"program": name, "equations": equations(jax.make_jaxpr(
            lambda d, fn=fn: fn(env.mjx_model, d))(one).jaxpr)}), flush=True)

    def physics(data):
        step = jax.vmap(lambda d: control_step(env.mjx_model, d, d.ctrl))
        return jax.lax.scan(lambda d, _: (step(d), None), data, None, length=steps)[0]

    def env_steps(env_state):
        zero = jnp.zeros((cfg.num_envs, env.action_size))
        return jax.lax.scan(lambda s, _: (jax.vmap(env.step)(s, zero), None), env_state, None, length=steps)[0]

    rows = [timed_compile("physics", physics, state.env.body.data),
            timed_compile("env", env_steps, state.env),
            timed_compile("rollout", lambda ts, k: trainer.rollout(env, ts, k), state, jax.random.PRNGKey(0)),
            timed_compile("chunk", trainer.make_train_chunk(cfg.iterations_per_call, Placement()), state,
                          trainer.data)]
    return rows


if __name__ == "__main__":          # planning spawns worker processes: they import this module
    main(sys.argv[1], *(int(v) for v in sys.argv[2:3]))
