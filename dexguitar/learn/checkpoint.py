"""Saving and restoring pytrees with orbax: the whole `TrainState` of a run (for --resume), a compact part of it
(`only`: what cannot be rebuilt, small enough to carry between machines) and policy exports.

A training run saves through a `Saver`, in the background: the save returns once the arrays are copied to host
memory and the disk write overlaps the next training chunk. Orbax writes each step into a temporary folder and
renames it when complete, so a process killed mid-write leaves the step before it as the newest.

A checkpoint directory holds numbered steps; the newest few are kept. Restoring falls back to the newest intact step
when a later one is damaged (a file truncated or deleted by hand, a disk that filled up), with a warning, so one bad
save never loses a run.
"""
from __future__ import annotations

import sys
from pathlib import Path

import jax
import numpy as np
import orbax.checkpoint as ocp

from dexguitar.errors import RunError


def _manager(directory: Path, keep: int = 2, create: bool = True) -> ocp.CheckpointManager:
    return ocp.CheckpointManager(Path(directory).absolute(), options=ocp.CheckpointManagerOptions(
        max_to_keep=keep, create=create))


def _leaves(tree, only=None) -> dict:
    """The non-empty leaves of a pytree by position (orbax refuses zero-size arrays, e.g. MJX's empty `act`), or
    those of them that `only(key path, leaf)` keeps."""
    return {f"{i:05d}": leaf for i, (path, leaf) in enumerate(jax.tree_util.tree_flatten_with_path(tree)[0])
            if np.size(leaf) > 0 and (only is None or only(path, leaf))}


class Saver:
    """The saves of one checkpoint directory, written in the background. `save` returns when the arrays are on the
    host (a donating jit may then reuse their device buffers) and first waits for the save before it; `wait` (or
    leaving the `with` block) returns when everything saved is complete on disk."""

    def __init__(self, directory, keep: int = 2, only=None):
        self.directory, self.only = Path(directory), only
        self._mngr = _manager(directory, keep)

    def save(self, step: int, tree) -> None:
        self._mngr.save(int(step), args=ocp.args.StandardSave(_leaves(tree, self.only)), force=True)

    def wait(self) -> None:
        self._mngr.wait_until_finished()

    def close(self) -> None:
        self.wait()
        self._mngr.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def save(directory, step: int, tree, keep: int = 2, only=None) -> None:
    """Save a pytree (or the leaves `only` keeps) at `step` (blocking: when this returns the checkpoint is complete
    on disk)."""
    with Saver(directory, keep, only) as saver:
        saver.save(step, tree)


def steps(directory) -> list[int]:
    """The saved steps, newest first."""
    if not Path(directory).is_dir():
        return []
    with _manager(directory, create=False) as mngr:
        return sorted(mngr.all_steps(), reverse=True)


def latest_step(directory) -> int | None:
    found = steps(directory)
    return found[0] if found else None


def restore(directory, target, step: int | None = None, only=None):
    """(tree, step): the pytree saved at `step` (default: the newest intact one), restored into the structure,
    dtypes and placement of `target`; its empty leaves, and those `only` leaves out (as saved), are taken as they
    are."""
    candidates = [step] if step is not None else steps(directory)
    if not candidates:
        raise RunError(f"{directory}: no checkpoint")
    leaves, treedef = jax.tree.flatten(target)
    errors = []
    for s in candidates:
        try:
            with _manager(directory, create=False) as mngr:
                restored = mngr.restore(s, args=ocp.args.StandardRestore(_leaves(target, only)))
        except Exception as err:    # noqa: BLE001 - a damaged checkpoint surfaces as many error types
            errors.append(f"step {s}: {type(err).__name__}: {str(err).splitlines()[0][:200] if str(err) else ''}")
            print(f"warning: {directory}: checkpoint step {s} cannot be read ({errors[-1]}); trying an older one",
                  file=sys.stderr)
            continue
        if errors:
            print(f"warning: {directory}: restored step {s}, the newest intact one", file=sys.stderr)
        return jax.tree.unflatten(treedef, [restored.get(f"{i:05d}", leaf) for i, leaf in enumerate(leaves)]), s
    raise RunError(f"{directory}: no intact checkpoint ({'; '.join(errors)})")
