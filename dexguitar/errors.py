"""Errors a user can act on. Library code raises them; only `cli.main` turns them into one line and an exit code.

`UserError` is the base: a bad file, path, option or run directory. `InputError` adds the file and the position in
it. Anything else that escapes to the CLI is a bug in dexguitar, not in the user's input.
"""
from __future__ import annotations

import os
import stat
from pathlib import Path


class UserError(Exception):
    """Something the user can fix; the message says what and where."""


class InputError(UserError, ValueError):
    """Bad input: the message names the file, the position in it and what was expected."""

    def __init__(self, path: str | Path | None, where: str | None, message: str):
        self.path, self.where, self.detail = path, where, message
        loc = str(path) if path is not None else "<input>"
        if where:
            loc += f":{where}"
        super().__init__(f"{loc}: {message}")


class RunError(UserError):
    """A run directory that cannot be used as asked: locked, from another config, missing or corrupted."""


class TrainingDiverged(UserError):
    """Training produced non-finite numbers again and again, even after rolling back to the last good checkpoint."""


_SPECIAL_FILES = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                  (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def special_file(path: str | Path) -> str | None:
    """What `path` is when it exists but is no regular file ("a FIFO (named pipe)", "a directory", ...), else None.
    Found with `stat`, which never blocks: opening a FIFO waits for a writer, forever if none comes."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):      # missing, unreadable, or a name with a NUL byte: open() says which
        return None
    if stat.S_ISREG(mode):
        return None
    return next((name for test, name in _SPECIAL_FILES if test(mode)), "not a regular file")


def read_input(path: str | Path, what: str, error=InputError, limit: int | None = None, why_limit: str = "",
               empty_ok: bool = False) -> bytes:
    """The bytes of a user's file, or `error(path, None, why)` when it is missing, a directory, unreadable, empty
    (unless `empty_ok`: the caller says what an empty file is not) or larger than `limit` bytes. At most `limit` + 1
    bytes are read, so an oversized file is refused at once. A special file (a FIFO, a device, a socket) is refused
    before it is opened."""
    path = Path(path)
    kind = special_file(path)
    if kind is not None:
        raise error(path, None, f"is {kind}, not {what}")
    try:
        with open(path, "rb") as f:
            data = f.read(-1 if limit is None else limit + 1)
    except FileNotFoundError:
        raise error(path, None, "no such file") from None
    except IsADirectoryError:
        raise error(path, None, f"is a directory, not {what}") from None
    except OSError as e:
        raise error(path, None, f"cannot read the file: {e.strerror or e}") from None
    if not data and not empty_ok:
        raise error(path, None, "the file is empty")
    if limit is not None and len(data) > limit:
        raise error(path, None, f"the file is larger than {limit} bytes, the limit for {what}{why_limit}")
    return data
