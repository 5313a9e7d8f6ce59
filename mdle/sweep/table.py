"""The results table: one CSV row per finished run, appended as runs finish.

The CSV file is the sweep's journal: each row is written with one ``write(2)`` of a
whole line, so a sweep killed at any moment (even by SIGKILL) leaves every finished row
intact and at most one partial last line, which :class:`ResultsTable` drops when it
reopens the file. Reopening collects the keys of the finished runs, so a resumed sweep
skips them. With pyarrow installed a Parquet copy (typed columns) is written at the
end of the sweep.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from mdle.core.errors import MdleError

__all__ = ["ResultsTable", "columns_for", "read_rows", "write_parquet", "column_type",
           "RESULT_COLUMNS"]

_DESCRIBE = ("key", "index", "plan", "entry", "world", "robot", "sensing", "rate", "seed",
             "x0", "y0", "theta0")
RESULT_COLUMNS = ("status", "ended", "cause", "duration", "collided", "collisions",
                  "min_clearance", "distance", "ticks", "follow_rc", "follow_mean_err",
                  "follow_max_err", "engaged", "engage_time", "engage_distance",
                  "engaged_mean_err", "engaged_max_err")
_TAIL = ("attempts", "worker", "wall_time", "cpu_time")
_INT = {"index", "seed", "collisions", "ticks", "attempts"}
_BOOL = {"collided", "engaged"}
_TEXT = {"key", "plan", "entry", "world", "robot", "sensing", "status", "ended", "cause",
         "worker"}


def columns_for(parameters: Sequence[str], fields: Sequence[str]) -> list[str]:
    """Return a study's columns: description, parameters, results, trace fields, timing."""
    return ([*_DESCRIBE, *(f"param_{p}" for p in parameters), *RESULT_COLUMNS,
             *(f"{f}_{s}" for f in fields for s in ("mean", "max")), *_TAIL])


_FLOAT = ({*RESULT_COLUMNS, "rate", "x0", "y0", "theta0", "wall_time", "cpu_time"}
          - _INT - _BOOL - _TEXT)


def column_type(name: str) -> str:
    """Return the type of a column: ``text``, ``int``, ``bool``, ``float`` or ``any``.

    ``any`` (a column of another table, an experiment's) is read as the value looks:
    a whole number, a number, true/false, else text.
    """
    if name in _TEXT or name.startswith("param_"):
        return "text"
    if name in _INT:
        return "int"
    if name in _BOOL:
        return "bool"
    if name in _FLOAT or name.endswith(("_mean", "_max")):
        return "float"
    return "any"


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else ("inf" if value > 0 else
                                                          "-inf" if value < 0 else "nan")
    return str(value)


def _typed(name: str, text: str) -> Any:
    kind = column_type(name)
    if kind == "text":
        return text
    if text == "":
        return None
    if kind == "bool":
        return text == "true"
    if kind == "int":
        return int(text)
    if kind == "float":
        return float(text)
    for convert in (int, float):
        try:
            return convert(text)
        except ValueError:
            pass
    return {"true": True, "false": False}.get(text, text)


class ResultsTable:
    """Append rows to a results CSV; reopen it to resume.

    Parameters
    ----------
    path : path-like
        The CSV file (created with its header if missing or empty).
    columns : sequence of str
        The study's columns; an existing file must have exactly these.

    Raises
    ------
    MdleError
        The existing file is not a results table of this study (other columns).
    """

    def __init__(self, path: str | os.PathLike[str], columns: Sequence[str]) -> None:
        self.path = Path(path)
        self.columns = list(columns)
        self.done: set[str] = set()
        self.rows = 0
        self._repair_and_read()
        self._fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        if self.path.stat().st_size == 0:
            self._write_line(self.columns)

    def _repair_and_read(self) -> None:
        if not self.path.exists() or self.path.stat().st_size == 0:
            return
        data = self.path.read_bytes()
        if not data.endswith(b"\n"):    # a line cut off by a kill: the run is not finished
            cut = data.rfind(b"\n") + 1
            with open(self.path, "r+b") as f:
                f.truncate(cut)
            data = data[:cut]
        reader = csv.reader(io.StringIO(data.decode("utf-8")))
        header = next(reader, None)
        if header is None:
            return
        if header != self.columns:
            missing = [c for c in self.columns if c not in header]
            extra = [c for c in header if c not in self.columns]
            raise MdleError(f"{self.path}: a results table of another study (columns "
                            f"differ: missing {missing or 'none'}, extra {extra or 'none'}); "
                            "give another --out folder or remove it")
        key_at = header.index("key")
        for row in reader:
            if len(row) == len(header):
                self.done.add(row[key_at])
                self.rows += 1

    def _write_line(self, cells: Iterable[str]) -> None:
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow(list(cells))
        data = buf.getvalue().encode("utf-8")
        written = os.write(self._fd, data)
        while written < len(data):      # a short write: finish the same line
            written += os.write(self._fd, data[written:])

    def append(self, row: Mapping[str, Any]) -> None:
        """Write one finished run's row (columns it lacks are left empty)."""
        self._write_line(_cell(row.get(c)) for c in self.columns)
        self.done.add(str(row["key"]))
        self.rows += 1

    def close(self) -> None:
        """Close the file (every row is already written)."""
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1

    def __enter__(self) -> ResultsTable:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def read_rows(path: str | os.PathLike[str]) -> list[dict[str, Any]]:
    """Read a results table (CSV or Parquet) into typed rows.

    Raises
    ------
    MdleError
        The file is missing, unreadable or not a results table.
    """
    p = Path(path)
    if p.is_dir():
        p = p / "results.csv"
    if not p.is_file():
        raise MdleError(f"no results table at {path} (give the sweep's --out folder, its "
                        "results.csv or results.parquet)")
    if p.suffix == ".parquet":
        try:
            import pyarrow.parquet as pq
        except ImportError:
            raise MdleError(f"{p}: reading Parquet needs pyarrow (pip install "
                            "'mdle[parquet]'); or give results.csv") from None
        return list(pq.read_table(p).to_pylist())
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise MdleError(f"cannot read {p}: {err}") from None
    reader = csv.reader(io.StringIO(text))
    header = next(reader, None)
    if not header or "key" not in header or "status" not in header:
        raise MdleError(f"{p}: not a results table of `mdle sweep` (no key and status "
                        "columns)")
    return [{h: _typed(h, v) for h, v in zip(header, row, strict=True)}
            for row in reader if len(row) == len(header)]


def _arrow_type(pa: Any, values: list[Any]) -> Any:
    """Pick an Arrow type for a column read as the values looked."""
    seen = {type(v) for v in values if v is not None}
    if seen <= {bool} and seen:
        return pa.bool_()
    if seen <= {int} and seen:
        return pa.int64()
    if seen <= {int, float} and seen:
        return pa.float64()
    return pa.string()


def write_parquet(csv_path: str | os.PathLike[str], out: str | os.PathLike[str]) -> bool:
    """Write a typed Parquet copy of a results CSV; False when pyarrow is not installed."""
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return False
    rows = read_rows(csv_path)
    header = next(csv.reader(io.StringIO(Path(csv_path).read_text(encoding="utf-8"))))
    kinds = {"text": pa.string(), "int": pa.int64(), "bool": pa.bool_(), "float": pa.float64()}
    schema = pa.schema([(c, kinds[column_type(c)] if column_type(c) in kinds
                         else _arrow_type(pa, [r.get(c) for r in rows])) for c in header])
    for field in schema:
        if field.type == pa.string():   # a mixed column: keep its values as text
            for r in rows:
                if r.get(field.name) is not None and not isinstance(r[field.name], str):
                    r[field.name] = _cell(r[field.name])
    table = pa.Table.from_pylist(rows, schema=schema)
    tmp = Path(str(out) + ".tmp")
    pq.write_table(table, tmp)
    os.replace(tmp, out)
    return True
