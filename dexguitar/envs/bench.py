"""Env throughput: control steps per second of the full env step (physics, detection, rewards, bookkeeping,
auto-reset), timed apart from compilation. `bare=True` times the MJX physics alone for comparison."""
from __future__ import annotations

import time

import jax
from dexguitar import mjx as _quiet_mjx

from dexguitar.world import scene as S

mjx = _quiet_mjx()


def default_songs(hand: str):
    """The embedded songs (left, duet) or procedural picking patterns (right)."""
    from dexguitar.music import library, procedural
    from dexguitar.music import timeline as TL
    songs = procedural.right_patterns(0, 16) if hand == "right" else [library.load(n) for n in library.names()]
    return [TL.from_song(s) for s in songs]


def bench_env(hand: str, n_envs: int, steps: int, *, bare: bool = False, noise: float = 0.05, seed: int = 0,
              backend: str = "jax") -> dict:
    from dexguitar import envs
    env = envs.make(hand, default_songs(hand), backend=backend) if backend != "jax" else envs.make(
        hand, default_songs(hand))
    keys = jax.random.split(jax.random.PRNGKey(seed), n_envs)

    if bare:
        data0 = jax.vmap(env.reset)(keys).data

        def one(data, key):
            ctrl = env.action_to_ctrl(noise * jax.random.normal(key, (env.action_size,)))
            data = data.replace(ctrl=ctrl)
            return jax.lax.fori_loop(0, S.SUBSTEPS, lambda _, d: mjx.step(env.mjx_model, d), data)

        def body(carry, _):
            data, key = carry
            key, sub = jax.random.split(key)
            return (jax.vmap(one)(data, jax.random.split(sub, n_envs)), key), None
        carry0 = (data0, jax.random.PRNGKey(seed + 1))
    else:
        state0 = jax.vmap(env.reset)(keys)

        def body(carry, _):
            state, key = carry
            key, sub = jax.random.split(key)
            action = noise * jax.random.normal(sub, (n_envs, env.action_size))
            return (jax.vmap(env.step)(state, action), key), None
        carry0 = (state0, jax.random.PRNGKey(seed + 1))

    run = jax.jit(lambda c: jax.lax.scan(body, c, None, length=steps)[0])
    t0 = time.perf_counter()
    compiled = run.lower(carry0).compile()
    compile_s = time.perf_counter() - t0
    out = jax.block_until_ready(compiled(carry0))           # warm-up
    t0 = time.perf_counter()
    out = jax.block_until_ready(compiled(out))
    run_s = time.perf_counter() - t0
    rate = n_envs * steps / run_s
    return {"hand": hand, "envs": n_envs, "steps": steps, "bare": bare, "compile_s": compile_s, "run_s": run_s,
            "control_steps_per_s": rate, "physics_steps_per_s": rate * S.SUBSTEPS,
            "device": jax.devices()[0].device_kind, "backend": jax.default_backend()}
