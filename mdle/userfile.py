"""Read a file the user named, safely: regular files of bounded size only.

Every path a user gives mdle (a plan, an import, a world, a trace, a file ``:load``-ed
in the REPL, and whatever a trace header names) is opened here. ``/dev/zero`` would be
read until memory runs out and a FIFO with no writer would block forever, so anything
that is not a regular file is refused, as is a file larger than
:data:`MAX_FILE_BYTES`. The FIFO is opened without blocking (``O_NONBLOCK``) before it
is looked at, so refusing it cannot hang either.

Callers turn :class:`UserFileError` into their own error (a located diagnostic for an
import, a world error for a world) with :attr:`UserFileError.reason` as the words.
"""

from __future__ import annotations

import os
import stat
from typing import BinaryIO

__all__ = ["MAX_FILE_BYTES", "UserFileError", "open_user_file", "read_user_file"]

#: Largest file mdle reads (64 MB): plans, worlds and traces are far smaller.
MAX_FILE_BYTES = 64 * 1024 * 1024

_KINDS = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"),
          (stat.S_ISDIR, "a directory"))


class UserFileError(Exception):
    """A user's file cannot be read; ``reason`` says why in words (``no such file``)."""

    def __init__(self, path: str, reason: str) -> None:
        super().__init__(f"cannot read `{path}`: {reason}")
        self.path = path
        self.reason = reason


def _size(n: int) -> str:
    return f"{n / 1024 / 1024:.1f} MB" if n >= 1024 * 1024 else f"{n} bytes"


def open_user_file(path: str | os.PathLike[str], limit: int = MAX_FILE_BYTES) -> BinaryIO:
    """Open a regular file of at most ``limit`` bytes for reading (binary).

    Raises
    ------
    UserFileError
        Missing, unreadable, not a regular file (a FIFO, a device, a socket, a
        directory), or larger than ``limit``.
    """
    name = os.fspath(path)
    shown = name if isinstance(name, str) else repr(name)
    try:
        fd = os.open(name, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0)
                     | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise UserFileError(shown, "no such file") from None
    except IsADirectoryError:
        raise UserFileError(shown, "it is a directory") from None
    except OSError as err:
        raise UserFileError(shown, err.strerror or str(err)) from None
    except ValueError:  # a NUL character in the path
        raise UserFileError(repr(shown), "not a file name") from None
    try:
        info = os.fstat(fd)
        for test, kind in _KINDS:
            if test(info.st_mode):
                raise UserFileError(shown, f"it is {kind}, not a regular file")
        if not stat.S_ISREG(info.st_mode):
            raise UserFileError(shown, "it is not a regular file")
        if info.st_size > limit:
            raise UserFileError(shown, f"it is {_size(info.st_size)}; mdle reads files of at "
                                       f"most {_size(limit)}")
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        try:
            os.close(fd)
        except OSError:
            pass
        raise


def read_user_file(path: str | os.PathLike[str], limit: int = MAX_FILE_BYTES) -> bytes:
    """Return the bytes of a regular file of at most ``limit`` bytes.

    Raises
    ------
    UserFileError
        As :func:`open_user_file`, or the file grew past ``limit`` while being read.
    """
    with open_user_file(path, limit) as f:
        data = f.read(limit + 1)
    if len(data) > limit:
        raise UserFileError(os.fspath(path) if isinstance(os.fspath(path), str) else repr(path),
                            f"it grew past {_size(limit)} while being read")
    return data
