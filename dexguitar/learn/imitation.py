"""GAN-like motion imitation (ICCGAN, reference §7.4): discriminators on 3 frames of link poses, hinge loss with a
gradient penalty, half simulated and half reference samples, a replay buffer of simulated samples.

The left hand has a composite pair of discriminators (wrist + thumb relative to the guitar; the four fingers relative
to the wrist), so the fingers are free of the wrist's pose; the right hand has one for the whole hand. Synchronization
keeps the left hand's two (the left hand is the first of the duet's hands)."""
from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from dexguitar.world.geometry import positive_w, quat_conj, quat_mul, quat_to_mat

FRAMES = 3
LINK_POSE = 7                  # position 3 + quaternion 4 per link


class Disc(NamedTuple):
    """One discriminator: which key links it sees (indices into hands.KEY_LINKS), relative to what ("guitar": as
    observed; "wrist": in the wrist's frame), and the PPO weight of its reward column (Eq. 9)."""

    links: tuple[int, ...]
    parent: str
    weight: float

    @property
    def features(self) -> int:
        return len(self.links) * LINK_POSE


# Reference §8: left 0.05 per discriminator, right 0.5; synchronization keeps only the left hand's two, with the
# authors' two-hand weight 0.025 doubled like the others (Sec. 5.3).
DISCRIMINATORS = {
    "left": {"wrist": Disc(tuple(range(4)), "guitar", 0.05), "fingers": Disc(tuple(range(4, 16)), "wrist", 0.05)},
    "right": {"hand": Disc(tuple(range(16)), "guitar", 0.5)},
    "duet": {"wrist": Disc(tuple(range(4)), "guitar", 0.05), "fingers": Disc(tuple(range(4, 16)), "wrist", 0.05)},
}


def features(link_hist, links, parent):
    """(..., 3, 16, 7) link pose history -> (..., 3, len(links) * 7) discriminator input."""
    sel = link_hist[..., jnp.asarray(links), :]
    if parent == "wrist":
        wrist = link_hist[..., 0:1, :]
        rot = quat_to_mat(wrist[..., 3:])                                  # (..., 1, 3, 3)
        pos = jnp.einsum("...ij,...i->...j", rot, sel[..., :3] - wrist[..., :3])
        quat = positive_w(quat_mul(quat_conj(wrist[..., 3:]), sel[..., 3:]))
        sel = jnp.concatenate([pos, quat], axis=-1)
    return sel.reshape(sel.shape[:-2] + (-1,))


def hinge_loss(apply, params, real, fake, key, gp_weight: float = 10.0):
    """mean ReLU(1 - D(real)) + mean ReLU(1 + D(fake)) + gp_weight * (|grad D(x_hat)| - 1)^2.

    Real, fake and their mixtures x_hat go through the network as one batch, and one backward pass of it gives the
    penalty's input gradient (zero cotangents on the real and fake rows): the loss's own gradient then differentiates
    one network twice instead of three networks and a fourth's gradient, a smaller training program."""
    n = real.shape[0]
    alpha = jax.random.uniform(key, (n,) + (1,) * (real.ndim - 1))
    mixed = alpha * real + (1 - alpha) * fake
    out, vjp = jax.vjp(lambda x: apply(params, x), jnp.concatenate([real, fake, mixed]))
    d_real, d_fake = out[:n], out[n:2 * n]
    (grad,) = vjp(jnp.concatenate([jnp.zeros_like(out[:2 * n]), jnp.ones_like(out[2 * n:])]))
    loss = jnp.mean(jax.nn.relu(1.0 - d_real)) + jnp.mean(jax.nn.relu(1.0 + d_fake))
    norm = jnp.sqrt(jnp.sum(grad[2 * n:].reshape(n, -1) ** 2, axis=-1) + 1e-12)
    gp = jnp.mean((norm - 1.0) ** 2)
    return loss + gp_weight * gp, {"disc_loss": loss, "grad_penalty": gp, "d_real": jnp.mean(d_real),
                                   "d_fake": jnp.mean(d_fake)}


def sample_reference(key, frames, length, n: int):
    """n windows of FRAMES consecutive control frames from the first `length` frames of a reference (T, ...)."""
    start = jax.random.randint(key, (n,), 0, jnp.maximum(length - FRAMES + 1, 1))
    return frames[start[:, None] + jnp.arange(FRAMES)[None, :]]


def buffer_init(size: int, shape):
    return {"data": jnp.zeros((size,) + tuple(shape)), "filled": jnp.int32(0), "head": jnp.int32(0)}


def buffer_add(buf, samples):
    """Ring buffer insert of n samples (n <= size)."""
    size, n = buf["data"].shape[0], samples.shape[0]
    idx = (buf["head"] + jnp.arange(n)) % size
    return {"data": buf["data"].at[idx].set(samples), "filled": jnp.minimum(buf["filled"] + n, size),
            "head": (buf["head"] + n) % size}


def buffer_sample(key, buf, n: int):
    idx = jax.random.randint(key, (n,), 0, jnp.maximum(buf["filled"], 1))
    return buf["data"][idx]
