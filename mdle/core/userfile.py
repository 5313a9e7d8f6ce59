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

import contextlib
import errno
import os
import stat
import tempfile
from collections.abc import Iterator
from typing import BinaryIO

__all__ = ["MAX_FILE_BYTES", "UserFileError", "open_user_file", "read_user_file", "same_file",
           "os_reason", "write_user_file", "replacing", "writable_folder", "file_fault",
           "file_fault_words"]

#: Largest file mdle reads (64 MB): plans, worlds and traces are far smaller.
MAX_FILE_BYTES = 64 * 1024 * 1024

_KINDS = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"),
          (stat.S_ISDIR, "a directory"))


class UserFileError(Exception):
    """A user's file cannot be read (or written); ``reason`` says why (``no such file``).

    ``code`` is the OSError's errno when the machine failed (a full disk): :attr:`fault`.
    """

    def __init__(self, path: str, reason: str, verb: str = "read",
                 code: int | None = None) -> None:
        super().__init__(f"cannot {verb} `{path}`: {reason}")
        self.path = path
        self.reason = reason
        self.code = code

    @property
    def fault(self) -> bool:
        """True for a fault of the machine (exit 74), not a refused or mistaken file."""
        return self.code in _FILE_FAULTS


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
        try:
            data = f.read(limit + 1)
        except OSError as err:  # EIO from a failing disk, a file vanished from a share
            name = os.fspath(path)
            raise UserFileError(name if isinstance(name, str) else repr(name),
                                os_reason(err), code=err.errno) from None
    if len(data) > limit:
        raise UserFileError(os.fspath(path) if isinstance(os.fspath(path), str) else repr(path),
                            f"it grew past {_size(limit)} while being read")
    return data


def same_file(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """Return True when ``a`` and ``b`` name one existing file (device and inode: links too).

    False when either does not exist or cannot be examined, so a path that cannot be
    compared is never taken for an input.
    """
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):
        return False


_REASONS = {errno.ENOSPC: "the disk is full", errno.EROFS: "the file system is read-only",
            errno.EACCES: "permission denied", errno.EPERM: "permission denied",
            errno.EIO: "input/output error (a failing disk or a lost network share?)",
            errno.EDQUOT: "the disk quota is used up", errno.ENOENT: "no such file or folder",
            errno.EISDIR: "it is a folder", errno.ENOTDIR: "a part of the path is not a folder"}


def os_reason(err: OSError) -> str:
    """Return an OSError in words (``the disk is full``), for a located message."""
    return _REASONS.get(err.errno or 0) or err.strerror or type(err).__name__


@contextlib.contextmanager
def replacing(path: str | os.PathLike[str]) -> Iterator[str]:
    """Give a temporary path beside ``path``; on success it is renamed onto ``path``.

    The file a reader sees at ``path`` is therefore either the old one or the whole new
    one, never a half-written one; on any error the temporary file is removed.

    Raises
    ------
    UserFileError
        The temporary file cannot be made or renamed (a read-only folder, a full disk).
    """
    name = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(name))
    _refuse_special(name)
    try:
        fd, tmp = tempfile.mkstemp(dir=folder, prefix="." + os.path.basename(name) + ".",
                                   suffix=".part")
        os.close(fd)
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp's 0600: give what open() would
    except OSError as err:
        raise UserFileError(name, os_reason(err), "write", err.errno) from None
    try:
        yield tmp
        os.replace(tmp, name)
    except OSError as err:
        _remove(tmp)
        raise UserFileError(name, os_reason(err), "write", err.errno) from None
    except BaseException:
        _remove(tmp)
        raise


def _refuse_special(name: str) -> None:
    """Refuse to replace anything but a regular file (renaming over /dev/full replaces it)."""
    try:
        info = os.stat(name)
    except FileNotFoundError:
        return
    except OSError as err:
        raise UserFileError(name, os_reason(err), "write") from None
    for test, kind in _KINDS:
        if test(info.st_mode):
            raise UserFileError(name, f"it is {kind}, not a regular file", "write")


def _umask() -> int:
    mask = os.umask(0o022)  # reading the mask means setting it: put it straight back
    os.umask(mask)
    return mask


def _remove(path: str) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass


def write_user_file(path: str | os.PathLike[str], data: bytes | str) -> None:
    """Write ``data`` to ``path`` whole (through a temporary file renamed into place).

    Raises
    ------
    UserFileError
        The file cannot be written: its words say why (``the disk is full``).
    """
    raw = data.encode("utf-8") if isinstance(data, str) else data
    with replacing(path) as tmp:
        with open(tmp, "wb") as f:
            f.write(raw)
            f.flush()
            os.fsync(f.fileno())


def writable_folder(path: str | os.PathLike[str]) -> None:
    """Make the folder ``path`` (and its parents) and prove a file can be written in it.

    Called before long work whose results go there, so a read-only disk or a missing
    permission is said at once rather than after the computing. A small file is created
    and removed: permission bits alone do not tell (root ignores them; a read-only
    mount does not).

    Raises
    ------
    UserFileError
        The folder cannot be made or written; the words say why.
    """
    name = os.fspath(path)
    try:
        os.makedirs(name, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=name, prefix=".mdle-probe-")
        os.close(fd)
        os.unlink(probe)
    except FileExistsError:
        raise UserFileError(name, "it is a file, not a folder", "write in") from None
    except OSError as err:
        raise UserFileError(name, os_reason(err), "write in", err.errno) from None


#: What the machine, not mdle, got wrong reading or writing a file: these OSErrors end a
#: command with a message and EXIT_IO wherever they surface (a full disk under a results
#: table, a read-only folder); any other OSError is still a bug (exit 70).
_FILE_FAULTS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EIO, errno.EROFS, errno.EACCES,
                          errno.EPERM, errno.ENOENT, errno.EISDIR, errno.ENOTDIR,
                          errno.ENAMETOOLONG, errno.EFBIG, errno.ESTALE})


def file_fault(exc: OSError) -> bool:
    """Return True for an OSError that is a fault of the machine's files, not of mdle."""
    return exc.errno in _FILE_FAULTS


def file_fault_words(exc: OSError) -> str:
    """Return the fault in words, naming the file when the error does."""
    where = f" `{exc.filename}`" if exc.filename else ""
    return f"cannot read or write the file{where}: {os_reason(exc)}"
