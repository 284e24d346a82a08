"""Synchronization (paper Sec. 4 and 5.3, reference §7.5): the two single-hand policies are frozen and a synchronizer
shifts their latents so that the hands play in time.

    z_L = E_L(o_L) + dz_L,  z_R = E_R(o_R) + dz_R                     (Eq. 1)
    dz_L, dz_R = S(concat(E'_L(o_L), E'_R(o_R)))                      (Eq. 2)

E_L, E_R are the frozen policies' encoders; E'_L, E'_R trainable copies of them; the last layer of S starts at zero.
Only the synchronizer and a new critic with one column per reward (the left hand's 6 strings, the right hand's
picking, the left hand's 2 discriminators; weights beside the duet env's columns and in `imitation`) learn, by the
same multi-objective PPO, in the duet env with the cooperative reward. The discriminators are reward models, trained
from scratch against the left reference motion as in single-hand training. Unlike the authors' code (which leaves
the log-std heads trainable, reference §12, 9) every parameter of both policies stays frozen, as the paper says.

The synchronizer's encoders read the duet frames through their own running normalizer, started from the two
policies' statistics; the frozen policies keep their own normalizers. Acting goes through `policy.distribution`.
"""
from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from dexguitar import envs as E
from dexguitar.learn.policy import PolicySpec, check_pair, init_synchronizer
from dexguitar.learn.trainer import Trainer, TrainConfig

# Synchronization plays the target songs as they are written: no fret shift, no tempo change; 20 s episodes (§3.7).
SYNC_ENV = E.EnvConfig(episode_frames=1200, shift_prob=0.0, tempo_prob=0.0)


class SyncTrainer(Trainer):
    """The single-hand trainer in the duet env, with the synchronizer as its policy and both hands' policies frozen.
    Everything else (rollout, discriminators, per-column GAE, PopArt, PPO, checkpoints) is shared."""

    def __init__(self, config: TrainConfig, songs, reference, left, right, env_config=None,
                 devices: int | None = None):
        """left, right: (params {"policy", "obs_norm"}, meta) of exported single-hand policies."""
        if config.hand != "duet":
            config = dataclasses.replace(config, hand="duet")
        self.left_spec = PolicySpec.from_meta(left[1])                                 # read by make_spec
        env_config = dataclasses.replace(env_config or SYNC_ENV, feedforward=self.left_spec.feedforward,
                                         right_feedforward=PolicySpec.from_meta(right[1]).right_feedforward)
        super().__init__(config, songs, reference, env_config, devices)
        check_pair(left[1], right[1], self.layout, where=(left[1].get("path", "LEFT"), right[1].get("path",
                                                                                                    "RIGHT")))
        self.frozen = {"left": left[0], "right": right[0]}
        self.sources = {"left": left[1], "right": right[1]}

    def make_spec(self) -> PolicySpec:
        return PolicySpec("synchronizer", "duet", self.env.action_size, self.layout,
                          bool(self.env.config.feedforward), self.left_spec.scale,
                          bool(self.env.config.right_feedforward))

    def init_inputs(self) -> dict:
        return dict(super().init_inputs(), frozen=self.frozen)   # arguments of `init`: one program for any pair

    def init_policy(self, key, inputs: dict | None = None):
        frozen = (inputs or {}).get("frozen", self.frozen)
        params, norm = init_synchronizer(key, frozen["left"], frozen["right"], self.layout)
        # fresh buffers: the training chunk donates its state, which must not take the trainer's own copy with it
        return params, norm, jax.tree.map(lambda x: jnp.array(x, copy=True), frozen)


__all__ = ["SyncTrainer", "SYNC_ENV"]
