"""The one physics step of every env, benchmark and check: PD targets held for `SUBSTEPS` MJX steps (240 Hz physics
under 60 Hz control), and the matmul precision of everything an env computes.

MJX has two implementations of the same physics: JAX's (any device) and Warp's (NVIDIA GPUs, `pip install
'dexguitar[warp]'`). `EnvConfig.physics` picks one and `resolve` says which runs. Warp's Data keeps some buffers
outside the env batch, shared by every env and rewritten by every step (contacts, their count, sizes): a selection
between two states (`where`) takes those from one side, never `jnp.where`s them, and an env reads contacts only
through what both implementations provide (positions of bodies, sites and geoms)."""
from __future__ import annotations

import contextlib
import ctypes
import functools
import os
import sys

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from dexguitar import mjx as _quiet_mjx
from dexguitar.world.scene import SUBSTEPS

mjx = _quiet_mjx()
# imported by the line above already, without the line it prints when warp is absent
from mujoco.mjx import warp as _mjx_warp
from mujoco.mjx.warp.types import DATA_NON_VMAP

PHYSICS = ("auto", "jax", "warp")

# A GPU's default float32 matmul is TF32 (a 10-bit mantissa, relative error 2^-11): a point half a metre from the
# origin moves by a quarter of a millimetre, a fair part of a press's depth. On an H100 a zero-residual left hand
# played snow at F1 0.924 with TF32 and 0.990 in full float32, as on the CPU (turkish_march 0.974 and 0.993;
# docs/benchmarks.md, "Float32 in the env"). Networks keep the default: only the world needs it.
PRECISION = "highest"


def exact(fn):
    """`fn` traced with full float32 matmuls (a no-op on the CPU, whose float32 matmuls are exact already)."""
    @functools.wraps(fn)
    def wrapped(*args, **kwargs):
        with jax.default_matmul_precision(PRECISION):
            return fn(*args, **kwargs)
    return wrapped


@exact
def control_step(mjx_model, data, ctrl, substeps: int = SUBSTEPS):
    """Advance `data` by one control step with the actuators' targets set to `ctrl`."""
    data = data.replace(ctrl=ctrl)
    return jax.lax.fori_loop(0, substeps, lambda _, d: mjx.step(mjx_model, d), data)


# ------------------------------------------------------------------------------------------------ which physics

def warp_installed() -> bool:
    """Does `warp` import (as MJX imports it)?"""
    return bool(_mjx_warp.WARP_INSTALLED)


@functools.cache
def resolve(physics: str = "auto", *, installed: bool | None = None, platform: str | None = None) -> str:
    """"jax" or "warp": the implementation `physics` ("auto", "jax" or "warp") runs on here. "auto" is Warp where
    `warp` imports and JAX's default backend is a GPU, else JAX; "warp" where it cannot run is JAX, with one line on
    stderr saying why. `installed` and `platform` (JAX's default backend) stand in for this machine's. Cached: the
    line is printed once per process."""
    if physics not in PHYSICS:
        raise ValueError(f"physics {physics!r}: expected one of {', '.join(PHYSICS)}")
    if physics == "jax":
        return "jax"
    installed = warp_installed() if installed is None else installed
    platform = jax.default_backend() if platform is None else platform
    why = ("warp-lang is not installed (pip install 'dexguitar[warp]')" if not installed else
           f"no GPU (JAX runs on {platform})" if platform != "gpu" else None)
    if why is None:
        return "warp"
    if physics == "warp":
        print(f"warning: physics 'warp' runs as 'jax' here: {why}", file=sys.stderr, flush=True)
    return "jax"


@contextlib.contextmanager
def stdout_to_stderr():
    """Inside the block, whatever is written to stdout goes to stderr: Python's prints and what native code writes
    to file descriptor 1. Warp's kernels print their warnings ("solver iterations limit reached ...", the overflow
    warnings that `m.opt.warn_overflow` selects) with the GPU's printf, which the CUDA driver hands to C's buffered
    stdout when the host next waits on the GPU, not to Python's `sys.stdout`; a command whose stdout is one document
    (`eval --json`, `play --json`, `train`'s summary) computes inside this block and prints the document after it.
    The warnings stay readable on stderr rather than silenced: they say the solver ran out of iterations."""
    sys.stdout.flush()
    _flush_c_stdout()
    try:
        saved = os.dup(1)
    except OSError:                         # no file descriptor 1 at all
        saved = None
    if saved is not None:
        os.dup2(2, 1)
    real, sys.stdout = sys.stdout, sys.stderr
    try:
        yield
    finally:
        sys.stderr.flush()
        _flush_c_stdout()                   # what C's stdout still holds goes to stderr, before fd 1 is restored
        if saved is not None:
            os.dup2(saved, 1)
            os.close(saved)
        sys.stdout = real


def _flush_c_stdout() -> None:
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError, TypeError):    # no C library to reach (not Linux or macOS)
        pass


# ------------------------------------------------------------------------------------------------ model and data

def warp_sizes(model: mujoco.MjModel, envs: int) -> dict:
    """Warp's buffer sizes for `envs` envs stepped at once: contacts for all envs together (`naconmax`) and
    constraint rows per env (`njmax`), each the most the scene can have, as JAX's implementation allocates them
    (every candidate contact and every constraint row of those contacts and of the joint limits)."""
    data = mjx.make_data(model, impl="jax")
    return {"naconmax": int(data._impl.contact.dist.shape[0]) * max(envs, 1),
            "njmax": int(data._impl.efc_J.shape[0])}


def put(model: mujoco.MjModel, data: mujoco.MjData, physics: str, envs: int, device=None):
    """(mjx.Model, mjx.Data) of `physics` ("jax" or "warp", resolved) on `device`; Warp's buffers hold `envs` envs."""
    if physics != "warp":
        return mjx.put_model(model, impl=physics, device=device), mjx.put_data(model, data, impl=physics, device=device)
    wp = _mjx_warp.warp
    wp.config.log_level = wp.LOG_WARNING     # not Warp's greeting and kernel-load lines, which it prints to stdout
    mjx_model = mjx.put_model(model, impl=physics, device=device)
    # The solver's "iterations limit reached" lines are not printed: with the scenes' 4 iterations (JAX's behaviour
    # too, silently) they come every few steps, thousands a training chunk. How often the solver used them all is
    # what `bench env` measures (`solver_at_limit`). Buffer overflows are still printed.
    quiet = int(_mjx_warp.mjwp_types.OverflowType.ITERATIONS | _mjx_warp.mjwp_types.OverflowType.LS_ITERATIONS)
    opt = mjx_model.opt
    mjx_model = mjx_model.replace(opt=opt.replace(_impl=opt._impl.replace(
        warn_overflow=int(opt._impl.warn_overflow) & ~quiet)))
    return mjx_model, mjx.put_data(model, data, impl=physics, device=device, **warp_sizes(model, envs))


def shared(data) -> tuple:
    """Names of the fields of `data._impl` that Warp keeps outside the env batch (none under JAX), sorted: MJX keeps
    them in a set, whose order changes from process to process (string hashing), and a program that makes them in
    that order (`refill`) would be another program for JAX's persistent cache in every run."""
    return tuple(sorted(DATA_NON_VMAP)) if data.impl == mjx.Impl.WARP else ()


def fills(data) -> dict:
    """{name: (shape, dtype, value)} of Warp's shared buffers in `data` that hold one value throughout (empty
    contact slots, zero counts): `refill` makes them inside a traced program instead of capturing them, since JAX
    writes a captured array into the program, and Warp's contact buffer for thousands of envs is hundreds of MB."""
    out = {}
    for name in shared(data):
        x = getattr(data._impl, name)
        if isinstance(x, jax.Array) and x.size > 1:
            x = np.asarray(x)
            if np.all(x == x.reshape(-1)[0]):
                out[name] = (x.shape, x.dtype, x.reshape(-1)[0])
    return out


def refill(data, fills: dict):
    """`data` with the buffers `fills` describes made anew (`jnp.full`)."""
    if not fills:
        return data
    return data.replace(_impl=data._impl.replace(**{k: jnp.full(shape, value, dtype)
                                                     for k, (shape, dtype, value) in fills.items()}))


def where(cond, a, b):
    """`a` where `cond` else `b`, leaf by leaf, over pytrees that may hold `mjx.Data`; `cond` is a scalar or has
    the leading (batch) shape of the leaves. Warp's shared buffers (`shared`) come from `b` whole."""
    cond = jnp.asarray(cond)

    def pick(x, y):
        x, y = jnp.asarray(x), jnp.asarray(y)
        return jnp.where(cond.reshape(cond.shape + (1,) * (x.ndim - cond.ndim)), x, y)

    def node(x, y):
        if not isinstance(x, mjx.Data):
            return pick(x, y)
        names = shared(x)
        if not names:
            return jax.tree.map(pick, x, y)
        impl = x._impl.replace(**{f.name: getattr(y._impl, f.name) if f.name in names else
                                  jax.tree.map(pick, getattr(x._impl, f.name), getattr(y._impl, f.name))
                                  for f in type(x._impl).fields() if isinstance(getattr(x._impl, f.name), jax.Array)})
        public = {f.name: jax.tree.map(pick, getattr(x, f.name), getattr(y, f.name))
                  for f in type(x).fields() if f.name != "_impl"}
        return x.replace(**public, _impl=impl)

    return jax.tree.map(node, a, b, is_leaf=lambda n: isinstance(n, mjx.Data))
