"""Recorded robot runs for fitting profiles: per-tick commands, measured motion, scan ages.

Two layouts are read. A CSV with a header row holding at least ``t_s``, ``v_mps``,
``omega_radps``, ``cmd_v_mps`` and ``cmd_omega_radps`` (optionally ``scan_age_s``; other
columns are ignored; empty cells are missing values), one row per control tick, as
the hardware recordings are. Or an mdle trace (``mdle run --backend pioneer --trace
F.jsonl``), whose samples carry ``t``, ``v``, ``omega``, ``cmd_v``, ``cmd_omega`` and
``scan_age``. Each row's command is the one sent at that tick; its ``v`` and ``omega``
were measured at that tick, before the command was sent.
"""

from __future__ import annotations

import csv
import io
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mdle.core.errors import MdleError
from mdle.core.userfile import UserFileError, read_user_file

__all__ = ["CSV_COLUMNS", "Recording", "read_recording"]

#: CSV column of each recording field.
CSV_COLUMNS = {"t": "t_s", "v": "v_mps", "omega": "omega_radps", "cmd_v": "cmd_v_mps",
               "cmd_omega": "cmd_omega_radps", "scan_age": "scan_age_s"}
_MIN_TICKS = 10


@dataclass(frozen=True, eq=False)
class Recording:
    """One recorded run, arrays of one entry per control tick (SI units).

    ``scan_age`` is NaN where the tick had no scan (or the recording has none).
    """

    source: str
    t: np.ndarray
    v: np.ndarray
    omega: np.ndarray
    cmd_v: np.ndarray
    cmd_omega: np.ndarray
    scan_age: np.ndarray

    @property
    def tick(self) -> float:
        """Return the median time between ticks, seconds."""
        return float(np.median(np.diff(self.t)))

    def __len__(self) -> int:
        return len(self.t)


def read_recording(path: str | os.PathLike[str]) -> Recording:
    """Read a recording CSV or an mdle trace (``.jsonl``).

    Raises
    ------
    MdleError
        Unreadable file, missing columns, a cell that is not a number (file:line),
        times that do not increase, or fewer than 10 ticks.
    """
    p = Path(path)
    if p.suffix in (".jsonl", ".json"):
        rec = _from_trace(p)
    else:
        rec = _from_csv(p)
    if len(rec) < _MIN_TICKS:
        raise MdleError(f"{p}: {len(rec)} ticks recorded; a fit needs at least {_MIN_TICKS}")
    bad = np.flatnonzero(np.diff(rec.t) <= 0)
    if bad.size:
        raise MdleError(f"{p}: tick {bad[0] + 2}: time does not increase "
                        f"({rec.t[bad[0]]:g} s, then {rec.t[bad[0] + 1]:g} s)")
    for name in ("v", "omega", "cmd_v", "cmd_omega"):
        col = getattr(rec, name)
        if not np.all(np.isfinite(col)):
            i = int(np.flatnonzero(~np.isfinite(col))[0])
            raise MdleError(f"{p}: tick {i + 1}: `{name}` is missing")
    return rec


def _from_csv(p: Path) -> Recording:
    # read as every user file is: a regular file of bounded size (not /dev/zero or a FIFO)
    try:
        text = read_user_file(p).decode("utf-8")
    except UserFileError as err:  # missing, a FIFO, too large, EIO
        raise MdleError(f"cannot read recording {p}: {err.reason}") from None
    except UnicodeDecodeError as err:
        raise MdleError(f"cannot read recording {p}: not UTF-8 text ({err.reason} at byte "
                        f"{err.start})") from None
    try:
        with io.StringIO(text, newline="") as f:
            reader = csv.reader(f)
            header = next(reader, None)
            if header is None:
                raise MdleError(f"{p}: empty file (expected a CSV header row)")
            header = [h.strip() for h in header]
            need = [c for k, c in CSV_COLUMNS.items() if k != "scan_age"]
            missing = [c for c in need if c not in header]
            if missing:
                raise MdleError(f"{p}:1: missing column(s) {', '.join(missing)} (a recording "
                                f"needs {', '.join(need)}; scan_age_s optional)")
            index = {k: header.index(c) for k, c in CSV_COLUMNS.items() if c in header}
            cols: dict[str, list[float]] = {k: [] for k in CSV_COLUMNS}
            for row in reader:
                if not row or all(not c.strip() for c in row):
                    continue
                for key in CSV_COLUMNS:
                    i = index.get(key)
                    cell = row[i].strip() if i is not None and i < len(row) else ""
                    try:
                        cols[key].append(float(cell) if cell else math.nan)
                    except ValueError:
                        raise MdleError(f"{p}:{reader.line_num}: column {CSV_COLUMNS[key]}: "
                                        f"not a number: {cell!r}") from None
    except csv.Error as err:  # a NUL byte, a quote left open
        raise MdleError(f"{p}:{reader.line_num}: not a CSV row: {err}") from None
    arrays = {k: np.asarray(v, dtype=float) for k, v in cols.items()}
    return Recording(source=str(p), **arrays)


def _from_trace(p: Path) -> Recording:
    from mdle.record.load import read_trace

    trace = read_trace(p)
    if not trace.samples:
        raise MdleError(f"{p}: the trace has no samples")
    return Recording(
        source=str(p),
        t=trace.column("t"), v=trace.column("v"), omega=trace.column("omega"),
        cmd_v=trace.column("cmd_v"), cmd_omega=trace.column("cmd_omega"),
        scan_age=trace.column("scan_age"))
