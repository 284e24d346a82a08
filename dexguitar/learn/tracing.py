"""One program per shape, in every process: the big programs (the training chunk, the evaluation's player) are traced
from JAX's empty tracing caches.

Why: a trace calls thousands of small jitted helpers (`jnp.where`, `clip`, `take`, MJX's pieces). The lowering emits
one private function per traced helper and shares it between the calls that got the same traced jaxpr back from
JAX's tracing caches; those are LRU caches of 2048 entries, and the trace of one training chunk alone misses ~2,900
times, so entries are evicted in the middle of it, and which ones depends on all that the process traced before (an
evaluation, another stage). The same chunk then lowered to another program after the first song of a process (in a
tiny CPU config 587 private functions, then 603 after an evaluation: another persistent-cache key, so a full compile,
90-110 s on an H100, for the second song). From empty caches the program is a function of the code and the shapes
alone.

The price: `jax.clear_caches()` also drops the process's compiled small programs (eager operations, `jit`s held by
nothing else); `Compiled` objects that callers keep, like the evaluation's, stay.
"""
from __future__ import annotations

import jax


def fresh_trace() -> None:
    """Empty JAX's tracing (and in-memory compilation) caches, so that the next trace does not depend on the past."""
    jax.clear_caches()


__all__ = ["fresh_trace"]
