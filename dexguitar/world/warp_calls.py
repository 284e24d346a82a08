"""The Warp calls a compiled program names, so that a program compiled and saved by one process runs in another.

MJX runs its Warp physics through JAX FFI targets (`mujoco.mjx.warp.ffi`), one per MJX function (forward, step),
registered when a trace first meets it and named in the order of registration. Each call in a traced program carries
a call id, under which Warp keeps that call's static arguments (the model's sizes and flags) in the process that
traced it. A compiled program refers to both, so a process that loads it instead of tracing it needs the same
targets under the same names and those call ids described. `taken` notes what a trace added; `restore` puts it back
in a process that has traced the same things before it, and refuses where anything differs (the caller then
traces)."""
from __future__ import annotations

from typing import Callable

try:
    from mujoco.mjx.warp import ffi as _ffi
    from warp._src.jax.ffi import FfiCallDesc
except ImportError:         # no warp-lang (or another layout of it): no Warp targets
    _ffi = FfiCallDesc = None
# Can this process record and restore Warp calls? Where not, a program that calls Warp is not kept in a file.
AVAILABLE = hasattr(_ffi, "_JAX_CALLABLE_VARIADIC_TUPLE_REGISTRY") and hasattr(
    _ffi, "_JAX_CALLABLE_VARIADIC_TUPLE_REGISTRY_LOCK")


def _what(key) -> str:
    """What a target wraps: MJX's function and its number of (flattened) arguments."""
    func, signature = key[0], key[1]
    return f"{func.__module__}.{func.__qualname__}/{len(signature.parameters)}"


def _targets() -> dict:
    """{FFI target name: (what it wraps, Warp's callable)} of every MJX Warp target registered in this process."""
    if not AVAILABLE:
        return {}
    with _ffi._JAX_CALLABLE_VARIADIC_TUPLE_REGISTRY_LOCK:
        items = list(_ffi._JAX_CALLABLE_VARIADIC_TUPLE_REGISTRY.items())
    return {c.name: (_what(key), c) for key, c in items}


def counts() -> dict:
    """{target name: its next call id}: how far this process's traces have called each target."""
    return {name: c.call_id for name, (_, c) in _targets().items()}


def taken(before: dict) -> dict:
    """The calls traced since `counts()` returned `before`, per target called: what it wraps, the first and the next
    call id, and each call's static arguments."""
    out = {}
    for name, (what, c) in _targets().items():
        first = before.get(name, 0)
        if c.call_id > first:
            out[name] = {"what": what, "first": first, "next": c.call_id,
                         "calls": {i: dict(c.call_descriptors[i].static_inputs) for i in range(first, c.call_id)}}
    return out


def restore(record: dict, register: Callable[[], object]) -> bool:
    """Describe the calls of `record` (`taken`) in this process, as the trace that made it had: True, or False where
    this process cannot serve them. Each target must stand at the call id the recorded trace started from (this
    process traced what the recording one had traced before it); `register` is a trace that registers the targets
    this process lacks (one env step), in the order the recorded trace first met them. Afterwards each target goes
    on from the recorded next call id, so later traces number their calls as in the recording process."""
    now = counts()
    if any(now.get(name, 0) != r["first"] for name, r in record.items()):
        return False
    if any(name not in now for name in record):
        register()
    live = _targets()
    if any(name not in live or live[name][0] != r["what"] or live[name][1].call_id > r["next"]
           for name, r in record.items()):
        return False
    for name, r in record.items():
        target = live[name][1]
        for i, static in r["calls"].items():
            target.call_descriptors[int(i)] = FfiCallDesc(dict(static))
        target.call_id = r["next"]
    return True
