"""Networks of the paper (Fig. S2, reference §7) in flax.linen.

Policy: a GRU(256) encodes the 2-frame pose history, a 2-layer MLP encodes the goal; their sum is the latent z that
the synchronizer shifts. Then MLP 1024-1024-512 (ReLU6) and a Gaussian head with a state-dependent log-std.
Critic: the same shape, one output per reward column (normalized by PopArt outside the network).
Discriminator: GRU(256) over 3 frames of link poses, MLP 256-128-32; its reward is the mean of clip(D, -1, 1).
Synchronizer (Sec. 4, reference §7.5): copies of both policies' encoders -> MLP 1024-1024 -> latent offsets.
"""
from __future__ import annotations

from typing import Sequence

import flax.linen as nn
import jax
import jax.numpy as jnp

LATENT = 256


def relu6(x):
    return jnp.clip(x, 0.0, 6.0)


class _Weights(nn.Module):
    """One gate's kernel (and bias) under the name and initializer `nn.GRUCell` gives it, so checkpoints match."""

    features: int
    kernel_init: nn.initializers.Initializer
    use_bias: bool = True

    @nn.compact
    def __call__(self, inputs: int):
        kernel = self.param("kernel", self.kernel_init, (inputs, self.features))
        bias = self.param("bias", nn.initializers.zeros, (self.features,)) if self.use_bias else None
        return kernel, bias


class GRU(nn.Module):
    """`nn.GRUCell` run over the frames from a zero state, with its six gate kernels joined into two matrices: the
    input's projection of every frame is one product, each later frame adds one product of the state, and the first
    frame none (its state is zero). The same function and parameters as the cell, with a sixth of its products, so
    the training program (the actor's, the critic's and the discriminators' GRUs, the last differentiated twice for
    the gradient penalty) compiles in fewer instructions (docs/benchmarks.md, "The training program's size")."""

    features: int = LATENT

    @nn.compact
    def __call__(self, frames):
        w = lambda name, init, bias=True: _Weights(self.features, init, bias, name=name)  # noqa: E731
        lecun, orth = nn.initializers.lecun_normal(), nn.initializers.orthogonal()
        gates_in = [w(n, lecun)(frames.shape[-1]) for n in ("ir", "iz", "in")]
        gates_h = [w(n, orth, n == "hn")(self.features) for n in ("hr", "hz", "hn")]
        x = frames @ jnp.concatenate([k for k, _ in gates_in], 1) + jnp.concatenate([b for _, b in gates_in])
        w_h, b_hn = jnp.concatenate([k for k, _ in gates_h], 1), gates_h[2][1]
        h = None
        for t in range(frames.shape[-2]):
            x_r, x_z, x_n = jnp.split(x[..., t, :], 3, axis=-1)
            if h is None:
                h_r = h_z = 0.0
                h_n = b_hn
            else:
                h_r, h_z, h_n = jnp.split(h @ w_h, 3, axis=-1)
                h_n = h_n + b_hn
            r, z = jax.nn.sigmoid(x_r + h_r), jax.nn.sigmoid(x_z + h_z)
            n = jnp.tanh(x_n + r * h_n)
            h = (1.0 - z) * n if h is None else (1.0 - z) * n + z * h
        return h


class Encoder(nn.Module):
    """(pose history (H, F), goal (G,)) -> latent z (256,): GRU over the frames + goal MLP, added."""

    @nn.compact
    def __call__(self, frames, goal):
        h = GRU(name="gru")(frames)
        g = nn.Dense(LATENT, name="goal1")(goal)
        g = nn.Dense(LATENT, name="goal2")(relu6(g))
        return h + g


class Trunk(nn.Module):
    """MLP 1024-1024-512 with ReLU6 between layers (the policy's last layer has none, the critic's has one)."""

    last_activation: bool = False

    @nn.compact
    def __call__(self, z):
        x = relu6(nn.Dense(1024, name="fc1")(z))
        x = relu6(nn.Dense(1024, name="fc2")(x))
        x = nn.Dense(512, name="fc3")(x)
        return relu6(x) if self.last_activation else x


class Policy(nn.Module):
    """Gaussian policy; `dz` (the synchronizer's offset) is added to the latent before the trunk.

    `scale` multiplies the action (mean and std): a residual on the planner needs corrections of thousandths of a
    half range, and Adam moves every weight by about its learning rate whatever the gradient, so a small output
    scale keeps the usual learning rates from jumping the hand around (`TrainConfig.action_scale`)."""

    action_size: int
    log_std_init: float = -2.3   # std 0.1 of a half-range action = the authors' e^-3 of a full-range action
    scale: float = 1.0

    def setup(self):
        self.encoder = Encoder()
        self.trunk = Trunk()
        self.mu = nn.Dense(self.action_size, kernel_init=nn.initializers.uniform(2e-3), name="mu")
        self.log_std = nn.Dense(self.action_size, kernel_init=nn.initializers.uniform(1e-4),
                                bias_init=nn.initializers.constant(self.log_std_init), name="log_std")

    def latent(self, frames, goal):
        return self.encoder(frames, goal)

    def head(self, z):
        x = self.trunk(z)
        log_std = jnp.clip(self.log_std(x), -10.0, 2.0)
        if self.scale == 1.0:
            return self.mu(x), log_std
        return self.scale * self.mu(x), log_std + jnp.log(self.scale)

    def __call__(self, frames, goal, dz=None):
        z = self.latent(frames, goal)
        if dz is not None:
            z = z + dz
        return self.head(z)


class Critic(nn.Module):
    """One value per reward column (multi-objective), small initial outputs."""

    columns: int

    @nn.compact
    def __call__(self, frames, goal):
        z = Encoder(name="encoder")(frames, goal)
        x = Trunk(last_activation=True, name="trunk")(z)
        return nn.Dense(self.columns, kernel_init=nn.initializers.uniform(1e-4), name="value")(x)


class Discriminator(nn.Module):
    """GRU(256) over the frames then MLP 256-128-32 (ReLU); 32 outputs, averaged after clipping into a reward."""

    @nn.compact
    def __call__(self, frames):
        h = GRU(name="gru")(frames)
        orth = nn.initializers.orthogonal
        x = nn.relu(nn.Dense(256, kernel_init=orth(jnp.sqrt(2.0)), name="fc1")(h))
        x = nn.relu(nn.Dense(128, kernel_init=orth(jnp.sqrt(2.0)), name="fc2")(x))
        return nn.Dense(32, kernel_init=orth(1.0), name="fc3")(x)


class Synchronizer(nn.Module):
    """Eq. 2: trainable copies of both policies' encoders, concatenated, into an MLP whose last layer starts at zero.
    Its output (dz_left, dz_right) shifts the frozen policies' latents (Eq. 1); at initialization both are zero, so
    the frozen policies act exactly as they did alone."""

    hidden: Sequence[int] = (1024, 1024)

    @nn.compact
    def __call__(self, frames_left, goal_left, frames_right, goal_right):
        x = jnp.concatenate([Encoder(name="encoder_left")(frames_left, goal_left),
                             Encoder(name="encoder_right")(frames_right, goal_right)], axis=-1)
        for i, width in enumerate(self.hidden):
            x = nn.relu(nn.Dense(width, name=f"fc{i + 1}")(x))
        dz = nn.Dense(2 * LATENT, kernel_init=nn.initializers.zeros, bias_init=nn.initializers.zeros, name="dz")(x)
        return dz[..., :LATENT], dz[..., LATENT:]


def gaussian_log_prob(mu, log_std, action):
    """Sum over action dimensions of log N(action; mu, exp(log_std))."""
    z = (action - mu) * jnp.exp(-log_std)
    return jnp.sum(-0.5 * z ** 2 - log_std - 0.5 * jnp.log(2 * jnp.pi), axis=-1)


def disc_reward(logits):
    """Reward of a discriminator: mean over its 32 outputs of clip(D, -1, 1), in [-1, 1]."""
    return jnp.mean(jnp.clip(logits, -1.0, 1.0), axis=-1)


# --------------------------------------------------------------------------------------- running normalizer

def normalizer_init(size: int):
    return {"mean": jnp.zeros(size), "var": jnp.ones(size), "count": jnp.float32(1.0)}


def normalizer_update(stats, x):
    """Merge the mean/variance of a batch x (..., size) into the running statistics (parallel algorithm)."""
    x = x.reshape(-1, x.shape[-1])
    n = jnp.float32(x.shape[0])
    mean, var = jnp.mean(x, 0), jnp.var(x, 0)
    total = stats["count"] + n
    delta = mean - stats["mean"]
    new_mean = stats["mean"] + delta * n / total
    m2 = stats["var"] * stats["count"] + var * n + delta ** 2 * stats["count"] * n / total
    return {"mean": new_mean, "var": m2 / total, "count": total}


def normalize(stats, x, clip: float = 5.0):
    return jnp.clip((x - stats["mean"]) / jnp.sqrt(stats["var"] + 1e-5), -clip, clip)


def split_obs(obs, history: int, goal_size: int):
    """Actor observation -> (frames (..., history, F), goal (..., goal_size))."""
    state, goal = obs[..., :-goal_size], obs[..., -goal_size:]
    return state.reshape(state.shape[:-1] + (history, -1)), goal


def init_params(module: nn.Module, key, *shapes: Sequence[int]):
    return module.init(key, *[jnp.zeros(s) for s in shapes])


__all__ = ["Policy", "Critic", "Discriminator", "Encoder", "Synchronizer", "gaussian_log_prob", "disc_reward",
           "normalizer_init", "normalizer_update", "normalize", "split_obs", "init_params"]
