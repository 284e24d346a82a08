"""Training windows played in MJX by the IK planner's actions or by a policy's mean action, with optional noise: how
exact the left hand's actions must be (`experiments/planner_noise.py`), and whether a trained residual plays better
or only survives its own noise (`experiments/residual_noise.py`).

The planner's actions for a window depend on the window only (open-loop PD targets from the home pose), so they are
planned once per reset key, in CPU processes, and rolled out beside any policy.

Data flow: song batch -> training windows (the env's own sampler, augmentation included) -> plans (CPU processes)
-> MJX rollouts (jit + vmap: the observations and per-note scores).
"""
from __future__ import annotations

import time

import jax
import jax.numpy as jnp
import numpy as np

from dexguitar.envs.core import GuitarEnv
from dexguitar.learn import policy as PO
from dexguitar.motion.feedforward import in_processes, plan_notes
from dexguitar.motion.planner import LATEST, RIGHT_LATEST, Notes


# ------------------------------------------------------------------------------------------------- plans

def window_keys(key, n: int):
    """Per window, the reset key whose window the plan is made for."""
    return jax.random.split(key, n)


def plan_windows(env: GuitarEnv, keys, workers: int = 0, log=print) -> list[np.ndarray]:
    """The planner's actions for the window `env.reset(k)` samples, per key k (CPU processes in parallel)."""
    sample = jax.jit(jax.vmap(lambda k: env.sample_window(jax.random.split(k, 3)[0])))   # as `reset` splits it
    windows = jax.tree.map(np.asarray, sample(keys))
    role = env.roles[0]
    version = LATEST if role == "left" else RIGHT_LATEST
    jobs = []
    for i in range(len(keys)):
        notes = Notes.from_window(jax.tree.map(lambda x: x[i], windows))
        jobs.append((notes.left, notes.pick, notes.onset, version, role))
    t0 = time.time()
    plans, workers = in_processes(plan_notes, jobs, workers)
    log(f"planned {len(plans)} window{'s' * (len(plans) != 1)} ({sum(len(a) for a, _ in plans):,} frames) in "
        f"{time.time() - t0:.0f} s on {workers} process{'es' * (workers != 1)}")
    return [action for action, _ in plans]


def pad_plans(plans: list[np.ndarray], frames: int) -> tuple[np.ndarray, np.ndarray]:
    """(actions (B, frames, A) padded with each plan's last action, valid (B, frames)), cut at `frames`."""
    acts = np.stack([np.concatenate([p[:frames], np.repeat(p[-1:], max(frames - len(p), 0), 0)]) for p in plans])
    valid = np.arange(frames)[None] < np.array([len(p) for p in plans])[:, None]
    return np.clip(acts, -1.0, 1.0).astype(np.float32), valid


# ------------------------------------------------------------------------------------------------- rollouts

def rollout_fn(env: GuitarEnv, spec: PO.PolicySpec):
    """rollout(params, keys, plans, student, noise, key) -> (obs (B, T, O), alive (B, T), scores (B, T, 3),
    closed (B, T)): each window from `env.reset(k)`, stepped with the plan's actions or (`student`) the policy's mean,
    plus noise. `alive` is False from an episode's termination on; `scores` are the hand's per-note precision, recall
    and F1 where a note closed."""
    act = PO.act_fn(spec, deterministic=True)
    hand = spec.hand

    def one(params, key, plan, student, noise, k_noise):
        state = env.reset(key)

        def body(carry, xs):
            s, alive = carry
            a_plan, k = xs
            a = jnp.where(student, act(params, s.obs[None])[0][0], a_plan)
            a = a + noise * jax.random.normal(k, a.shape)
            nxt = env.step(s, a)
            closed = nxt.info["note_end"] & (nxt.info["song_note"] >= 0) & alive
            out = (s.obs, alive, nxt.info[hand][:3], closed)
            return (nxt, alive & ~nxt.terminated), out
        ks = jax.random.split(k_noise, plan.shape[0])
        return jax.lax.scan(body, (state, jnp.bool_(True)), (plan, ks))[1]

    @jax.jit
    def rollout(params, keys, plans, student, noise, key):
        return jax.vmap(one, in_axes=(None, 0, 0, None, None, 0))(params, keys, plans, student, noise,
                                                                  jax.random.split(key, keys.shape[0]))
    return rollout


def chunked(rollout, params, keys, plans, student, noise, key):
    """`rollout` over slices of the windows: all at once on an accelerator, 16 at a time on a CPU, where XLA's
    thread pool hung (all threads idle, the result never ready) on 32 windows of 600 steps or 64 of 100."""
    n = keys.shape[0]
    size = n if jax.default_backend() != "cpu" else 16
    parts = [jax.tree.map(np.asarray, rollout(params, keys[i:i + size], plans[i:i + size], student, noise,
                                              jax.random.fold_in(key, i)))
             for i in range(0, n, size)]
    return tuple(np.concatenate(x) for x in zip(*parts))


def window_scores(scores, closed, valid) -> np.ndarray:
    """Mean per-note (precision, recall, F1) over the notes closed inside the plans (the song notes of each window)."""
    m = np.asarray(closed) & valid
    return np.asarray(scores)[m].mean(0) if m.any() else np.full(3, np.nan)


def window_f1(scores, closed, valid) -> float:
    return float(window_scores(scores, closed, valid)[2])


__all__ = ["plan_windows", "pad_plans", "rollout_fn", "chunked", "window_keys", "window_scores", "window_f1"]
