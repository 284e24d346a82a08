"""A trained policy: the one way to act, and its export.

A policy is a parameter pytree and a `PolicySpec`. The pytree is {"policy": network parameters, "obs_norm": the
observation normalizer}; a synchronizer's adds {"frozen": {"left": ..., "right": ...}}, the two single-hand policies
whose latents it shifts (paper Eq. 1-2). `act_fn(spec, deterministic)` is a pure function of (params, obs, key) used by
the trainer's rollout, evaluation, synchronization and play alike; it takes the parameters as an argument, so a
jitted caller compiles once for any weights. `make_act` binds parameters for a quick `act(obs)`.

An export is a directory with `policy.json` (the spec and provenance) and `params/` (orbax, network weights in
float16 to keep the repository and device transfers small; normalizer statistics stay float32). A synchronizer's
export names its two frozen policies by path, relative to the export when they were given as paths there.
"""
from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from dexguitar.envs.layout import ObsLayout
from dexguitar.errors import UserError
from dexguitar.learn import checkpoint as C
from dexguitar.learn import networks as N
from dexguitar.planner import PLANNER_VERSION, RIGHT_PLANNER_VERSION
from dexguitar.world.hands import N_DOF

KINDS = ("policy", "synchronizer")
STORE_DTYPE = jnp.float16          # network weights on disk; |w| << 65504 and 3 significant digits suffice to act


@dataclasses.dataclass(frozen=True)
class PolicySpec:
    """What acting needs besides the weights (hashable: a static argument of jitted functions)."""

    kind: str                 # "policy" (one hand) or "synchronizer" (two frozen hands, shifted)
    hand: str                 # "left", "right" or "duet"
    action_size: int
    layout: ObsLayout
    feedforward: bool = False     # the left hand's action is a residual on the planner's (`planner.plans`)
    scale: float = 1.0            # the left hand's network output times this (`networks.Policy.scale`)
    right_feedforward: bool = False   # the right hand's action is a residual on the right planner's

    def hand_spec(self, i: int) -> "PolicySpec":
        """The single-hand policy of hand i of a synchronizer."""
        role = self.layout.roles[i]
        left = role == "left"
        return PolicySpec("policy", role, self.action_size // self.layout.hands, self.layout.one_hand(i),
                          self.feedforward if left else False, self.scale if left else 1.0,
                          False if left else self.right_feedforward)

    def env_config(self, config):
        """`config` (an `EnvConfig`) as this policy must be played in: on the planners' feedforwards or not."""
        return dataclasses.replace(config, feedforward=self.feedforward, right_feedforward=self.right_feedforward)

    def to_meta(self) -> dict:
        meta = {"kind": self.kind, "hand": self.hand, "action_size": self.action_size,
                "layout": self.layout.to_dict(), "obs_size": self.layout.obs_size, "goal_size": self.layout.goal_size,
                "planner_at_run_time": bool(self.feedforward or self.right_feedforward)}
        if self.feedforward:            # the planner's version number: older releases read it
            meta["feedforward"] = PLANNER_VERSION
        if self.scale != 1.0:
            meta["scale"] = float(self.scale)
        if self.right_feedforward:
            meta["right_feedforward"] = RIGHT_PLANNER_VERSION
        return meta

    @classmethod
    def from_meta(cls, meta: dict) -> "PolicySpec":
        """The spec `policy.json` describes; a residual on a planner version this release does not have raises
        `OldPlanner`."""
        if "layout" in meta:
            layout = ObsLayout.from_dict(meta["layout"])
        else:                  # exports written before the layout was recorded: one or two hands of 2 frames
            roles = ("left", "right") if meta["hand"] == "duet" else (meta["hand"],)
            goal = meta["goal_size"] // len(roles)
            layout = ObsLayout(roles, 2, (meta["obs_size"] - meta["goal_size"]) // (2 * len(roles)), goal, 6)
        return cls(meta.get("kind", "policy"), meta["hand"], meta["action_size"], layout,
                   _on_planner(meta, "feedforward"), float(meta.get("scale", 1.0)),
                   _on_planner(meta, "right_feedforward"))


class OldPlanner(ValueError):
    """A policy trained as a residual on a planner version that this release no longer has."""


# `policy.json`'s keys of a residual on a planner, and the planner version number each holds
PLANNER_KEYS = {"feedforward": PLANNER_VERSION, "right_feedforward": RIGHT_PLANNER_VERSION}


def _on_planner(meta: dict, key: str) -> bool:
    """Is `policy.json`'s policy a residual on the planner (`key`: "feedforward", the left one, or
    "right_feedforward")? Its value is the planner's version number (`planner.PLANNER_VERSION`,
    `RIGHT_PLANNER_VERSION`), or absent, 0 or false for none; any other (true: the first residuals' version 1) is a
    planner this release does not have: `OldPlanner`."""
    value = meta.get(key, 0)
    if value is None or value is False or (type(value) is int and value == 0):
        return False
    if type(value) is int and value == PLANNER_KEYS[key]:
        return True
    raise OldPlanner(f"trained on a planner version this release no longer has ({json.dumps(key)}: "
                     f"{json.dumps(value)}); only the left planner of version {PLANNER_VERSION} and the right "
                     f"planner of version {RIGHT_PLANNER_VERSION} are kept, so use a newer export of this policy")


# ----------------------------------------------------------------------------------------------------- acting

def distribution(spec: PolicySpec, params: dict, obs):
    """(mean, log std) of the action on a batch of observations."""
    frames, goal = spec.layout.split(obs)
    if spec.kind == "policy":
        return N.Policy(spec.action_size, scale=spec.scale).apply(params["policy"],
                                                                  N.normalize(params["obs_norm"], frames), goal)
    shared = N.normalize(params["obs_norm"], frames)        # the synchronizer's encoders read its own normalizer
    dz = N.Synchronizer().apply(params["policy"], *spec.layout.hand_parts(shared, goal, 0),
                                *spec.layout.hand_parts(shared, goal, 1))
    out = []
    for i, role in enumerate(spec.layout.roles):
        frozen = params["frozen"][role]
        f, g = spec.layout.hand_parts(frames, goal, i)
        out.append(N.Policy(spec.action_size // 2, scale=spec.hand_spec(i).scale).apply(
            frozen["policy"], N.normalize(frozen["obs_norm"], f), g, dz[i]))
    return jnp.concatenate([out[0][0], out[1][0]], -1), jnp.concatenate([out[0][1], out[1][1]], -1)


def act_fn(spec: PolicySpec, deterministic: bool):
    """act(params, obs, key) -> (action, log-probability, mean). Deterministic: the mean action (key unused)."""
    def act(params, obs, key=None):
        mu, log_std = distribution(spec, params, obs)
        if deterministic:
            return mu, N.gaussian_log_prob(mu, log_std, mu), mu
        action = mu + jnp.exp(log_std) * jax.random.normal(key, mu.shape)
        return action, N.gaussian_log_prob(mu, log_std, action), mu
    return act


def make_act(params: dict, spec: PolicySpec | dict, deterministic: bool = True):
    """act(obs) -> action with these parameters (the mean action unless `deterministic` is False: then act(obs,
    key))."""
    spec = spec if isinstance(spec, PolicySpec) else PolicySpec.from_meta(spec)
    fn = act_fn(spec, deterministic)
    return lambda obs, key=None: fn(params, obs, key)[0]


def with_log_std(params, log_std: float):
    """The policy with its log-std head set to the constant `log_std` (zero kernel)."""
    net = params["policy"]["params"]
    head = {"kernel": jnp.zeros_like(net["log_std"]["kernel"]), "bias": jnp.full_like(net["log_std"]["bias"], log_std)}
    return {**params, "policy": {**params["policy"], "params": {**net, "log_std": head}}}


def unsynchronized(params: dict) -> dict:
    """A synchronizer's parameters with its output layer zeroed: the frozen pair exactly as it plays alone (the
    same program as the synchronized pair, so one compilation serves "before" and "after")."""
    layer = params["policy"]["params"]["dz"]
    dz = jax.tree.map(jnp.zeros_like, layer)
    return {**params, "policy": {**params["policy"], "params": {**params["policy"]["params"], "dz": dz}}}


def init_synchronizer(key, left: dict, right: dict, layout: ObsLayout):
    """(synchronizer parameters, its normalizer): random MLP with a zero last layer; encoders copied from the
    policies (Sec. 4); normalizer = both policies' statistics side by side, with a count of 1 so that it follows the
    duet's own statistics from the first update (as the authors do)."""
    f, g = jnp.zeros((layout.history, layout.frame)), jnp.zeros(layout.goal)
    params = N.Synchronizer().init(key, f, g, f, g)
    copy = lambda tree: jax.tree.map(lambda x: jnp.array(x, copy=True), tree)  # noqa: E731  (own buffers)
    inner = {**params["params"], "encoder_left": copy(left["policy"]["params"]["encoder"]),
             "encoder_right": copy(right["policy"]["params"]["encoder"])}
    norm = {"mean": jnp.concatenate([left["obs_norm"]["mean"], right["obs_norm"]["mean"]]),
            "var": jnp.concatenate([left["obs_norm"]["var"], right["obs_norm"]["var"]]),
            "count": jnp.float32(1.0)}
    return {**params, "params": inner}, norm


def template(spec: PolicySpec) -> dict:
    """A parameter pytree of the right structure and shapes (to restore into): zeros, shaped without running the
    networks' initializers (which take seconds on a CPU)."""
    return jax.tree.map(lambda s: np.zeros(s.shape, s.dtype), jax.eval_shape(lambda: _initial(spec)))


def _initial(spec: PolicySpec) -> dict:
    layout = spec.layout
    if spec.kind == "synchronizer":
        hand = _initial(spec.hand_spec(0))
        policy, norm = init_synchronizer(jax.random.PRNGKey(0), hand, hand, layout)
        return {"policy": policy, "obs_norm": norm}
    return {"policy": N.init_params(N.Policy(spec.action_size), jax.random.PRNGKey(0),
                                    (layout.history, layout.frame), (layout.goal,)),
            "obs_norm": N.normalizer_init(layout.frame)}


# ----------------------------------------------------------------------------------------------------- export

def export_dir(directory) -> Path:
    """An exported policy's directory: `directory` itself, or the `policy/` export of a run directory."""
    directory = Path(directory)
    if not (directory / "policy.json").exists() and (directory / "policy" / "policy.json").exists():
        return directory / "policy"
    return directory


def _stored(params: dict) -> dict:
    """Network weights in STORE_DTYPE; normalizers (counts reach 1e9) stay float32."""
    return {k: (v if k == "obs_norm" else jax.tree.map(lambda x: jnp.asarray(x, STORE_DTYPE), v))
            for k, v in params.items()}


def export(directory, params: dict, meta: dict, saver: C.Saver | None = None) -> None:
    """Write `params` ({"policy", "obs_norm"}, without the frozen policies) and `policy.json`; the weights in the
    background through `saver` (a training run's, for `directory / "params"`) if one is given."""
    directory = Path(directory).absolute()
    directory.mkdir(parents=True, exist_ok=True)
    own = _stored({"policy": params["policy"], "obs_norm": params["obs_norm"]})
    step = int(meta.get("iteration", 0))
    if saver is None:
        C.save(directory / "params", step, own, keep=1)
    else:
        saver.save(step, own)
    tmp = directory / "policy.json.tmp"
    tmp.write_text(json.dumps(meta, indent=2))
    os.replace(tmp, directory / "policy.json")


def source_path(export: Path, path) -> str:
    """How an export records a frozen policy's path: relative to the export when that is possible."""
    path = Path(path).absolute()
    try:
        return os.path.relpath(path, Path(export).absolute())
    except ValueError:          # another drive (Windows)
        return str(path)


def _resolve_source(export: Path, recorded: str) -> Path:
    """A recorded source path: relative to the export (as written now), else as given (older exports recorded the
    path relative to the directory `dexguitar sync` ran in)."""
    for candidate in (Path(export) / recorded, Path(recorded)):
        if (export_dir(candidate) / "policy.json").exists():
            return export_dir(candidate)
    raise UserError(f"{export}: the policy it synchronizes, {recorded}, is missing")


def read_meta(directory) -> dict:
    """`policy.json` of an exported policy or a run directory's export, checked to describe a policy; no weights
    read (what a command checks before it builds anything)."""
    meta_path = export_dir(directory).absolute() / "policy.json"
    if not meta_path.exists():
        raise UserError(f"{meta_path.parent}: not an exported policy or a run (no policy.json)")
    try:
        meta = json.loads(meta_path.read_text())
        PolicySpec.from_meta(meta)
    except OldPlanner as err:
        raise UserError(f"{meta_path}: {err}") from None
    except (ValueError, KeyError, TypeError) as err:
        raise UserError(f"{meta_path}: not a policy description ({err})") from None
    return meta


def load(directory):
    """(params, meta) of an exported policy or a run directory's export. A synchronizer's frozen policies are
    loaded into params["frozen"]. Weights come back as float32."""
    directory = export_dir(directory).absolute()
    meta = read_meta(directory)
    spec = PolicySpec.from_meta(meta)
    params = C.restore(directory / "params", template(spec))[0]
    params = jax.tree.map(lambda x: jnp.asarray(x, jnp.float32), params)
    if spec.kind == "synchronizer":
        params["frozen"] = {side: load(_resolve_source(directory, src["path"]))[0]
                            for side, src in meta["sources"].items()}
    return params, meta


def check_pair(left_meta: dict, right_meta: dict, layout: ObsLayout, where=("LEFT", "RIGHT")) -> None:
    """Refuse single-hand policies that cannot play their hand of a two-hand `layout`, naming them."""
    for i, (meta, name) in enumerate(((left_meta, where[0]), (right_meta, where[1]))):
        spec, want = PolicySpec.from_meta(meta), layout.roles[i]
        if spec.kind != "policy" or spec.hand != want:
            raise UserError(f"{name}: a {spec.kind} for the {spec.hand} hand, expected a policy for the {want} hand")
        if spec.action_size != N_DOF or spec.layout != layout.one_hand(i):
            raise UserError(f"{name}: action size {spec.action_size} and observation layout {spec.layout}, "
                            f"expected {N_DOF} and {layout.one_hand(i)}")


def load_pair(left_dir, right_dir):
    """((params, meta), (params, meta)) of two exported single-hand policies (or runs); meta["path"] is where each
    was found. `check_pair` says whether they fit a duet."""
    out = []
    for directory in (left_dir, right_dir):
        params, meta = load(directory)
        out.append((params, dict(meta, path=str(export_dir(directory)))))
    return tuple(out)
