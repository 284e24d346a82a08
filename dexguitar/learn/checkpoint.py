"""Saving and restoring pytrees with orbax: the whole `TrainState` of a run (for --resume), a compact part of it
(`only`: what cannot be rebuilt, small enough to carry between machines) and policy exports.

A training run saves through a `Saver`, in the background: the save returns once the arrays are copied to host
memory and the disk write overlaps the next training chunk. Orbax writes each step into a temporary folder and
renames it when complete, so a process killed mid-write leaves the step before it as the newest.

A checkpoint directory holds numbered steps; the newest few are kept. Restoring falls back to the newest intact step
when a later one is damaged (a file truncated or deleted by hand, a disk that filled up), with a warning, so one bad
save never loses a run; a run that continues sets the damaged steps aside (`<step>.damaged-<time>`, a name orbax does
not read as a step) and writes those steps again. A save that finds the disk full raises one `DiskFull` error naming
the directory and the step kept; orbax's own reports of it (log records with tracebacks, the abandoned writes) are
silenced, and the half-written step is removed.
"""
from __future__ import annotations

import atexit
import contextlib
import errno
import gc
import logging
import os
import shutil
import sys
import time
import warnings
from pathlib import Path

import jax
import numpy as np
import orbax.checkpoint as ocp

from dexguitar.errors import RunError


_FULL = (errno.ENOSPC, errno.EDQUOT)
_FULL_TEXT = tuple(os.strerror(code) for code in _FULL) + tuple(f"os_error_code='{code}'" for code in _FULL)


def disk_full(err: BaseException | None) -> bool:
    """Does `err`, or an error it came from, say that the disk (or the user's quota) is full? Python reports it as an
    `OSError`, orbax's writes (TensorStore) as a RESOURCE_EXHAUSTED error with the OS error's code in its text."""
    seen = set()
    while err is not None and id(err) not in seen:
        seen.add(id(err))
        if (isinstance(err, OSError) and err.errno in _FULL) or any(t in str(err) for t in _FULL_TEXT):
            return True
        err = err.__cause__ or err.__context__
    return False


class DiskFull(RunError):
    """A save that found the disk full."""


def full_message(where, kept: int | None = None) -> str:
    """What a user reads when a save or a write of a run found the disk full."""
    keep = (f"the newest complete checkpoint, step {kept}, is kept" if kept is not None else
            "no checkpoint is complete")
    return f"{where}: the disk is full (no space left on device); {keep}. Free some space and continue with --resume"


class _Silenced(logging.Filter):
    """Drops the log records of a failed save or restore that the failure's own error says in one line: orbax's
    background threads log each failed write of a full disk with its traceback, and asyncio each task that orbax
    abandoned when another failed (hundreds of lines in all)."""

    def filter(self, record: logging.LogRecord) -> bool:
        exc = record.exc_info[1] if record.exc_info else None
        try:
            message = record.getMessage()
        except Exception:           # noqa: BLE001 - a record that cannot be formatted is not ours to judge
            return True
        if record.name == "asyncio" and "never retrieved" in message and any(
                k in message for k in ("orbax", "TensorStore", "tensorstore", "OCDBT")):
            return False
        return not (disk_full(exc) or any(t in message for t in _FULL_TEXT))


for _name in ("absl", "asyncio"):
    logging.getLogger(_name).addFilter(_Silenced())


def _leftover(unraisable) -> bool:
    """An error of the writes that orbax abandons when a save or a restore fails: a pending write coroutine that is
    collected, or TensorStore finishing a write for an event loop that orbax already closed."""
    code = getattr(unraisable.object, "cr_code", None)
    if code is not None and "orbax" in code.co_filename:
        return True
    return isinstance(unraisable.exc_value, RuntimeError) and str(unraisable.exc_value) == "Event loop is closed"


def _quiet_leftovers() -> None:
    """Drop the errors of the writes that orbax abandons when a save or a restore fails, each of which would print a
    traceback (a hundred or more: "Event loop is closed", "sys.meta_path is None"); at exit, collect them while this
    hook still runs (the interpreter's last collection bypasses it). Set up before orbax is used: TensorStore ends
    the abandoned writes in its own threads, before the failure is seen."""
    if getattr(sys.unraisablehook, "leftovers", False):
        return
    hook = sys.unraisablehook

    def quiet(unraisable):
        if not _leftover(unraisable):
            hook(unraisable)
    quiet.leftovers = True
    sys.unraisablehook = quiet
    atexit.unregister(gc.collect)
    atexit.register(gc.collect)


def collect_abandoned() -> None:
    """Collect now the reads or writes that orbax abandoned when a restore or a save failed, quietly: their errors go
    to `_quiet_leftovers`' hook, and a read that never started would warn that its coroutine "was never awaited"."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r"coroutine .* was never awaited", category=RuntimeWarning)
        gc.collect()


def _manager(directory: Path, keep: int = 2, create: bool = True, writer: bool = False) -> ocp.CheckpointManager:
    """Orbax's manager of a checkpoint directory; a `writer` (the one process that saves there) first removes the
    temporary folders of saves that never completed."""
    _quiet_leftovers()
    return ocp.CheckpointManager(Path(directory).absolute(), options=ocp.CheckpointManagerOptions(
        max_to_keep=keep, create=create, cleanup_tmp_directories=writer))


def _why(err: BaseException) -> str:
    """The first line of the error a failure came from (orbax wraps TensorStore's in a long message)."""
    while (err.__cause__ or err.__context__) is not None:
        err = err.__cause__ or err.__context__
    text = str(err).strip()
    return f"{type(err).__name__}: {text.splitlines()[0][:200]}" if text else type(err).__name__


def _leaves(tree, only=None) -> dict:
    """The non-empty leaves of a pytree by position (orbax refuses zero-size arrays, e.g. MJX's empty `act`), or
    those of them that `only(key path, leaf)` keeps."""
    return {f"{i:05d}": leaf for i, (path, leaf) in enumerate(jax.tree_util.tree_flatten_with_path(tree)[0])
            if np.size(leaf) > 0 and (only is None or only(path, leaf))}


class Saver:
    """The saves of one checkpoint directory, written in the background. `save` returns when the arrays are on the
    host (a donating jit may then reuse their device buffers) and first waits for the save before it; `wait` (or
    leaving the `with` block) returns when everything saved is complete on disk. A save that fails raises a
    `RunError` when it is next waited for. The steps from `step` on that a directory already holds were written by
    the future of a run that went back to an older step: they are deleted first (else orbax, keeping the newest
    steps, would delete the new one)."""

    def __init__(self, directory, keep: int = 2, only=None):
        self.directory, self.only = Path(directory), only
        self._mngr = _manager(directory, keep, writer=True)
        self._step = None           # the step being written
        self._failed = None         # the RunError of a failed save, raised again by later waits

    def save(self, step: int, tree) -> None:
        step = int(step)
        self.wait()
        self._step = step
        with self._reported():
            for later in [s for s in self._mngr.all_steps() if s >= step]:
                self._mngr.delete(later)
            self._mngr.save(step, args=ocp.args.StandardSave(_leaves(tree, self.only)), force=True)

    def wait(self) -> None:
        if self._failed is not None:
            raise self._failed
        with self._reported():
            self._mngr.wait_until_finished()

    @contextlib.contextmanager
    def _reported(self):
        """A write that fails for a full disk or another OSError raises a RunError, now and at every later wait."""
        try:
            yield
        except Exception as err:    # noqa: BLE001 - orbax reports a failed write as many error types
            if not (disk_full(err) or isinstance(err, OSError)):
                raise
            self._failed = self._failure(err)
            raise self._failed from None

    def _failure(self, err: BaseException) -> RunError:
        """The RunError of a failed save, once its half-written step is removed."""
        collect_abandoned()
        for tmp in self.directory.glob(f"{self._step}.orbax-checkpoint-tmp*"):
            shutil.rmtree(tmp, ignore_errors=True)
        kept = max(self._mngr.all_steps(), default=None)
        if disk_full(err):
            return DiskFull(full_message(self.directory, kept))
        return RunError(f"{self.directory}: saving step {self._step} failed ({_why(err)}); "
                        + (f"step {kept} is the newest complete checkpoint" if kept is not None else
                           "no checkpoint is complete"))

    def close(self) -> None:
        try:
            self.wait()
        finally:
            if self._failed is None:
                self._mngr.close()

    def __enter__(self):
        return self

    def __exit__(self, kind, error, trace):
        try:
            self.close()
        except RunError:
            if error is None:       # else the error in flight is the one to report (a full disk fails every save)
                raise


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


def set_aside(directory, step: int) -> Path:
    """Rename a damaged step to `<step>.damaged-<time>`, which orbax does not read as a step: the step can be written
    again, and what was there is still there to look at."""
    source = Path(directory) / str(step)
    target = source.with_name(f"{step}.damaged-{time.strftime('%Y%m%d-%H%M%S')}")
    n = 1
    while target.exists():
        n += 1
        target = target.with_name(f"{step}.damaged-{time.strftime('%Y%m%d-%H%M%S')}-{n}")
    source.rename(target)
    return target


def restore(directory, target, step: int | None = None, only=None, set_damaged_aside: bool = False):
    """(tree, step): the pytree saved at `step` (default: the newest intact one), restored into the structure,
    dtypes and placement of `target`; its empty leaves, and those `only` leaves out (as saved), are taken as they
    are. `set_damaged_aside`: the damaged steps newer than the one restored are renamed (`set_aside`), for a run
    that continues from it and writes those steps again."""
    candidates = [step] if step is not None else steps(directory)
    if not candidates:
        raise RunError(f"{directory}: no checkpoint")
    leaves, treedef = jax.tree.flatten(target)
    errors, damaged = [], []
    for s in candidates:
        try:
            with _manager(directory, create=False) as mngr:
                restored = mngr.restore(s, args=ocp.args.StandardRestore(_leaves(target, only)))
        except Exception as err:    # noqa: BLE001 - a damaged checkpoint surfaces as many error types
            collect_abandoned()
            errors.append(f"step {s}: {_why(err)}")
            damaged.append(s)
            print(f"warning: {directory}: checkpoint step {s} cannot be read ({_why(err)}); trying an older one",
                  file=sys.stderr)
            continue
        if errors:
            aside = [set_aside(directory, d).name for d in damaged] if set_damaged_aside else []
            print(f"warning: {directory}: restored step {s}, the newest intact one"
                  + (f"; the damaged steps are set aside as {', '.join(aside)}" if aside else ""), file=sys.stderr)
        return jax.tree.unflatten(treedef, [restored.get(f"{i:05d}", leaf) for i, leaf in enumerate(leaves)]), s
    raise RunError(f"{directory}: no intact checkpoint ({'; '.join(errors)})")
