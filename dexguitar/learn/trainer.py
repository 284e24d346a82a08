"""One hand at a time: PPO + GAN-like imitation as a jitted training iteration, run many times per host call.

An iteration = rollout (`lax.scan` over the vmapped env and policy) -> discriminator update -> discriminator
rewards -> per-column GAE with PopArt -> observation normalizer update -> PPO epochs over minibatches, in three
stages (`act`, `judge`, `learn`), each a program of its own (`learn.stages`), or one program scanning whole
iterations (`TrainConfig.one_program`). Everything, env states included, lives in one `TrainState` pytree, so a
checkpoint holds the whole run and a resumed run continues with exactly the iteration it would have run next.

The songs and the reference motion are an argument of the compiled chunk (`Data`), padded to fixed capacities, never
constants inside it: one compiled program serves every song set of a size. Non-finite numbers are contained where
they arise: an env whose physics went non-finite is terminated and reset (`envs.core`), an update whose gradients
are non-finite is skipped, and the counts come back in the metrics (`nonfinite/*`) for the host to act on.
"""
from __future__ import annotations

import dataclasses
import functools
from typing import Any

import jax
import jax.numpy as jnp
import optax
from flax import struct

from dexguitar import envs as E
from dexguitar.errors import UserError
from dexguitar.learn import imitation as IM
from dexguitar.learn import networks as N
from dexguitar.learn import ppo
from dexguitar.learn.devices import Placement
from dexguitar.learn.policy import PolicySpec, act_fn, distribution
from dexguitar.learn.stages import Stages
from dexguitar.music import timeline as TL


@dataclasses.dataclass(frozen=True)
class TrainConfig:
    """Defaults reproduce Table S1 of the paper (one V100: 512 envs); dexguitar/configs/ holds the GPU-sized configs."""

    hand: str = "left"
    num_envs: int = 512               # PPO workers
    horizon: int = 8                  # 512 x 8 = 4096 samples per update ("PPO replay buffer size")
    minibatch: int = 256              # PPO batch size
    epochs: int = 5                   # PPO optimization epochs
    actor_lr: float = 5e-6
    critic_lr: float = 1e-4
    disc_lr: float = 1e-5
    gamma: float = 0.95               # reward discount
    lam: float = 0.95                 # GAE discount
    clip: float = 0.2                 # surrogate clip range
    grad_clip: float = 1.0
    value_coef: float = 0.5
    gp_weight: float = 10.0           # gradient penalty coefficient
    disc_buffer: int = 8192           # discriminator replay buffer size
    disc_batch: int = 512             # discriminator batch: half simulated, half reference
    disc_steps: int = 16              # discriminator minibatches per iteration
    goal_weight: float = -1.0         # per goal column; -1 = the env's (`reward_weights`)
    disc_weight: float = -1.0         # per discriminator column; -1 = the discriminator's (`imitation`)
    iterations: int = 100_000         # ~4e8 samples at 4096 per iteration
    iterations_per_call: int = 50     # run on the device between host updates
    one_program: bool = False         # True: a host call's iterations as one program, a `lax.scan` of iterations;
                                      # False: each iteration's three stages as programs compiled at once
                                      # (`learn.stages`: a first compile in half the time, the same numbers)
    actor_warmup: int = 0             # iterations in which only the critic and discriminators learn (warm starts)
    log_std_init: float = -2.3        # initial log std of the actions: std 0.1 of a half range (reference §7.1)
    kl_target: float = 0.0            # > 0: the actor's learning rate adapts to hold this KL per minibatch step
    action_scale: float = 1.0         # the policy's action times this (`networks.Policy.scale`; 1: the paper's)
    prior_kl: float = 0.0             # > 0: weight of KL(pi || N(0, std)), pulling the mean to the zero action
    teacher_weight: float = 0.0       # > 0: the actor's loss adds this x the negative log-likelihood, per action
                                      # number, of the planner's label of each visited state (`EnvConfig.teacher`):
                                      # DAgger on the student's own states, beside PPO (not in the paper)
    teacher_fade: int = 0             # iterations over which teacher_weight falls linearly to 0 (0: it stays)
    seed: int = 42

    @property
    def batch(self) -> int:
        return self.num_envs * self.horizon

    def check(self) -> None:
        """Refuse sizes that cannot train, naming the field."""
        for name in ("num_envs", "horizon", "minibatch", "epochs", "iterations", "iterations_per_call",
                     "disc_steps", "disc_batch", "disc_buffer"):
            if getattr(self, name) < 1:
                raise ValueError(f"TrainConfig.{name} must be at least 1, got {getattr(self, name)}")
        if self.actor_warmup < 0:
            raise ValueError(f"TrainConfig.actor_warmup must be at least 0, got {self.actor_warmup}")
        if self.kl_target < 0:
            raise ValueError(f"TrainConfig.kl_target must be at least 0, got {self.kl_target}")
        if self.prior_kl < 0:
            raise ValueError(f"TrainConfig.prior_kl must be at least 0, got {self.prior_kl}")
        if self.teacher_weight < 0 or self.teacher_fade < 0:
            raise ValueError(f"TrainConfig.teacher_weight and teacher_fade must be at least 0, got "
                             f"{self.teacher_weight} and {self.teacher_fade}")
        if not self.action_scale > 0:
            raise ValueError(f"TrainConfig.action_scale must be above 0, got {self.action_scale}")
        if self.minibatch > self.batch:
            raise ValueError(f"TrainConfig.minibatch {self.minibatch} exceeds the batch of {self.num_envs} envs x "
                             f"{self.horizon} steps = {self.batch}")


@struct.dataclass
class Data:
    """What a training chunk reads besides its state; an argument, so its values are never compiled in."""

    songs: TL.Timeline             # a padded batch (`timeline.batch`)
    reference: dict                # {discriminator: (T, F) its features of each reference frame at 60 Hz, padded}
    reference_frames: jnp.ndarray  # int32 (): valid frames of `reference`


KL_LR_BOUNDS = (1e-6, 1e-2)           # the adaptive actor learning rate stays within these


def adapt_lr(lr, kl, target: float):
    """The adaptive learning rate's step: /1.5 when the policy moved more than twice the KL target, x1.5 when less
    than half of it (the schedule of massively parallel PPO, e.g. Rudin et al. 2022)."""
    lr = jnp.where(kl > 2.0 * target, lr / 1.5, jnp.where(kl < 0.5 * target, lr * 1.5, lr))
    return jnp.clip(lr, *KL_LR_BOUNDS)


def actor_schedule(cfg: TrainConfig):
    """The actor's learning rate per optimizer update: 0 for the first `actor_warmup` iterations (a fresh critic
    learns the values of a warm-started policy before that policy moves), then `actor_lr`."""
    updates = cfg.actor_warmup * cfg.epochs * max(cfg.batch // cfg.minibatch, 1)
    return lambda count: jnp.where(count < updates, 0.0, cfg.actor_lr)


@struct.dataclass
class TrainState:
    params: dict
    opt: dict
    obs_norm: dict
    disc_norm: dict
    popart: dict
    buffers: dict
    env: Any
    key: jnp.ndarray
    iteration: jnp.ndarray


def reference_data(reference, discs: dict) -> tuple[dict, jnp.ndarray]:
    """({discriminator: padded features}, count): each discriminator's input features of every frame of a reference
    motion (T, 16, 7), computed once here, so the training program only gathers windows of them; zero-padded to a
    power-of-two length."""
    n = IM.FRAMES if reference is None else reference.shape[0]
    pad = lambda x: jnp.zeros((TL.capacity(n, 1024), x.shape[-1]), jnp.float32).at[:n].set(x)  # noqa: E731
    return ({name: pad(IM.features(jnp.asarray(reference, jnp.float32), d.links, d.parent))
             for name, d in discs.items()}, jnp.int32(n))


def host_device():
    """The host's CPU, or the default device where JAX runs without its CPU backend (JAX_PLATFORMS=cuda)."""
    try:
        return jax.devices("cpu")[0]
    except RuntimeError:
        return jax.devices()[0]


def finite(tree) -> jnp.ndarray:
    """Are all the numbers of a pytree finite? One test of all of them joined: a test per array (hundreds, for
    parameters and optimizer states) would be as many reductions for XLA to compile."""
    leaves = [jnp.ravel(x) for x in jax.tree.leaves(tree) if jnp.issubdtype(x.dtype, jnp.inexact)]
    return jnp.all(jnp.isfinite(jnp.concatenate(leaves))) if leaves else jnp.bool_(True)


class Trainer:
    """Builds the networks and the jitted iteration for one hand over a song batch and reference motions."""

    def __init__(self, config: TrainConfig, songs, reference: jnp.ndarray | None, env_config=None,
                 devices: int | None = None):
        """songs: timelines (or a batch); reference: (T, 16, 7) link poses of the reference motion at 60 Hz (see
        `dexguitar.motion`), or None for no imitation. `devices`: how many devices the run spreads its envs over
        (default: every device, as `run.train`'s); the env's physics is chosen and sized for them
        (`EnvConfig.sized`)."""
        config.check()
        self.config = config
        if not isinstance(songs, TL.Timeline):
            songs = TL.batch(list(songs))
        env_config = env_config or E.EnvConfig(episode_frames=1200 if config.hand == "duet" else 600)  # envs.make's
        if config.teacher_weight and not env_config.teacher:
            raise ValueError("TrainConfig.teacher_weight learns from the planner's labels: the env needs "
                             "EnvConfig(teacher=True)")
        self.devices = Placement(devices).n
        if config.num_envs % self.devices or config.minibatch % self.devices:
            raise UserError(f"{config.num_envs} envs and minibatches of {config.minibatch} do not split evenly over "
                            f"{self.devices} devices")
        self.env = E.make(config.hand, songs, env_config.sized(config.num_envs, self.devices))
        self.layout = self.env.layout
        self.spec = self.make_spec()
        self.disc_specs = IM.DISCRIMINATORS[config.hand] if reference is not None else {}
        self.data = Data(self.env.songs, *reference_data(reference, self.disc_specs))
        self.columns = tuple(self.env.reward_columns) + tuple(f"disc_{n}" for n in self.disc_specs)
        goal = config.goal_weight if config.goal_weight >= 0 else None
        disc = config.disc_weight if config.disc_weight >= 0 else None
        self.weights = jnp.asarray([goal if goal is not None else w for w in self.env.reward_weights]
                                   + [disc if disc is not None else d.weight for d in self.disc_specs.values()],
                                   jnp.float32)
        self.critic = N.Critic(len(self.columns))
        self.disc = N.Discriminator()
        # The schedule (and its step counter in the optimizer state) only with a warm-up: runs without one keep
        # their checkpoint layout and compiled program. With a KL target the actor's step is Adam's direction times
        # a learning rate kept in the state (`opt["lr"]`).
        if config.kl_target:
            actor = optax.chain(optax.clip_by_global_norm(config.grad_clip), optax.scale_by_adam(),
                                optax.scale(-1.0))
        else:
            actor = optax.chain(optax.clip_by_global_norm(config.grad_clip),
                                optax.adam(actor_schedule(config) if config.actor_warmup else config.actor_lr))
        self.optimizers = {
            "policy": actor,
            "critic": optax.chain(optax.clip_by_global_norm(config.grad_clip), optax.adam(config.critic_lr)),
            "disc": optax.adam(config.disc_lr),
        }

    def make_spec(self) -> PolicySpec:
        return PolicySpec("policy", self.config.hand, self.env.action_size, self.layout,
                          bool(self.env.config.feedforward), self.config.action_scale,
                          bool(self.env.config.right_feedforward))

    # ------------------------------------------------------------------------------------------ init
    def init(self, key=None) -> TrainState:
        """The first state of a run. One compiled program per trainer shape: the songs (and a synchronizer's frozen
        policies) are its arguments (`init_inputs`), never constants, so the next song of a capacity loads it from
        the persistent cache instead of compiling it again.

        The networks' first parameters are drawn by a program of their own on the host's CPU: on a GPU, XLA took
        12.1 s to compile it (14,506 instructions, the orthogonal initializers' QR factorizations), beside the
        training chunk's compile and slowing it (docs/benchmarks.md, "A first and a later run under Warp")."""
        key = jax.random.PRNGKey(self.config.seed) if key is None else key
        inputs, cpu = self.init_inputs(), host_device()
        nets = self._params_program(jax.device_put(key, cpu), jax.device_put(inputs, cpu))
        return self._init_program(key, inputs, jax.device_put(nets, jax.devices()[0]))

    def init_inputs(self) -> dict:
        """What `init` reads besides the key: the arguments of its programs."""
        return {"songs": self.env.songs}

    @functools.cached_property
    def state_shapes(self):
        """The first state's shapes and dtypes (`jax.ShapeDtypeStruct`s), without computing it."""
        return jax.eval_shape(self.init)

    @functools.cached_property
    def _params_program(self):
        return jax.jit(self.initial_params)

    @functools.cached_property
    def _init_program(self):
        return jax.jit(self.initial_state)

    def initial_params(self, key, inputs: dict) -> tuple[dict, dict]:
        """(parameters {"policy", "critic", "disc"[, "frozen"]}, observation normalizer) of a run's start."""
        k_pol, k_crit, k_disc = jax.random.split(key, 6)[:3]
        policy, obs_norm, frozen = self.init_policy(k_pol, inputs)
        frames = (self.layout.history, self.layout.frame_size)
        params = {
            "policy": policy,
            "critic": N.init_params(self.critic, k_crit, frames, (self.layout.goal_size + self.layout.privileged,)),
            "disc": {name: N.init_params(self.disc, k, (IM.FRAMES, d.features))
                     for (name, d), k in zip(self.disc_specs.items(),
                                             jax.random.split(k_disc, max(len(self.disc_specs), 1)))},
        }
        if frozen is not None:
            params["frozen"] = frozen
        return params, obs_norm

    def optimizer_states(self, params: dict) -> dict:
        """The optimizers' first states for `params` (and the adaptive actor rate's, with a KL target)."""
        opt = {k: self.optimizers[k].init(params[k]) for k in self.optimizers if k in params}
        if self.config.kl_target:
            opt["lr"] = jnp.float32(self.config.actor_lr)
        return opt

    def initial_state(self, key, inputs: dict, nets: tuple[dict, dict] | None = None) -> TrainState:
        """The first state from `key`; `nets`: `initial_params(key, inputs)`, made here if not given."""
        cfg = self.config
        params, obs_norm = self.initial_params(key, inputs) if nets is None else nets
        k_env, k_age, key = jax.random.split(key, 6)[3:]
        opt = self.optimizer_states(params)
        env_state = self.reset_envs(self.env.bind(inputs["songs"]), jax.random.split(k_env, cfg.num_envs))
        # Envs start at random ages, so their time-outs spread over the episode instead of all of them restarting
        # from the home pose together every `episode_frames` steps.
        env_state = env_state.replace(lifetime=jax.random.randint(k_age, (cfg.num_envs,), 0,
                                                                  self.env.config.episode_frames))
        return TrainState(
            params=params, opt=opt, obs_norm=obs_norm,
            disc_norm={n: N.normalizer_init(d.features) for n, d in self.disc_specs.items()},
            popart=ppo.popart_init(len(self.columns)),
            buffers={n: IM.buffer_init(cfg.disc_buffer, (IM.FRAMES, d.features)) for n, d in self.disc_specs.items()},
            env=env_state, key=key, iteration=jnp.int32(0))

    def reset_envs(self, env, keys):
        """The envs reset from `keys`. Under Warp in as many groups as the run has devices, joined along their first
        axis: each group holds the Warp buffers that its device steps it with (`Placement.each`; sized for a group of
        envs, `EnvConfig.sized`). Under JAX every leaf is per env, so one reset of them all is the same state, traced
        once instead of once per device."""
        groups = [jax.vmap(env.reset)(k) for k in jnp.split(keys, self.devices if env.physics == "warp" else 1)]
        return groups[0] if len(groups) == 1 else jax.tree.map(lambda *x: jnp.concatenate(x), *groups)

    # ------------------------------------------------------------------------------------------ pieces
    def init_policy(self, key, inputs: dict | None = None):
        """(trainable policy parameters, observation normalizer, frozen parameters or None); `inputs`: `init`'s."""
        policy = N.Policy(self.env.action_size, self.config.log_std_init, self.config.action_scale)
        params = N.init_params(policy, key, (self.layout.history, self.layout.frame_size), (self.layout.goal_size,))
        if self.env.config.feedforward or self.env.config.right_feedforward:   # a residual starts at exactly zero
            mu = dict(params["params"]["mu"], kernel=jnp.zeros_like(params["params"]["mu"]["kernel"]))
            params = {**params, "params": {**params["params"], "mu": mu}}
        return params, N.normalizer_init(self.layout.frame_size), None

    @staticmethod
    def actor_params(params, obs_norm) -> dict:
        """The acting parameters ({"policy", "obs_norm"[, "frozen"]}, as exported) out of the training ones."""
        out = {"policy": params["policy"], "obs_norm": obs_norm}
        if "frozen" in params:
            out["frozen"] = params["frozen"]
        return out

    def value(self, params, obs_norm, obs, privileged):
        frames, goal = self.layout.split(obs)
        return self.critic.apply(params, N.normalize(obs_norm, frames), jnp.concatenate([goal, privileged], -1))

    def rollout(self, env, ts: TrainState, key, placement: Placement | None = None):
        """`horizon` steps of every env; over several devices (`placement`), each device steps its own envs."""
        act = act_fn(self.spec, deterministic=False)
        actor = self.actor_params(ts.params, ts.obs_norm)
        step = jax.vmap(env.step) if placement is None else placement.each(jax.vmap(env.step))

        def one(env_state, k):
            action, logp, _ = act(actor, env_state.obs, k)
            nxt = step(env_state, action)
            out = dict(obs=env_state.obs, privileged=env_state.privileged, action=action, logp=logp,
                       reward=nxt.reward, done=nxt.done, terminated=nxt.terminated,
                       link_hist=nxt.body.link_hist, note_end=nxt.info["note_end"], nonfinite=nxt.info["nonfinite"],
                       **{f"score_{h}": nxt.info[h] for h in ("left", "right", "both")})
            if self.config.teacher_weight:
                out["teacher"] = nxt.info["teacher"]          # the label of the state the action was taken in
            return nxt, out
        return jax.lax.scan(one, ts.env, jax.random.split(key, self.config.horizon))

    def disc_inputs(self, link_hist):
        """(..., 3, hands, 16, 7) -> {name: (..., 3, F)} (the first hand is the one being imitated)."""
        return {n: IM.features(link_hist[..., 0, :, :], d.links, d.parent) for n, d in self.disc_specs.items()}

    def update_discriminators(self, ts: TrainState, traj, data: Data, key):
        cfg = self.config
        if not self.disc_specs:
            return ts.params["disc"], ts.opt["disc"], ts.disc_norm, ts.buffers, {}, []
        fake_all = self.disc_inputs(traj["link_hist"])          # (T, E, 3, F)
        half = cfg.disc_batch // 2
        k_ins, k_steps, key = jax.random.split(key, 3)
        norms, buffers, rewards = {}, {}, []

        def reference(k, n, name):
            return IM.sample_reference(k, data.reference[name], data.reference_frames, n)
        for i, name in enumerate(self.disc_specs):
            k_ref, k_pick = jax.random.split(jax.random.fold_in(k_ins, i))
            fake = fake_all[name].reshape((-1,) + fake_all[name].shape[-2:])
            norms[name] = N.normalizer_update(N.normalizer_update(ts.disc_norm[name], fake),
                                              reference(k_ref, fake.shape[0] // 4 + 1, name))
            pick = jax.random.permutation(k_pick, fake.shape[0])[:cfg.disc_buffer // 4]
            buffers[name] = IM.buffer_add(ts.buffers[name], fake[pick])

        def loss_fn(p, k):
            total, log = 0.0, {}
            for name in self.disc_specs:
                k1, k2, k3, k = jax.random.split(k, 4)
                fake = N.normalize(norms[name], IM.buffer_sample(k1, buffers[name], half), clip=1e9)
                real = N.normalize(norms[name], reference(k2, half, name), clip=1e9)
                loss, log_n = IM.hinge_loss(lambda pp, x: self.disc.apply(pp, x), p[name], real, fake, k3,
                                            cfg.gp_weight)
                total = total + loss
                log.update({f"{name}/{key_}": v for key_, v in log_n.items()})
            return total, log

        def step(carry, k):
            p, o = carry
            (_, log), grads = jax.value_and_grad(loss_fn, has_aux=True)(p, k)
            updates, o2 = self.optimizers["disc"].update(grads, o, p)
            ok = finite(grads)
            p, o = jax.tree.map(lambda new, old: jnp.where(ok, new, old), (optax.apply_updates(p, updates), o2),
                                (p, o))
            return (p, o), dict(log, skipped=1.0 - ok.astype(jnp.float32))
        (params, opt), log = jax.lax.scan(step, (ts.params["disc"], ts.opt["disc"]),
                                          jax.random.split(k_steps, cfg.disc_steps))
        skipped = jnp.sum(log.pop("skipped"))
        logs = dict(jax.tree.map(jnp.mean, log), **{"nonfinite/disc_updates": skipped})
        for name in self.disc_specs:
            x = N.normalize(norms[name], fake_all[name], clip=1e9)
            rewards.append(N.disc_reward(self.disc.apply(params[name], x)))
        return params, opt, norms, buffers, logs, rewards

    def ppo_update(self, ts: TrainState, batch, key, split=None):
        """PPO epochs over `batch`. `split`: the sharding that spreads a minibatch's samples over the devices. A
        minibatch gathered by a random permutation is otherwise whole on every device, and each device computed the
        whole minibatch's gradient: on 4 H100s an iteration grew as if each did the update of all 4
        (docs/benchmarks.md, "Several GPUs")."""
        cfg = self.config
        n = batch["obs"].shape[0]
        n_mb = max(n // cfg.minibatch, 1)
        obs_norm, frozen = ts.obs_norm, ts.params.get("frozen")
        teacher_weight = cfg.teacher_weight * (
            jnp.clip(1.0 - ts.iteration / cfg.teacher_fade, 0.0, 1.0) if cfg.teacher_fade else 1.0)

        def loss_fn(params, mb):
            actor = self.actor_params(dict(params, **({"frozen": frozen} if frozen is not None else {})), obs_norm)
            mu, log_std = distribution(self.spec, actor, mb["obs"])
            logp = N.gaussian_log_prob(mu, log_std, mb["action"])
            pl, clipped = ppo.policy_loss(logp, mb["logp"], mb["adv"], cfg.clip)
            v = self.value(params["critic"], obs_norm, mb["obs"], mb["privileged"])
            vl = jnp.mean(jnp.sum((v - mb["target"]) ** 2, -1)) / v.shape[-1]
            log = {"policy_loss": pl, "value_loss": vl, "clip_frac": clipped, "kl": ppo.approx_kl(logp, mb["logp"]),
                   "std": jnp.mean(jnp.exp(log_std))}
            loss = pl + cfg.value_coef * vl
            if cfg.prior_kl:
                log["prior_kl"] = ppo.prior_kl(mu, log_std)
                loss = loss + cfg.prior_kl * log["prior_kl"]
            if cfg.teacher_weight:
                log["teacher_nll"] = -jnp.mean(N.gaussian_log_prob(mu, log_std, mb["teacher"])) / mu.shape[-1]
                log["teacher_rms"] = jnp.sqrt(jnp.mean((mu - mb["teacher"]) ** 2))
                loss = loss + teacher_weight * log["teacher_nll"]
            return loss, log

        def epoch(carry, k):
            perm = jax.random.permutation(k, n)[: n_mb * cfg.minibatch].reshape(n_mb, cfg.minibatch)

            def minibatch(carry, idx):
                params, opt = carry
                mb = jax.tree.map(lambda x: x[idx], batch)
                if split is not None:
                    mb = jax.lax.with_sharding_constraint(mb, split)
                (_, log), grads = jax.value_and_grad(loss_fn, has_aux=True)(params, mb)
                new_params, new_opt = dict(params), dict(opt)
                for name in ("policy", "critic"):
                    updates, new_opt[name] = self.optimizers[name].update(grads[name], opt[name], params[name])
                    if name == "policy" and cfg.kl_target:
                        # the KL of this minibatch before its step sets the step's rate. In a warm-up the step is 0
                        # and the rate stays as it is: the KL of a still actor is 0, and adapting to it would climb
                        # to the upper bound and throw the first real step far (a KL of 52,000).
                        warm = ts.iteration < cfg.actor_warmup
                        new_opt["lr"] = jnp.where(warm, opt["lr"], adapt_lr(opt["lr"], log["kl"], cfg.kl_target))
                        rate = jnp.where(warm, 0.0, new_opt["lr"])
                        updates = jax.tree.map(lambda u: rate * u, updates)
                        log = dict(log, actor_lr=new_opt["lr"])
                    new_params[name] = optax.apply_updates(params[name], updates)
                ok = finite(grads)
                carry = jax.tree.map(lambda new, old: jnp.where(ok, new, old), (new_params, new_opt),
                                     (params, opt))
                return carry, dict(log, skipped=1.0 - ok.astype(jnp.float32))
            return jax.lax.scan(minibatch, carry, perm)

        params = {"policy": ts.params["policy"], "critic": ts.params["critic"]}
        opt = {k: v for k, v in ts.opt.items() if k != "disc"}
        (params, opt), log = jax.lax.scan(epoch, (params, opt), jax.random.split(key, cfg.epochs))
        skipped = jnp.sum(log.pop("skipped"))
        return params, opt, dict(jax.tree.map(jnp.mean, log), **{"nonfinite/ppo_updates": skipped})

    # ------------------------------------------------------------------------------------------ iteration
    def iteration(self, ts: TrainState, data: Data, placement: Placement | None = None):
        """One iteration; over the devices of `placement` (default: one), which step their own envs and split each
        PPO minibatch: the rollout (`act`), the rewards and advantages (`judge`), PPO (`learn`)."""
        return self.learn(*self.judge(*self.act(ts, data, placement), data), placement)

    def act(self, ts: TrainState, data: Data, placement: Placement | None = None):
        """The rollout: (state with the envs moved on, trajectory (steps, envs, ...), the later stages' keys)."""
        k_roll, k_disc, k_ppo, key = jax.random.split(ts.key, 4)
        env_state, traj = self.rollout(self.env.bind(data.songs), ts, k_roll, placement)
        return ts.replace(env=env_state, key=key), traj, {"disc": k_disc, "ppo": k_ppo}

    def judge(self, ts: TrainState, traj, keys, data: Data):
        """The discriminators' update and rewards, per-column GAE with PopArt, the observation normalizer: (state,
        the PPO batch (steps, envs, ...), the keys, the rollout's metrics)."""
        cfg = self.config
        env_state = ts.env
        disc_params, disc_opt, disc_norm, buffers, disc_log, disc_rewards = self.update_discriminators(
            ts, traj, data, keys["disc"])
        rewards = traj["reward"]
        if disc_rewards:
            d = jnp.stack(disc_rewards, -1)
            d = jnp.where(traj["terminated"][..., None], self.env.config.terminate_reward, d)
            rewards = jnp.concatenate([rewards, d], -1)

        # values (normalized outputs -> returns scale) at every step and after the last one
        all_obs = jnp.concatenate([traj["obs"], env_state.obs[None]])
        all_priv = jnp.concatenate([traj["privileged"], env_state.privileged[None]])
        values = ppo.popart_denormalize(ts.popart, self.value(ts.params["critic"], ts.obs_norm, all_obs, all_priv))
        adv, returns = ppo.gae(rewards, values[:-1], values[1:], traj["terminated"], traj["done"], cfg.gamma,
                               cfg.lam)
        weighted = ppo.standardize_advantages(adv, self.weights)

        critic = ts.params["critic"]
        popart, kernel, bias = ppo.popart_update(ts.popart, returns, critic["params"]["value"]["kernel"],
                                                 critic["params"]["value"]["bias"])
        critic = {**critic, "params": {**critic["params"], "value": {"kernel": kernel, "bias": bias}}}
        frames, _ = self.layout.split(traj["obs"])
        obs_norm = N.normalizer_update(ts.obs_norm, frames)

        batch = {"obs": traj["obs"], "privileged": traj["privileged"], "action": traj["action"],
                 "logp": traj["logp"], "adv": weighted, "target": ppo.popart_normalize(popart, returns)}
        if cfg.teacher_weight:
            batch["teacher"] = traj["teacher"]

        metrics = {"reward/" + c: jnp.mean(rewards[..., i]) for i, c in enumerate(self.columns)}
        for h in self.env.roles + (("both",) if len(self.env.roles) == 2 else ()):
            score = traj[f"score_{h}"]       # [precision, recall, f1, tp, predicted, targets] at note ends
            counted = (traj["note_end"] & (score[..., 4] + score[..., 5] > 0)).astype(jnp.float32)
            metrics[f"f1/{h}"] = jnp.sum(score[..., 2] * counted)
            metrics[f"notes/{h}"] = jnp.sum(counted)
        metrics["episodes"] = jnp.sum(traj["done"].astype(jnp.float32))
        metrics["terminations"] = jnp.sum(traj["terminated"].astype(jnp.float32))
        metrics["nonfinite/env_steps"] = jnp.sum(traj["nonfinite"].astype(jnp.float32))
        metrics.update(disc_log)
        ts = ts.replace(params=dict(ts.params, critic=critic, disc=disc_params), opt=dict(ts.opt, disc=disc_opt),
                        obs_norm=obs_norm, disc_norm=disc_norm, popart=popart, buffers=buffers)
        return ts, batch, keys, metrics

    def learn(self, ts: TrainState, batch, keys, metrics, placement: Placement | None = None):
        """The PPO epochs over the batch's steps and envs as one axis: (the next iteration's state, the iteration's
        metrics)."""
        split = placement.split if placement is not None and placement.n > 1 else None
        batch = jax.tree.map(lambda x: x.reshape((-1,) + x.shape[2:]), batch)
        params, opt, ppo_log = self.ppo_update(ts, batch, keys["ppo"], split)
        new = ts.replace(params=dict(ts.params, policy=params["policy"], critic=params["critic"]),
                         opt=dict(opt, disc=ts.opt["disc"]), iteration=ts.iteration + 1)
        metrics = dict(metrics, **ppo_log)
        metrics["nonfinite/state"] = 1.0 - finite((new.params, new.opt, new.obs_norm, new.popart)).astype(
            jnp.float32)
        return new, metrics

    def make_train_chunk(self, n: int, placement: Placement | None = None) -> Stages:
        """The programs of n iterations (`learn.stages`: (state, data) -> (state, metrics summed over them)): the
        stages of an iteration each a program of its own, compiled at once, or with `TrainConfig.one_program` one
        program scanning the n iterations. The state is split over the devices of `placement` (default: every
        device) and comes back placed as it went in, a rollout's arrays split along their envs between the stages, so
        every call runs the same compiled programs."""
        placement = placement or Placement()
        state, data = placement.shardings(self.state_shapes), placement.replicated(self.data)
        steps, whole = placement.steps, placement.whole

        def stage(fn, arg, out):
            return jax.jit(fn, donate_argnums=0, in_shardings=(arg, data), out_shardings=out)
        if self.config.one_program:
            return Stages([stage(lambda ts, d: jax.lax.scan(lambda s, _: self.iteration(s, d, placement), ts, None,
                                                            length=n), state, (state, whole))], 1)
        return Stages([
            stage(lambda ts, d: self.act(ts, d, placement), state, (state, steps, whole)),
            stage(lambda x, d: self.judge(*x, d), (state, steps, whole), (state, steps, whole, whole)),
            stage(lambda x, d: self.learn(*x, placement), (state, steps, whole, whole), (state, whole)),
        ], n)
