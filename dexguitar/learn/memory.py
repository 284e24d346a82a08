"""Whether a number of envs can fit in memory, decided before anything is allocated.

The estimate is a floor, from shapes alone (`jax.eval_shape`, nothing computed): what a run must hold at once. A
count whose floor exceeds the free memory cannot run, and is refused at once with the estimate, instead of growing
until the machine runs out (a GPU's allocator fails, a CPU host swaps or is killed). A count under the floor may
still fail later on the step's temporaries, which shapes alone do not tell.
"""
from __future__ import annotations

import os

import jax
import numpy as np

from dexguitar.errors import UserError


def tree_bytes(tree) -> int:
    """Bytes of the arrays (or `jax.ShapeDtypeStruct`s) of a pytree."""
    return int(sum(int(np.prod(x.shape, dtype=np.int64)) * np.dtype(x.dtype).itemsize
                   for x in jax.tree.leaves(tree)))


def env_bytes(env) -> int:
    """Bytes of one env's state (`env.reset`'s shapes)."""
    return tree_bytes(jax.eval_shape(env.reset, jax.random.PRNGKey(0)))


def training_bytes(trainer) -> tuple[int, int]:
    """(bytes per env, bytes that do not grow with the envs) a training run holds at least: its state
    (`trainer.state_shapes`, computed once and used again to compile: env states, networks, optimizers, replay
    buffers), a second env state (a step's output beside its input), and each env's observation, privileged
    observation and link history for every step of the rollout."""
    shapes = trainer.state_shapes
    n = trainer.config.num_envs
    state_env = tree_bytes(shapes.env) // n
    step = tree_bytes((shapes.env.obs, shapes.env.privileged, shapes.env.body.link_hist)) // n
    per_env = 2 * state_env + trainer.config.horizon * step
    return per_env, tree_bytes(shapes) - n * state_env


def _host_free() -> int:
    """The host's available memory: MemAvailable, or free pages, capped by a cgroup (container) limit."""
    free = None
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    free = int(line.split()[1]) * 1024
    except OSError:
        pass
    if free is None:
        free = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    try:
        with open("/sys/fs/cgroup/memory.max") as f_max, open("/sys/fs/cgroup/memory.current") as f_now:
            limit, used = f_max.read().strip(), f_now.read().strip()
        if limit.isdigit():
            free = min(free, int(limit) - int(used))
    except (OSError, ValueError):
        pass
    return free


def free_memory(devices: int | None = None) -> tuple[int, str] | None:
    """(bytes free for the envs, where): on an accelerator the free memory of one local device (its allocator's
    limit less what is in use) times the `devices` that share the envs (default: all); on a CPU the host's. None
    when the backend does not say."""
    device = jax.local_devices()[0]
    if device.platform == "cpu":
        return _host_free(), "this machine"
    stats = device.memory_stats() or {}
    if "bytes_limit" not in stats:
        return None
    n = devices or len(jax.devices())
    free = (stats["bytes_limit"] - stats.get("bytes_in_use", 0)) * n
    return free, f"{n} {device.device_kind}" + (" devices" if n > 1 else "")


def _gib(n: int) -> str:
    return f"{n / 2**30:,.1f} GiB" if n >= 2**30 else f"{n / 2**20:,.1f} MiB"


def check_envs(n_envs: int, per_env: int, fixed: int = 0, *, devices: int | None = None, option: str = "--envs",
               free: tuple[int, str] | None = None) -> None:
    """`UserError` when `n_envs` envs of `per_env` bytes each, plus `fixed` bytes, exceed the free memory (`free`,
    default `free_memory(devices)`), with the estimate and the most envs that would fit."""
    free = free if free is not None else free_memory(devices)
    if free is None:
        return
    have, where = free
    need = fixed + n_envs * per_env
    if need <= have:
        return
    fit = max(0, (have - fixed) // per_env)
    raise UserError(f"{option} {n_envs:,}: needs at least {_gib(need)} ({per_env / 1024:,.0f} KiB per env"
                    + (f" and {_gib(fixed)} besides" if fixed else "") + f"), but {where} has {_gib(have)} free; "
                    f"at most about {fit:,} envs fit")
