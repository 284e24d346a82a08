"""Synchronization (paper Sec. 4 and 5.3, reference §7.5): the two single-hand policies are frozen and a synchronizer
shifts their latents so that the hands play in time.

    z_L = E_L(o_L) + dz_L,  z_R = E_R(o_R) + dz_R                     (Eq. 1)
    dz_L, dz_R = S(concat(E'_L(o_L), E'_R(o_R)))                      (Eq. 2)

E_L, E_R are the frozen policies' encoders; E'_L, E'_R trainable copies of them; the last layer of S starts at zero.
Only the synchronizer and a new critic with one column per reward (the left hand's 6 strings, the right hand's
picking, the left hand's 2 discriminators) learn, by the same multi-objective PPO, in the duet env with the
cooperative reward. The discriminators are reward models, trained from scratch against the left reference motion as
in single-hand training. Unlike the authors' code (which leaves the log-std heads trainable, reference §12, 9) every
parameter of both policies stays frozen, as the paper says.

The synchronizer's encoders read the duet frames through their own running normalizer, started from the two
policies' statistics; the frozen policies keep their own normalizers.
"""
from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from dexguitar import envs as E
from dexguitar.envs.core import HISTORY, LINK_FEATURES
from dexguitar.learn import networks as N
from dexguitar.learn.trainer import Trainer, TrainConfig
from dexguitar.world import hands as H

HAND_FRAME = 16 * LINK_FEATURES          # one hand's numbers in one history frame (208)
HAND_GOAL = 35                           # one hand's goal: 5 notes x (6 strings + timer)
# Reward weights (reference §5.3): the authors' two-hand weights [0.075 x 6, 0.5, 0.025 x 2] doubled (sum 2).
SYNC_WEIGHTS = (0.15,) * 6 + (1.0,) + (0.05, 0.05)
# Synchronization plays one target song as it is written: no fret shift, no tempo change; 20 s episodes (§3.7).
SYNC_ENV = E.EnvConfig(episode_frames=1200, shift_prob=0.0, tempo_prob=0.0)

_LEFT, _RIGHT, _SYNC = N.Policy(H.N_DOF), N.Policy(H.N_DOF), N.Synchronizer()


def split_duet(frames, goal):
    """Duet frames (..., HISTORY, 416) and goal (..., 70) -> ((left frames, left goal), (right frames, right goal))."""
    return ((frames[..., :HAND_FRAME], goal[..., :HAND_GOAL]),
            (frames[..., HAND_FRAME:], goal[..., HAND_GOAL:2 * HAND_GOAL]))


def distribution(params, obs, shift: bool = True):
    """(mean, log std) of both hands' actions (..., 54) on duet observations.

    params: {"policy": synchronizer, "obs_norm": its normalizer (416), "frozen": {"left"|"right": {"policy",
    "obs_norm"}}}. shift=False gives the frozen policies alone (before synchronization)."""
    frames, goal = N.split_obs(obs, HISTORY, 2 * HAND_GOAL)
    (fl, gl), (fr, gr) = split_duet(frames, goal)
    frozen = params["frozen"]
    dz_l = dz_r = None
    if shift:
        (sl, _), (sr, _) = split_duet(N.normalize(params["obs_norm"], frames), goal)
        dz_l, dz_r = _SYNC.apply(params["policy"], sl, gl, sr, gr)
    mu_l, ls_l = _LEFT.apply(frozen["left"]["policy"], N.normalize(frozen["left"]["obs_norm"], fl), gl, dz_l)
    mu_r, ls_r = _RIGHT.apply(frozen["right"]["policy"], N.normalize(frozen["right"]["obs_norm"], fr), gr, dz_r)
    return jnp.concatenate([mu_l, mu_r], -1), jnp.concatenate([ls_l, ls_r], -1)


def init_synchronizer(key, left: dict, right: dict):
    """(synchronizer parameters, its normalizer): random MLP with a zero last layer; encoders copied from the
    policies (Sec. 4); normalizer = both policies' statistics side by side, with a count of 1 so that it follows
    the duet's own statistics from the first update (as the authors do)."""
    f = jnp.zeros((HISTORY, HAND_FRAME))
    g = jnp.zeros(HAND_GOAL)
    params = _SYNC.init(key, f, g, f, g)
    inner = dict(params["params"])
    copy = lambda tree: jax.tree.map(lambda x: jnp.array(x, copy=True), tree)  # noqa: E731  (own buffers)
    inner["encoder_left"] = copy(left["policy"]["params"]["encoder"])
    inner["encoder_right"] = copy(right["policy"]["params"]["encoder"])
    norm = {"mean": jnp.concatenate([left["obs_norm"]["mean"], right["obs_norm"]["mean"]]),
            "var": jnp.concatenate([left["obs_norm"]["var"], right["obs_norm"]["var"]]),
            "count": jnp.float32(1.0)}
    return {**params, "params": inner}, norm


def check_pair(left_meta: dict, right_meta: dict, where=("LEFT", "RIGHT")) -> None:
    """Refuse policies of the wrong hand or size with a message that names them."""
    for meta, want, name in ((left_meta, "left", where[0]), (right_meta, "right", where[1])):
        if meta.get("hand") != want:
            raise ValueError(f"{name}: a policy for the {meta.get('hand')} hand, expected the {want} hand")
        if meta.get("action_size") != H.N_DOF or meta.get("goal_size") != HAND_GOAL:
            raise ValueError(f"{name}: action size {meta.get('action_size')} / goal size {meta.get('goal_size')}, "
                             f"expected {H.N_DOF} / {HAND_GOAL}")


class SyncTrainer(Trainer):
    """The single-hand trainer in the duet env, with the synchronizer as its policy and both hands' policies frozen.
    Everything else (rollout, discriminators, per-column GAE, PopArt, PPO, checkpoints) is shared."""

    def __init__(self, config: TrainConfig, songs, reference, left, right, env_config=None):
        """left, right: (params {"policy", "obs_norm"}, meta) of exported single-hand policies."""
        if config.hand != "duet":
            config = dataclasses.replace(config, hand="duet")
        check_pair(left[1], right[1])
        super().__init__(config, songs, reference, env_config or SYNC_ENV)
        self.frozen = {"left": left[0], "right": right[0]}
        self.sources = {"left": left[1], "right": right[1]}
        if len(self.columns) != len(SYNC_WEIGHTS):
            raise ValueError(f"synchronization expects columns {len(SYNC_WEIGHTS)}, got {self.columns}")
        self.weights = jnp.asarray(SYNC_WEIGHTS, jnp.float32)

    def init_policy(self, key):
        params, norm = init_synchronizer(key, self.frozen["left"], self.frozen["right"])
        # fresh buffers: the training chunk donates its state, which must not take the trainer's own copy with it
        return params, norm, jax.tree.map(lambda x: jnp.array(x, copy=True), self.frozen)

    def distribution(self, params, frozen, obs_norm, obs):
        return distribution({"policy": params, "obs_norm": obs_norm, "frozen": frozen}, obs)


def load_pair(left_dir, right_dir):
    """((params, meta), (params, meta)) of two exported single-hand policies (or run directories), checked."""
    from dexguitar.learn import checkpoint as C
    out = []
    for directory in (left_dir, right_dir):
        directory = C.export_dir(directory)
        params, meta = C.load_policy(directory)
        out.append((params, dict(meta, path=str(directory))))
    check_pair(out[0][1], out[1][1], where=(str(left_dir), str(right_dir)))
    return tuple(out)


def players(params):
    """(before, after): mean-action players over duet observations without and with the synchronizer."""
    return (lambda obs: distribution(params, obs, shift=False)[0],
            lambda obs: distribution(params, obs, shift=True)[0])


__all__ = ["SyncTrainer", "SYNC_ENV", "SYNC_WEIGHTS", "distribution", "init_synchronizer", "players", "check_pair",
           "load_pair"]
