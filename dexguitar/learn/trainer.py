"""One hand at a time: PPO + GAN-like imitation as one jitted training iteration, scanned over many iterations.

An iteration = rollout (`lax.scan` over the vmapped env and policy) -> discriminator update -> discriminator
rewards -> per-column GAE with PopArt -> observation normalizer update -> PPO epochs over minibatches. Everything,
env states included, lives in one `TrainState` pytree, so a checkpoint holds the whole run and a resumed run
continues with exactly the iteration it would have run next.
"""
from __future__ import annotations

import dataclasses
from typing import Any

import jax
import jax.numpy as jnp
import optax
from flax import struct

from dexguitar import envs as E
from dexguitar.envs.core import HISTORY
from dexguitar.learn import imitation as IM
from dexguitar.learn import networks as N
from dexguitar.learn import ppo as P


@dataclasses.dataclass(frozen=True)
class TrainConfig:
    """Defaults reproduce Table S1 of the paper (one V100: 512 envs); experiments/ holds the GPU-sized configs."""

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
    goal_weight: float = -1.0         # per goal column; -1 = the paper's (left 0.15 x 6, right 0.5)
    disc_weight: float = -1.0         # per discriminator column; -1 = the paper's (left 0.05 x 2, right 0.5)
    iterations: int = 100_000         # ~4e8 samples at 4096 per iteration
    iterations_per_call: int = 50     # scanned on the device between host updates
    seed: int = 42

    @property
    def batch(self) -> int:
        return self.num_envs * self.horizon

    def weights(self, env_columns: int, disc_columns: int):
        goal = self.goal_weight if self.goal_weight >= 0 else (0.15 if env_columns > 1 else 0.5)
        disc = self.disc_weight if self.disc_weight >= 0 else (0.05 if env_columns > 1 else 0.5)
        return jnp.asarray([goal] * env_columns + [disc] * disc_columns, jnp.float32)


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


class Trainer:
    """Builds the networks and the jitted iteration for one hand over a song batch and reference motions."""

    def __init__(self, config: TrainConfig, songs, reference: jnp.ndarray | None, env_config=None):
        """reference: (T, 16, 7) link poses of the reference motion at 60 Hz (see `dexguitar.motion`)."""
        self.config = config
        self.env = E.make(config.hand, songs, env_config)
        self.disc_specs = IM.DISCRIMINATORS[config.hand] if reference is not None else {}
        self.reference = None if reference is None else jnp.asarray(reference, jnp.float32)
        self.env_columns = len(self.env.reward_columns)
        self.columns = tuple(self.env.reward_columns) + tuple(f"disc_{n}" for n in self.disc_specs)
        self.weights = config.weights(self.env_columns, len(self.disc_specs))
        self.frame_size = (self.env.obs_size - self.env.goal_size) // HISTORY
        self.policy = N.Policy(self.env.action_size)
        self.critic = N.Critic(len(self.columns))
        self.disc = N.Discriminator()
        self.optimizers = {
            "policy": optax.chain(optax.clip_by_global_norm(config.grad_clip), optax.adam(config.actor_lr)),
            "critic": optax.chain(optax.clip_by_global_norm(config.grad_clip), optax.adam(config.critic_lr)),
            "disc": optax.adam(config.disc_lr),
        }

    # ------------------------------------------------------------------------------------------ init
    def init(self, key=None) -> TrainState:
        cfg = self.config
        key = jax.random.PRNGKey(cfg.seed) if key is None else key
        k_pol, k_crit, k_disc, k_env, key = jax.random.split(key, 5)
        frames = (HISTORY, self.frame_size)
        policy, obs_norm, frozen = self.init_policy(k_pol)
        params = {
            "policy": policy,
            "critic": N.init_params(self.critic, k_crit, frames, (self.env.goal_size + 6,)),
            "disc": {name: N.init_params(self.disc, k, (IM.FRAMES, len(links) * 7))
                     for (name, (links, _)), k in zip(self.disc_specs.items(),
                                                      jax.random.split(k_disc, max(len(self.disc_specs), 1)))},
        }
        if frozen is not None:
            params["frozen"] = frozen
        opt = {k: self.optimizers[k].init(params[k]) for k in self.optimizers}
        env_state = jax.jit(jax.vmap(self.env.reset))(jax.random.split(k_env, cfg.num_envs))
        return TrainState(
            params=params, opt=opt, obs_norm=obs_norm,
            disc_norm={n: N.normalizer_init(len(links) * 7) for n, (links, _) in self.disc_specs.items()},
            popart=P.popart_init(len(self.columns)),
            buffers={n: IM.buffer_init(cfg.disc_buffer, (IM.FRAMES, len(links) * 7))
                     for n, (links, _) in self.disc_specs.items()},
            env=env_state, key=key, iteration=jnp.int32(0))

    # ------------------------------------------------------------------------------------------ pieces
    def init_policy(self, key):
        """(trainable policy parameters, observation normalizer, frozen parameters or None)."""
        frames = (HISTORY, self.frame_size)
        return (N.init_params(self.policy, key, frames, (self.env.goal_size,)), N.normalizer_init(self.frame_size),
                None)

    def distribution(self, params, frozen, obs_norm, obs):
        """(mean, log std) of the action on a batch of actor observations."""
        frames, goal = N.split_obs(obs, HISTORY, self.env.goal_size)
        return self.policy.apply(params, N.normalize(obs_norm, frames), goal)

    def act(self, params, frozen, obs_norm, obs, key=None):
        """Policy on a batch of actor observations: (action, log_prob, mean). key None = the mean action."""
        mu, log_std = self.distribution(params, frozen, obs_norm, obs)
        if key is None:
            return mu, N.gaussian_log_prob(mu, log_std, mu), mu
        action = mu + jnp.exp(log_std) * jax.random.normal(key, mu.shape)
        return action, N.gaussian_log_prob(mu, log_std, action), mu

    def value(self, params, obs_norm, obs, privileged):
        frames, goal = N.split_obs(obs, HISTORY, self.env.goal_size)
        return self.critic.apply(params, N.normalize(obs_norm, frames), jnp.concatenate([goal, privileged], -1))

    def disc_inputs(self, link_hist):
        """(..., 3, hands, 16, 7) -> {name: (..., 3, F)} (the first hand is the one being trained)."""
        return {n: IM.features(link_hist[..., 0, :, :], links, parent)
                for n, (links, parent) in self.disc_specs.items()}

    def rollout(self, ts: TrainState, key):
        def one(carry, k):
            env_state = carry
            action, logp, _ = self.act(ts.params["policy"], ts.params.get("frozen"), ts.obs_norm, env_state.obs, k)
            nxt = jax.vmap(self.env.step)(env_state, action)
            out = dict(obs=env_state.obs, privileged=env_state.privileged, action=action, logp=logp,
                       reward=nxt.reward, done=nxt.done, terminated=nxt.terminated,
                       link_hist=nxt.link_hist, note_end=nxt.info["note_end"],
                       **{f"score_{h}": nxt.info[h] for h in ("left", "right", "both")})
            return nxt, out
        env_state, traj = jax.lax.scan(one, ts.env, jax.random.split(key, self.config.horizon))
        return env_state, traj

    def update_discriminators(self, ts: TrainState, traj, key):
        cfg = self.config
        if not self.disc_specs:
            return ts.params["disc"], ts.opt["disc"], ts.disc_norm, ts.buffers, {}, []
        fake_all = self.disc_inputs(traj["link_hist"])          # (T, E, 3, F)
        half = cfg.disc_batch // 2
        k_ins, k_steps, key = jax.random.split(key, 3)
        params, opt, norms, buffers, rewards = dict(ts.params["disc"]), ts.opt["disc"], {}, {}, []
        for i, (name, (links, parent)) in enumerate(self.disc_specs.items()):
            k_ref, k_pick = jax.random.split(jax.random.fold_in(k_ins, i))
            fake = fake_all[name].reshape((-1,) + fake_all[name].shape[-2:])
            ref = IM.features(IM.sample_reference(k_ref, self.reference, fake.shape[0] // 4 + 1), links, parent)
            norms[name] = N.normalizer_update(N.normalizer_update(ts.disc_norm[name], fake), ref)
            pick = jax.random.permutation(k_pick, fake.shape[0])[:cfg.disc_buffer // 4]
            buffers[name] = IM.buffer_add(ts.buffers[name], fake[pick])

        def loss_fn(p, k):
            total, log = 0.0, {}
            for name, (links, parent) in self.disc_specs.items():
                k1, k2, k3, k = jax.random.split(k, 4)
                fake = N.normalize(norms[name], IM.buffer_sample(k1, buffers[name], half), clip=1e9)
                real = IM.features(IM.sample_reference(k2, self.reference, half), links, parent)
                real = N.normalize(norms[name], real, clip=1e9)
                loss, log_n = IM.hinge_loss(lambda pp, x: self.disc.apply(pp, x), p[name], real, fake, k3,
                                            cfg.gp_weight)
                total = total + loss
                log.update({f"{name}/{key_}": v for key_, v in log_n.items()})
            return total, log

        def step(carry, k):
            p, o = carry
            (_, log), grads = jax.value_and_grad(loss_fn, has_aux=True)(p, k)
            updates, o = self.optimizers["disc"].update(grads, o, p)
            return (optax.apply_updates(p, updates), o), log
        (params, opt), log = jax.lax.scan(step, (params, opt), jax.random.split(k_steps, cfg.disc_steps))
        logs = jax.tree.map(jnp.mean, log)
        for name in self.disc_specs:
            x = N.normalize(norms[name], fake_all[name], clip=1e9)
            rewards.append(N.disc_reward(self.disc.apply(params[name], x)))
        return params, opt, norms, buffers, logs, rewards

    def ppo_update(self, ts: TrainState, batch, key):
        cfg = self.config
        n = batch["obs"].shape[0]
        n_mb = max(n // cfg.minibatch, 1)
        ts_norm, frozen = ts.obs_norm, ts.params.get("frozen")

        def loss_fn(params, mb):
            frames, goal = N.split_obs(mb["obs"], HISTORY, self.env.goal_size)
            mu, log_std = self.distribution(params["policy"], frozen, ts_norm, mb["obs"])
            logp = N.gaussian_log_prob(mu, log_std, mb["action"])
            pl, clipped = P.policy_loss(logp, mb["logp"], mb["adv"], cfg.clip)
            v = self.critic.apply(params["critic"], N.normalize(ts_norm, frames),
                                  jnp.concatenate([goal, mb["privileged"]], -1))
            vl = jnp.mean(jnp.sum((v - mb["target"]) ** 2, -1)) / v.shape[-1]
            return pl + cfg.value_coef * vl, {"policy_loss": pl, "value_loss": vl, "clip_frac": clipped,
                                              "std": jnp.mean(jnp.exp(log_std))}

        def epoch(carry, k):
            params, opt = carry
            perm = jax.random.permutation(k, n)[: n_mb * cfg.minibatch].reshape(n_mb, cfg.minibatch)

            def minibatch(carry, idx):
                params, opt = carry
                mb = jax.tree.map(lambda x: x[idx], batch)
                (_, log), grads = jax.value_and_grad(loss_fn, has_aux=True)(params, mb)
                new_params, new_opt = dict(params), dict(opt)
                for name in ("policy", "critic"):
                    updates, new_opt[name] = self.optimizers[name].update(grads[name], opt[name], params[name])
                    new_params[name] = optax.apply_updates(params[name], updates)
                return (new_params, new_opt), log
            return jax.lax.scan(minibatch, (params, opt), perm)

        params = {"policy": ts.params["policy"], "critic": ts.params["critic"]}
        opt = {"policy": ts.opt["policy"], "critic": ts.opt["critic"]}
        (params, opt), log = jax.lax.scan(epoch, (params, opt), jax.random.split(key, cfg.epochs))
        return params, opt, jax.tree.map(jnp.mean, log)

    # ------------------------------------------------------------------------------------------ iteration
    def iteration(self, ts: TrainState, _=None):
        cfg = self.config
        k_roll, k_disc, k_ppo, key = jax.random.split(ts.key, 4)
        env_state, traj = self.rollout(ts, k_roll)

        disc_params, disc_opt, disc_norm, buffers, disc_log, disc_rewards = self.update_discriminators(
            ts, traj, k_disc)
        rewards = traj["reward"]
        if disc_rewards:
            d = jnp.stack(disc_rewards, -1)
            d = jnp.where(traj["terminated"][..., None], self.env.config.terminate_reward, d)
            rewards = jnp.concatenate([rewards, d], -1)

        # values (normalized outputs -> returns scale) at every step and after the last one
        all_obs = jnp.concatenate([traj["obs"], env_state.obs[None]])
        all_priv = jnp.concatenate([traj["privileged"], env_state.privileged[None]])
        values = P.popart_denormalize(ts.popart, self.value(ts.params["critic"], ts.obs_norm, all_obs, all_priv))
        adv, returns = P.gae(rewards, values[:-1], values[1:], traj["terminated"], traj["done"], cfg.gamma, cfg.lam)
        weighted = P.standardize_advantages(adv, self.weights)

        critic = ts.params["critic"]
        popart, kernel, bias = P.popart_update(ts.popart, returns, critic["params"]["value"]["kernel"],
                                               critic["params"]["value"]["bias"])
        critic = {**critic, "params": {**critic["params"], "value": {"kernel": kernel, "bias": bias}}}
        frames, _ = N.split_obs(traj["obs"], HISTORY, self.env.goal_size)
        obs_norm = N.normalizer_update(ts.obs_norm, frames)

        flat = lambda x: x.reshape((-1,) + x.shape[2:])  # noqa: E731
        batch = {"obs": flat(traj["obs"]), "privileged": flat(traj["privileged"]), "action": flat(traj["action"]),
                 "logp": flat(traj["logp"]), "adv": flat(weighted),
                 "target": flat(P.popart_normalize(popart, returns))}
        ts_mid = ts.replace(obs_norm=obs_norm, params=dict(ts.params, critic=critic))
        params, opt, ppo_log = self.ppo_update(ts_mid, batch, k_ppo)

        metrics = {"reward/" + c: jnp.mean(rewards[..., i]) for i, c in enumerate(self.columns)}
        for h in ("left", "right", "both"):
            score = traj[f"score_{h}"]       # [precision, recall, f1, tp, predicted, targets] at note ends
            counted = (traj["note_end"] & (score[..., 4] + score[..., 5] > 0)).astype(jnp.float32)
            metrics[f"f1/{h}"] = jnp.sum(score[..., 2] * counted)
            metrics[f"notes/{h}"] = jnp.sum(counted)
        metrics["episodes"] = jnp.sum(traj["done"].astype(jnp.float32))
        metrics["terminations"] = jnp.sum(traj["terminated"].astype(jnp.float32))
        metrics.update(ppo_log)
        metrics.update(disc_log)
        new = ts.replace(
            params=dict(ts.params, policy=params["policy"], critic=params["critic"], disc=disc_params),
            opt={"policy": opt["policy"], "critic": opt["critic"], "disc": disc_opt},
            obs_norm=obs_norm, disc_norm=disc_norm, popart=popart, buffers=buffers, env=env_state, key=key,
            iteration=ts.iteration + 1)
        return new, metrics

    def make_train_chunk(self, n: int):
        """A jitted function running n iterations in one `lax.scan`; metrics summed over the chunk (sums of F1
        and note counts, so the host can form the mean F1 per note)."""
        def chunk(ts):
            ts, metrics = jax.lax.scan(self.iteration, ts, None, length=n)
            return ts, jax.tree.map(lambda x: jnp.sum(x) if x.ndim else x, metrics)
        return jax.jit(chunk, donate_argnums=0)
