"""Training configurations, one module each: `CONFIG` (a `TrainConfig`) and optionally `ENV` (an `EnvConfig`).

`dexguitar train|sync --config NAME` (and `dexguitar songs --config-left|--config-right|--config-sync NAME`) picks
`dexguitar.configs.NAME`; a path to a .py file defining CONFIG (and optionally ENV) works too. `--set KEY=VALUE`
overrides a field of CONFIG, `--set env.KEY=VALUE` one of ENV (`load_config`).

  cpu_smoke              4 envs, 2 iterations: tests, notebooks' tiny mode, any CPU
  paper                  Table S1 of the paper (one V100: 512 envs), the `TrainConfig` defaults
  left_gpu, right_gpu    one hand on one GPU: 4,096 envs (`make train-left`, `make train-right`)
  sync_gpu               synchronization on one GPU: 4,096 duet envs
  sync_songs, sync_hold  synchronization in `dexguitar songs` (warm-up; sync_hold adds the both-hands hold reward:
                         the default of `make sync` and `dexguitar songs`)
  left_songs             the left hand on given songs as written, from scratch (one GPU)
  left_finetune          left_songs warm-started from another left hand (`dexguitar songs`' left stage)
  right_songs            the right hand on given songs' picking, warm-started (`dexguitar songs`' right stage)
  left_residual          the left hand as a residual on the IK planner (one GPU)
  left_general           the general left hand by PPO alone, the paper's recipe (about 8e8 samples)
  left_general_residual  left_residual on the general procedural material
  left_general_anchored  the general left hand held to the planner by a prior (`make train-left-general`)
  left_learned           the learned left hand: PPO with the planner's labels of its own states (DAgger)

Any other recipe is a .py file defining CONFIG (and optionally ENV), given as `--config PATH`.
"""
from __future__ import annotations

import dataclasses
import importlib
import os
import pkgutil
import runpy
import typing
from pathlib import Path

import numpy as np

from dexguitar import envs as E
from dexguitar.errors import UserError
from dexguitar.learn.run import TRAIN_DEFAULTS, planner_flags
from dexguitar.learn.trainer import TrainConfig


def names() -> list[str]:
    """The configs shipped in this package, sorted."""
    return sorted(m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_"))


def load(name: str):
    """The module `dexguitar.configs.<name>` (a KeyError for a name that is not one of `names()`)."""
    if name not in names():
        raise KeyError(name)
    return importlib.import_module(f"{__name__}.{name}")


def recorded_config(record: dict, sets=(), **overrides):
    """(TrainConfig, EnvConfig) as a run recorded them (its config.json, read), with `sets` applied as `load_config`
    does and TrainConfig fields overridden by name (None = keep): `--resume` without `--config` continues the run as
    it was made."""
    train = {k: v for k, v in record["train"].items() if k in TRAIN_DEFAULTS}
    env_fields = {f.name for f in dataclasses.fields(E.EnvConfig)}
    env = {k: tuple(v) if isinstance(v, list) else v for k, v in planner_flags(record["env"]).items()
           if k in env_fields}
    return _configured(TrainConfig(**train), E.EnvConfig(**env), sets, overrides, "the run's recorded config")


def _overridden(cfg: TrainConfig, overrides: dict) -> TrainConfig:
    """`cfg` with the fields named in `overrides` replaced (None = keep), checked (a UserError names a bad field)."""
    cfg = dataclasses.replace(cfg, **{k: v for k, v in overrides.items() if k in TRAIN_DEFAULTS and v is not None})
    try:
        cfg.check()
    except ValueError as err:
        raise UserError(str(err)) from None
    return cfg


def load_config(config: str | None, sets=(), **overrides):
    """(TrainConfig, EnvConfig or None) of `config`, a name in `dexguitar.configs` (`names()`: module
    `dexguitar.configs.<name>`) or a .py file, either defining CONFIG (and optionally ENV); None: the defaults (Table
    S1). Then `sets`, "KEY=VALUE" strings (`--set`): a TrainConfig field, or an EnvConfig one as "env.KEY" (from
    the config's ENV, else the env's defaults for the hand); then TrainConfig fields overridden by name (None = keep;
    a `--set` of the same field to another value is refused). The result is what the run records in its config.json,
    overrides included, and what --resume compares."""
    if not config:
        return _configured(TrainConfig(), None, sets, overrides, "the default config (TrainConfig())")
    if Path(config).is_file() or config.endswith(".py") or os.sep in config or "/" in config:
        if not Path(config).is_file():
            hint = (f"; the shipped configs are named now: --config {Path(config).stem}"
                    if Path(config).stem in names() else "")
            raise UserError(f"--config {config}: no such file{hint}")
        try:
            ns = runpy.run_path(config)
        except Exception as err:         # noqa: BLE001 - any error in the user's config file
            raise UserError(f"--config {config}: {type(err).__name__}: {err}") from None
    elif config in names():
        ns = vars(load(config))
    else:
        raise UserError(f"--config {config}: no such config; the configs are {', '.join(names())} "
                        "(dexguitar/configs/), or give a .py file defining CONFIG")
    if not isinstance(ns.get("CONFIG"), TrainConfig):
        raise UserError(f"--config {config}: defines no CONFIG = TrainConfig(...)")
    return _configured(ns["CONFIG"], ns.get("ENV"), sets, overrides, f"config {config}")


def _configured(cfg: TrainConfig, env, sets, overrides: dict, label: str):
    """(TrainConfig, EnvConfig or None): `cfg` and `env` with `sets` applied (`load_config`), then `overrides`."""
    train_sets, env_sets = {}, {}
    for item in sets or ():
        key, eq, text = item.partition("=")
        key = key.strip()
        if not eq or not key:
            raise UserError(f"--set {item}: expected KEY=VALUE (a TrainConfig field) or env.KEY=VALUE ({label})")
        cls, name, into = ((E.EnvConfig, key[4:], env_sets) if key.startswith("env.") else
                           (TrainConfig, key, train_sets))
        types = typing.get_type_hints(cls)
        if name not in types:
            fields = ", ".join(("env." if cls is E.EnvConfig else "") + f.name for f in dataclasses.fields(cls))
            raise UserError(f"--set {key}: {label} has no such field; {cls.__name__}'s are {fields}"
                            + ("" if cls is E.EnvConfig else " (and EnvConfig's as env.KEY)"))
        try:
            into[name] = parse_value(text.strip(), types[name])
        except ValueError as err:
            raise UserError(f"--set {key}={text}: {label}: {cls.__name__}.{name} {err}") from None
    for name, value in overrides.items():
        if value is not None and name in train_sets and train_sets[name] != value:
            raise UserError(f"--set {name}={train_sets[name]} disagrees with the command's own {name} {value} "
                            f"({label}): give one")
    try:
        cfg = _overridden(dataclasses.replace(cfg, **train_sets), overrides)
    except UserError as err:             # a --set made it: name the config
        raise (UserError(f"--set {' '.join(sets)}: {label}: {err}") if train_sets else err) from None
    if env_sets:
        if env is None:                  # what the trainers take for no ENV
            from dexguitar.learn.sync import SYNC_ENV
            env = SYNC_ENV if cfg.hand == "duet" else E.EnvConfig()
        env = dataclasses.replace(env, **env_sets)
    return cfg, env


def parse_value(text: str, kind):
    """`text` as a value of the type `kind` (int, float, bool, str, tuple[...] as "a,b", X | None as "none"); a
    ValueError says what was expected."""
    args = typing.get_args(kind)
    if type(None) in args:               # Optional[X]
        if text.lower() == "none":
            return None
        rest = [a for a in args if a is not type(None)]
        return parse_value(text, rest[0] if len(rest) == 1 else typing.Union[tuple(rest)])
    origin = typing.get_origin(kind)
    if origin is tuple:
        parts = [p.strip() for p in text.strip("()[] ").split(",") if p.strip()]
        items = [args[0]] * len(parts) if len(args) == 2 and args[1] is Ellipsis else list(args)
        if len(parts) != len(items):
            raise ValueError(f"is {len(items)} values separated by commas, not {text!r}")
        return tuple(parse_value(p, k) for p, k in zip(parts, items))
    if kind is bool:
        words = {"true": True, "1": True, "yes": True, "on": True, "false": False, "0": False, "no": False,
                 "off": False}
        if text.lower() not in words:
            raise ValueError(f"is true or false, not {text!r}")
        return words[text.lower()]
    if kind is int:
        try:
            return int(text)
        except ValueError:
            raise ValueError(f"is an integer, not {text!r}") from None
    if kind is float:
        try:
            value = float(text)
        except ValueError:
            raise ValueError(f"is a number, not {text!r}") from None
        if not np.isfinite(value):
            raise ValueError(f"is a finite number, not {text!r}")
        return value
    if kind is str:
        return text
    raise ValueError(f"has the type {kind}, which --set cannot give")
