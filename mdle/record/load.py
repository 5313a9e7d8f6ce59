"""Read any recorded run back as a :class:`~mdle.record.trace.Trace`.

A run is recorded as an mdle trace (JSON lines, :mod:`mdle.record.trace`), an MCAP file
(``mdle run --record``) or a rosbag2 folder holding one (``--rosbag``); plots, the REPL,
``mdle export`` and the profile fitter take any of them. The MCAP reader
(:mod:`mdle.record.read`) needs the optional extra ``mdle[mcap]``.
"""

from __future__ import annotations

import os

from mdle.record.read import read_recording
from mdle.record.trace import Trace, read_jsonl_trace

__all__ = ["read_trace"]


def read_trace(path: str | os.PathLike[str]) -> Trace:
    """Read a trace, an MCAP recording or a rosbag2 folder (told apart by content).

    Raises
    ------
    TraceError
        The file is missing, is not a recording of a run, has a newer version, or has a
        bad record other than a cut-off last one (the message names the file and line).
    """
    path = os.fspath(path)
    if _is_recording(path):
        return read_recording(path)
    return read_jsonl_trace(path)


def _is_recording(path: str) -> bool:
    """Return True for an MCAP file (by its magic) or a rosbag2 folder."""
    if os.path.isdir(path):
        return os.path.isfile(os.path.join(path, "metadata.yaml"))
    if not os.path.isfile(path):  # a FIFO or device: never open it here
        return False
    try:
        with open(path, "rb") as f:
            return f.read(8) == b"\x89MCAP0\r\n"
    except OSError:
        return False
