"""Multi-objective PPO (paper Eq. 9, reference §8): per-column GAE, per-column standardized advantages weighted by
the objective weights, clipped surrogate, critic regression on PopArt-normalized returns."""
from __future__ import annotations

import jax
import jax.numpy as jnp


def gae(rewards, values, next_values, terminated, done, gamma: float, lam: float):
    """Per-column generalized advantage estimation over a rollout of T steps.

    rewards, values, next_values: (T, E, C); terminated, done: (T, E). A terminated transition has no future
    (V(s') = 0); any ended episode (terminated or timed out) stops the advantage recursion. Returns (advantages,
    returns), both (T, E, C)."""
    not_term = 1.0 - terminated[..., None].astype(rewards.dtype)
    not_done = 1.0 - done[..., None].astype(rewards.dtype)
    delta = rewards + gamma * not_term * next_values - values

    def backward(carry, x):
        d, nd = x
        adv = d + gamma * lam * nd * carry
        return adv, adv
    _, adv = jax.lax.scan(backward, jnp.zeros_like(delta[0]), (delta, not_done), reverse=True)
    return adv, adv + values


def standardize_advantages(adv, weights):
    """Each column standardized over the whole batch (unbiased std), then weighted: Eq. 9's w_k * A_k."""
    flat = adv.reshape(-1, adv.shape[-1])
    n = flat.shape[0]
    mean = jnp.mean(flat, 0)
    std = jnp.sqrt(jnp.sum((flat - mean) ** 2, 0) / max(n - 1, 1))
    return (adv - mean) / (std + 1e-8) * weights


def policy_loss(log_prob, old_log_prob, weighted_adv, clip: float):
    """Clipped surrogate summed over objectives: -mean_b sum_k min(A_k r, A_k clip(r))."""
    ratio = jnp.exp(log_prob - old_log_prob)[..., None]
    surrogate = jnp.minimum(weighted_adv * ratio, weighted_adv * jnp.clip(ratio, 1 - clip, 1 + clip))
    return -jnp.mean(jnp.sum(surrogate, axis=-1)), jnp.mean(jnp.abs(ratio - 1.0) > clip)


def approx_kl(log_prob, old_log_prob):
    """KL(old || new) estimated from the samples' log-ratios, r - 1 - log r (never negative, low variance)."""
    log_ratio = log_prob - old_log_prob
    return jnp.mean(jnp.expm1(log_ratio) - log_ratio)


def prior_kl(mu, log_std):
    """KL(N(mu, s) || N(0, s)) = sum mu^2 / 2 s^2, the std held: how far a residual's mean strays from its planner,
    in its own exploration stds. Where the advantages carry no signal (a hand that already plays the note) their
    noise walks the mean away; this pulls it back, so only corrections that pay for themselves stay."""
    return jnp.mean(jnp.sum(0.5 * (mu / jax.lax.stop_gradient(jnp.exp(log_std))) ** 2, -1))


# ------------------------------------------------------------------------------------------------ PopArt

def popart_init(columns: int):
    """Exponential moving statistics of the returns per column; identity until the first update."""
    return {"m": jnp.zeros(columns), "v": jnp.zeros(columns), "debias": jnp.float32(0.0)}


def popart_moments(stats):
    d = jnp.maximum(stats["debias"], 1e-5)
    mean = jnp.where(stats["debias"] > 0, stats["m"] / d, 0.0)
    var = jnp.where(stats["debias"] > 0, stats["v"] / d - mean ** 2, 1.0)
    return mean, jnp.sqrt(jnp.maximum(var, 1e-4))


def popart_update(stats, returns, kernel, bias, beta: float = 0.1):
    """Update the return statistics and rescale the critic's last layer so its de-normalized outputs are
    unchanged (Preserving Outputs Precisely): W <- W s_old / s_new, b <- (s_old b + m_old - m_new) / s_new."""
    flat = returns.reshape(-1, returns.shape[-1])
    old_mean, old_std = popart_moments(stats)
    new = {"m": (1 - beta) * stats["m"] + beta * jnp.mean(flat, 0),
           "v": (1 - beta) * stats["v"] + beta * jnp.mean(flat ** 2, 0),
           "debias": (1 - beta) * stats["debias"] + beta}
    new_mean, new_std = popart_moments(new)
    kernel = kernel * old_std / new_std
    bias = (old_std * bias + old_mean - new_mean) / new_std
    return new, kernel, bias


def popart_denormalize(stats, normalized):
    mean, std = popart_moments(stats)
    return normalized * std + mean


def popart_normalize(stats, values):
    mean, std = popart_moments(stats)
    return (values - mean) / std
