"""CSV files the commands write (``experiment --csv``), written as every user file is.

A CSV option is checked against the command's inputs before any work (an output never
replaces an input), its folder is proved writable then too, and the table is written
whole at the end through :func:`mdle.core.userfile.write_user_file`: a temporary file renamed
into place, so a full disk leaves the old file or none, never half a table. A fault of
the machine ends the command with exit 74, a refused file (a FIFO, a folder) with 1.
"""

from __future__ import annotations

import csv
import io
import os
import sys
from collections.abc import Iterable, Sequence
from typing import Any

from mdle.cli.clobber import refuse_clobbering
from mdle.console import output
from mdle.core.userfile import UserFileError, writable_folder, write_user_file

__all__ = ["check_csv_output", "csv_text", "write_csv_output", "write_failed"]


def check_csv_output(option: str, path: str | os.PathLike[str],
                     inputs: Iterable[tuple[str, str | None]] = ()) -> None:
    """Before the work: refuse ``path`` if it is an input; prove its folder writable.

    Raises
    ------
    MdleError
        ``path`` names one of ``inputs`` (``(what, path)`` pairs).
    UserFileError
        It is a folder or a device, or its folder cannot be written.
    """
    name = os.fspath(path)
    refuse_clobbering([(option, name)], inputs)
    if os.path.isdir(name):
        raise UserFileError(name, "it is a folder", "write")
    if os.path.exists(name) and not os.path.isfile(name):  # /dev/full, a FIFO
        raise UserFileError(name, "it is not a regular file", "write")
    writable_folder(os.path.dirname(os.path.abspath(name)))


def csv_text(header: Sequence[str], rows: Iterable[Sequence[Any]]) -> str:
    """Return the CSV text of ``header`` and ``rows`` (no header and no rows: empty)."""
    buf = io.StringIO()
    if header:
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerow(header)
        writer.writerows(rows)
    return buf.getvalue()


def write_csv_output(path: str | os.PathLike[str], header: Sequence[str],
                     rows: Iterable[Sequence[Any]]) -> None:
    """Write the table to ``path`` whole (a temporary file renamed into place).

    Raises
    ------
    UserFileError
        The file cannot be written; :attr:`~mdle.core.userfile.UserFileError.fault` tells a
        fault of the machine from a refused path.
    """
    write_user_file(path, csv_text(header, rows))


def write_failed(command: str, err: UserFileError) -> int:
    """Say why a CSV was not written; return the exit code (74: the machine, 1: the path)."""
    print(f"{command}: {err}", file=sys.stderr)
    return output.EXIT_IO if err.fault else output.EXIT_INPUT
