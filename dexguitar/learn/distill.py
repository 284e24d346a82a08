"""Behaviour cloning from the IK planner: a policy that starts where the scripted hand already plays.

Why: PPO from scratch learns slowly to reach away from the home pose (issue 11: 0.19 zero-shot on the authors' songs
after 2e8 samples), while the planner (`motion.planner`, no learning) plays those songs at 0.87 with the left hand.
The planner's actions for a training window depend on the window only (open-loop PD targets from the home pose), so
they label every state a policy visits at that step of that window. That makes DAgger free of teacher queries:
round 0 rolls out the planner's actions, every later round the student's own mean actions, and each visited
observation is labelled with the planner's action of its step. The student's mean is fitted by least squares to the
aggregated labels; the export gets a small constant log-std, so PPO can go on from it (`--init-from`).

Measured (experiments/results/general_left/distill.md): not yet a hand that plays. The fitted mean misses the plans by
an RMS of ~0.03 of a half range, where 0.01 of noise already costs the planner a third of its F1, and open-loop labels
give no correction off the planned trajectory: 0.00-0.02 on the authors' songs.

Data flow: song batch -> training windows (the env's own sampler, augmentation included) -> plans (CPU processes)
-> MJX rollouts (jit + vmap, the obs and per-note scores) -> Adam on the policy mean -> export.
"""
from __future__ import annotations

import dataclasses
import time
import warnings

import jax
import jax.numpy as jnp
import numpy as np
import optax

from dexguitar.envs.core import GuitarEnv
from dexguitar.learn import networks as N
from dexguitar.learn import policy as PO
from dexguitar.motion.feedforward import in_processes


@dataclasses.dataclass(frozen=True)
class DistillConfig:
    windows: int = 1024          # planned training windows (each a rest + 9..18 notes, from the home pose)
    rounds: int = 3              # round 0: the planner's rollouts; rounds 1..: the student's (DAgger)
    steps: int = 2000            # Adam steps per round, on all the data gathered so far
    batch: int = 4096            # samples per Adam step
    lr: float = 3e-4
    # Action noise costs the planner most of its F1 (results/planner_noise.md: 0.60 without, 0.41 at std 0.01, 0.28
    # at 0.02, of which the wrist alone 0.27), hence these three:
    noise: float = 0.0           # Gaussian noise on the rolled-out actions
    wrist_weight: float = 10.0   # loss weight of the 6 wrist DoFs, which carry every fingertip
    log_std: float = -4.0        # the export's action log-std for PPO to go on from (std 0.018; the networks' -2.3)
    workers: int = 0             # planning processes; 0 = one per CPU
    seed: int = 0

    def check(self) -> None:
        for name in ("windows", "rounds", "steps", "batch"):
            if getattr(self, name) < 1:
                raise ValueError(f"DistillConfig.{name} must be at least 1, got {getattr(self, name)}")


# ------------------------------------------------------------------------------------------------- plans

_PLANNERS: dict = {}


def _plan(job):
    """One window's planned env actions (frames, 27), in a worker process (planners and IK caches kept there)."""
    from dexguitar.motion.planner import Notes, ScriptedLeft, ScriptedRight, Tracker
    role, left, pick, onset = job
    if role not in _PLANNERS:
        _PLANNERS[role] = (ScriptedLeft() if role == "left" else ScriptedRight(), Tracker(role))
    hand, tracker = _PLANNERS[role]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")          # "the pick cannot reach its stroke": the window still counts
        ctrl, _ = tracker.track(hand.desired(Notes(left, pick, onset)))
    return tracker.to_action(ctrl).astype(np.float32)


def window_keys(key, n: int):
    """Per window, the reset key whose window the plan is made for."""
    return jax.random.split(key, n)


def plan_windows(env: GuitarEnv, keys, workers: int = 0, log=print) -> list[np.ndarray]:
    """The planner's actions for the window `env.reset(k)` samples, per key k (CPU processes in parallel)."""
    from dexguitar.motion.planner import Notes
    sample = jax.jit(jax.vmap(lambda k: env.sample_window(jax.random.split(k, 3)[0])))   # as `reset` splits it
    windows = jax.tree.map(np.asarray, sample(keys))
    role = env.roles[0]
    jobs = []
    for i in range(len(keys)):
        notes = Notes.from_window(jax.tree.map(lambda x: x[i], windows))
        jobs.append((role, notes.left, notes.pick, notes.onset))
    t0 = time.time()
    plans, workers = in_processes(_plan, jobs, workers)
    log(f"planned {len(plans)} windows ({sum(len(p) for p in plans):,} frames) in {time.time() - t0:.0f} s "
        f"on {workers} processes")
    return plans


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


# ------------------------------------------------------------------------------------------------- fitting

def frame_stats(spec: PO.PolicySpec, obs: np.ndarray) -> dict:
    """The observation normalizer (`networks.normalizer_init` form) of the pose frames in `obs` (N, O)."""
    state = spec.layout.split(obs)[0].reshape(-1, spec.layout.frame_size).astype(np.float64)
    return {"mean": jnp.asarray(state.mean(0), jnp.float32), "var": jnp.asarray(state.var(0), jnp.float32),
            "count": jnp.float32(len(state))}


def fit_fn(spec: PO.PolicySpec, cfg: DistillConfig):
    """fit(params, opt_state, obs (N, O), labels (N, A), key) -> (params, opt_state, losses (steps,)): Adam on the
    mean squared error of the policy mean, `cfg.steps` minibatches of `cfg.batch` drawn with replacement."""
    tx = optax.adam(cfg.lr)
    weight = jnp.ones(spec.action_size).at[:6].set(cfg.wrist_weight)

    def loss_fn(p, obs, labels):
        mu, _ = PO.distribution(spec, p, obs)
        return jnp.mean(jnp.sum(weight * (mu - labels) ** 2, -1))

    @jax.jit
    def fit(params, opt_state, obs, labels, key):
        def step(carry, k):
            net, opt = carry
            idx = jax.random.randint(k, (cfg.batch,), 0, obs.shape[0])
            loss, g = jax.value_and_grad(lambda n: loss_fn({**params, "policy": n}, obs[idx], labels[idx]))(net)
            upd, opt = tx.update(g, opt, net)
            return (optax.apply_updates(net, upd), opt), loss
        (net, opt_state), losses = jax.lax.scan(step, (params["policy"], opt_state), jax.random.split(key, cfg.steps))
        return {**params, "policy": net}, opt_state, losses
    return fit, tx


# ------------------------------------------------------------------------------------------------- the loop

def distill(env: GuitarEnv, cfg: DistillConfig, log=print):
    """(params, spec, history): a policy of `env`'s hand fitted to the planner by `cfg.rounds` DAgger rounds.
    `history` holds per round the rolled-out window F1 (round 0: the planner's), the data size and the losses, then
    the fitted student's window F1."""
    cfg.check()
    key = jax.random.PRNGKey(cfg.seed)
    k_windows, k_init, key = jax.random.split(key, 3)
    keys = window_keys(k_windows, cfg.windows)
    plans = plan_windows(env, keys, cfg.workers, log)
    frames = env.config.episode_frames
    acts, valid = pad_plans(plans, frames)
    spec = PO.PolicySpec("policy", env.roles[0], env.action_size, env.layout)
    params = {"policy": N.init_params(N.Policy(spec.action_size), k_init, (spec.layout.history, spec.layout.frame),
                                      (spec.layout.goal,)),
              "obs_norm": N.normalizer_init(spec.layout.frame)}
    rollout = rollout_fn(env, spec)
    fit, tx = fit_fn(spec, cfg)
    opt_state = tx.init(params["policy"])
    data_obs, data_act, history = [], [], []
    for r in range(cfg.rounds):
        key, k_roll, k_fit = jax.random.split(key, 3)
        t0 = time.time()
        obs, alive, scores, closed = chunked(rollout, params, keys, jnp.asarray(acts), r > 0, jnp.float32(cfg.noise),
                                         k_roll)
        keep = valid & alive
        data_obs.append(obs[keep])
        data_act.append(acts[keep])
        score = window_f1(scores, closed, valid)
        if r == 0:
            params = {**params, "obs_norm": frame_stats(spec, data_obs[0])}
        all_obs, all_act = jnp.asarray(np.concatenate(data_obs)), jnp.asarray(np.concatenate(data_act))
        t1 = time.time()
        params, opt_state, losses = fit(params, opt_state, all_obs, all_act, k_fit)
        loss = float(losses[-1])
        history.append({"round": r, "rolled_out": "planner" if r == 0 else "student", "window_f1": score,
                        "samples": int(all_obs.shape[0]), "loss_first": float(losses[0]), "loss": loss,
                        "rollout_s": t1 - t0, "fit_s": time.time() - t1})
        log(f"round {r}: {'planner' if r == 0 else 'student'} F1 on its windows {score:.3f} (noise {cfg.noise}); "
            f"fitted {cfg.steps} steps on {all_obs.shape[0]:,} samples, loss {float(losses[0]):.4f} -> {loss:.4f} "
            f"({t1 - t0:.0f} s rollout, {time.time() - t1:.0f} s fit)")
    _, _, scores, closed = chunked(rollout, params, keys, jnp.asarray(acts), True, jnp.float32(0.0), key)
    history.append({"round": cfg.rounds, "rolled_out": "student", "window_f1": window_f1(scores, closed, valid)})
    log(f"the fitted student's F1 on the windows: {history[-1]['window_f1']:.3f}")
    return params, spec, history


def with_log_std(params, log_std: float):
    """The policy with its log-std head set to the constant `log_std` (zero kernel)."""
    net = params["policy"]["params"]
    head = {"kernel": jnp.zeros_like(net["log_std"]["kernel"]), "bias": jnp.full_like(net["log_std"]["bias"], log_std)}
    return {**params, "policy": {**params["policy"], "params": {**net, "log_std": head}}}


def export(directory, params, spec: PO.PolicySpec, cfg: DistillConfig, history, meta: dict | None = None) -> None:
    """The fitted policy with the log-std of `cfg`, as `policy.export` writes any policy."""
    params = with_log_std(params, cfg.log_std)
    PO.export(directory, params, {**spec.to_meta(), "iteration": 0, "samples": 0, "distilled": {
        "config": dataclasses.asdict(cfg), "history": history}, **(meta or {})})


__all__ = ["DistillConfig", "distill", "plan_windows", "pad_plans", "rollout_fn", "fit_fn", "frame_stats", "export",
           "window_keys", "window_scores", "window_f1"]
