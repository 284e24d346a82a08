"""Env throughput: control steps per second of the full env step (physics, detection, rewards, bookkeeping,
auto-reset), timed apart from compilation, under either MJX implementation (`EnvConfig.physics`). `bare=True` times
the MJX physics alone for comparison. Each run also reports how often the constraint solver used all its iterations
at the last physics step of a control step and, under Warp, the most contacts the envs had at once."""
from __future__ import annotations

import time

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from dexguitar import envs
from dexguitar import mjx as _quiet_mjx
from dexguitar.music import library, procedural
from dexguitar.music import timeline as TL
from dexguitar.world import scene as S
from dexguitar.world.physics import control_step

mjx = _quiet_mjx()


def default_songs(hand: str):
    """The embedded songs (left, duet) or procedural picking patterns (right)."""
    songs = procedural.right_patterns(0, 16) if hand == "right" else [library.load(n) for n in library.names()]
    return [TL.from_song(s) for s in songs]


def bench_env(hand: str, n_envs: int, steps: int, *, bare: bool = False, noise: float = 0.05, seed: int = 0,
              physics: str = "auto") -> dict:
    env = envs.make(hand, default_songs(hand), physics=physics, warp_envs=n_envs)
    keys = jax.random.split(jax.random.PRNGKey(seed), n_envs)

    def solver(data):
        """(envs whose solver used all its iterations, contacts of all envs: Warp's count, -1 under JAX)."""
        impl = data._impl
        full = jnp.sum(impl.solver_niter.reshape(n_envs, -1)[:, -1] >= env.model.opt.iterations)
        return full, impl.nacon.reshape(-1)[0] if hasattr(impl, "nacon") else jnp.int32(-1)

    if bare:
        data0 = jax.vmap(env.reset)(keys).body.data

        def one(data, key):
            return control_step(env.mjx_model, data, env.action_to_ctrl(noise * jax.random.normal(
                key, (env.action_size,))))

        def body(carry, _):
            data, key = carry
            key, sub = jax.random.split(key)
            data = jax.vmap(one)(data, jax.random.split(sub, n_envs))
            return (data, key), solver(data)
        carry0 = (data0, jax.random.PRNGKey(seed + 1))
    else:
        state0 = jax.vmap(env.reset)(keys)

        def body(carry, _):
            state, key = carry
            key, sub = jax.random.split(key)
            action = noise * jax.random.normal(sub, (n_envs, env.action_size))
            state = jax.vmap(env.step)(state, action)
            return (state, key), solver(state.body.data)
        carry0 = (state0, jax.random.PRNGKey(seed + 1))

    run = jax.jit(lambda c: jax.lax.scan(body, c, None, length=steps))
    t0 = time.perf_counter()
    compiled = run.lower(carry0).compile()
    compile_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    out, _ = jax.block_until_ready(compiled(carry0))           # warm-up (Warp builds its kernels on first use)
    first_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    out, (full, contacts) = jax.block_until_ready(compiled(out))
    run_s = time.perf_counter() - t0
    rate = n_envs * steps / run_s
    return {"hand": hand, "envs": n_envs, "steps": steps, "bare": bare, "physics": env.physics,
            "compile_s": compile_s, "first_run_s": first_s, "run_s": run_s,
            "control_steps_per_s": rate, "physics_steps_per_s": rate * S.SUBSTEPS,
            "solver_at_limit": float(np.mean(np.asarray(full))) / n_envs, "solver_iterations": env.model.opt.iterations,
            "max_contacts": int(np.max(np.asarray(contacts))),
            "device": jax.devices()[0].device_kind, "backend": jax.default_backend()}


def check_scenes(n_envs: int = 4, steps: int = 60, mirrored: bool = False) -> list[dict]:
    """Every scene (and with `mirrored` its left-handed twin) held at its home pose for `steps` control steps by
    n_envs vmapped MJX copies: compile time, speed, and whether the state stayed finite."""
    rows = []
    for name in S.SCENES:
        for mirror in ((False, True) if mirrored else (False,)):
            m = S.build_model(name, mirror=mirror)
            mx = mjx.put_model(m)
            d = mujoco.MjData(m)
            mujoco.mj_resetDataKeyframe(m, d, 0)
            batch = jax.tree.map(lambda x: jnp.stack([x] * n_envs), mjx.put_data(m, d))
            ctrl = jnp.asarray(m.key_qpos[0], jnp.float32)

            def rollout(data):
                step = jax.vmap(lambda x: control_step(mx, x, ctrl))
                return jax.lax.scan(lambda x, _: (step(x), None), data, None, length=steps)[0]
            run = jax.jit(rollout)
            t0 = time.perf_counter()
            out = jax.block_until_ready(run(batch))
            compile_s = time.perf_counter() - t0
            t0 = time.perf_counter()
            out = jax.block_until_ready(run(out))
            run_s = time.perf_counter() - t0
            rows.append({"scene": name + (" (mirrored)" if mirror else ""), "dof": m.nq, "compile_s": compile_s,
                         "control_steps_per_s": n_envs * steps / run_s,
                         "finite": bool(np.all(np.isfinite(np.asarray(out.qpos))))})
    return rows
