"""``mdle export``: a JSON lines trace to an MCAP file (or a rosbag2 folder).

The trace is read line by line and each record handed to a
:class:`~mdle.record.topics.RosRecording`, exactly as the live recorder hands them over, so
the export of a run's trace holds the messages ``mdle run --record`` writes. A trace
that is cut short or damaged is exported up to the last good record: the file is still
finished (summary and index), and the report says at which line the export stopped and
why.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from mdle.core.errors import Diagnostic, MdleError, Span
from mdle.core.userfile import UserFileError, open_user_file, os_reason, replacing
from mdle.record.topics import RosRecording
from mdle.record.trace import TRACE_FORMAT, TRACE_VERSION, TraceError, decode_ranges

__all__ = ["ExportReport", "export_trace"]


@dataclass(frozen=True)
class ExportReport:
    """What an export wrote.

    ``path`` the MCAP file, ``counts`` messages per topic, ``lines`` trace lines read,
    ``stopped`` (line, reason) when a bad record ended the export before the end of the
    file, ``truncated`` True when the last line was cut short (a run killed while
    writing), ``ended`` whether the trace had its ``end`` record, ``span`` the first and
    last time (s), ``warnings`` anything else worth saying (a world that did not load).
    """

    path: str
    counts: Mapping[str, int]
    lines: int
    stopped: tuple[int, str] | None = None
    truncated: bool = False
    ended: bool = False
    span: tuple[float, float] | None = None
    warnings: tuple[str, ...] = field(default=())

    @property
    def messages(self) -> int:
        """Messages written."""
        return sum(self.counts.values())


class _BadRecord(ValueError):
    """A record that cannot be exported (the reason is the message)."""


def _number(rec: Mapping[str, Any], key: str) -> float:
    value = rec[key] if key in rec else _missing(key)
    if value is None:
        return math.nan
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _BadRecord(f"`{key}` must be a number, got {json.dumps(value)}")
    return float(value)


def _missing(key: str) -> Any:
    raise _BadRecord(f"the record has no `{key}`")


#: Latest time a trace may hold (s): ROS stamps are nanoseconds in 64 bits (584 years).
MAX_TIME = 1e9


def _time(rec: Mapping[str, Any], key: str = "t") -> float:
    t = _number(rec, key)
    if not math.isfinite(t):
        raise _BadRecord(f"`{key}` must be a finite number of seconds")
    if abs(t) > MAX_TIME:
        raise _BadRecord(f"`{key}` is {t:g} s; a ROS time holds at most {MAX_TIME:g} s")
    return t


def _loads(text: str) -> Any:
    """Parse one JSON record; a record nested too deeply is a bad record, not a crash."""
    try:
        return json.loads(text)
    except RecursionError:
        raise _BadRecord("not a trace record (JSON nested too deeply)") from None


def _header(path: str, first: bytes) -> dict[str, Any]:
    try:
        rec = _loads(first.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, _BadRecord):
        rec = None
    if not isinstance(rec, dict) or rec.get("type") != "header" \
            or rec.get("format") != TRACE_FORMAT:
        raise TraceError(Diagnostic(Span(path, 1, 1, 1, 1), "not an mdle trace (the first "
                                    f"record must be a `header` with format `{TRACE_FORMAT}`)"))
    version = rec.get("version", 0)
    if not isinstance(version, int) or isinstance(version, bool) or version > TRACE_VERSION:
        raise TraceError(Diagnostic(Span(path, 1, 1, 1, 1), f"trace version {version!r} is not "
                                    f"one this mdle reads ({TRACE_VERSION} or older)"))
    return rec


def _world(header: Mapping[str, Any], world: Any) -> tuple[Any, list[str]]:
    """Return the world to draw on ``/map`` and warnings."""
    from mdle import sim

    if world is not None and not isinstance(world, (str, os.PathLike)):
        return world, []
    spec = world
    if spec is None:
        w = header.get("world")
        spec = w.get("spec") if isinstance(w, dict) else None
        if not isinstance(spec, str) or not spec:
            return None, []
    try:
        return sim.load_world(spec), []
    except MdleError as exc:
        if world is not None:
            raise
        return None, [f"the world `{spec}` the trace names does not load ({exc}); "
                      "no /map written (give it with --world)"]


def export_trace(trace_path: str | os.PathLike[str], target: str | os.PathLike[str], *,
                 rosbag: bool = False, world: Any = None) -> ExportReport:
    """Write the run in a trace as an MCAP file (or, with ``rosbag``, a rosbag2 folder).

    ``world`` (a :class:`sim.World`, a name or a file) overrides the world the trace
    header names, for ``/map``.

    Raises
    ------
    TraceError
        The file cannot be read or does not start with an mdle trace header (nothing is
        written).
    MdleError
        ``world`` does not load; the output cannot be created.
    """
    path = os.fspath(trace_path)
    try:  # a regular file only (a FIFO or /dev/zero is refused), of any size: it streams
        f = open_user_file(path, limit=_NO_LIMIT)
    except UserFileError as exc:
        raise TraceError(Diagnostic(None, f"cannot read trace `{path}`: {exc.reason}")) \
            from None
    with f:
        first = _read_line(f, path)
        header = _header(path, first)
        world_obj, warnings = _world(header, world)
        if rosbag:
            return _export(f, path, target, header, world_obj, warnings, True)
        try:
            with replacing(target) as part:  # the old file stays until the new one is whole
                report = _export(f, path, part, header, world_obj, warnings, False)
        except UserFileError as exc:
            raise MdleError(Diagnostic(None, str(exc))) from None
        return dataclasses.replace(report, path=os.fspath(target))


#: No size limit on a trace exported: it is read a line at a time.
_NO_LIMIT = 2 ** 62


def _read_line(f: Any, path: str) -> bytes:
    try:
        line: bytes = f.readline()
    except OSError as exc:
        raise TraceError(Diagnostic(None, f"cannot read trace `{path}`: "
                                          f"{os_reason(exc)}")) from None
    return line


def _export(f: Any, path: str, target: str | os.PathLike[str], header: Mapping[str, Any],
            world_obj: Any, warnings: list[str], rosbag: bool) -> ExportReport:
    """Export the records after the header line to ``target``; see :func:`export_trace`."""
    try:
        rec = RosRecording(target, header, world_obj, rosbag=rosbag)
    except OSError as exc:
        raise MdleError(Diagnostic(None, f"cannot write `{os.fspath(target)}`: "
                                         f"{os_reason(exc)}")) from None
    state = _Export(rec)
    n = 1
    stopped: tuple[int, str] | None = None
    truncated = False
    try:
        try:
            for n, raw in enumerate(f, 2):  # noqa: B007 - n is the line reached
                try:
                    state.line(raw)
                except _BadRecord as exc:
                    if not raw.endswith(b"\n") and state.cut(raw):
                        truncated = True
                        n -= 1
                    else:
                        stopped = (n, str(exc))
                    break
        finally:
            rec.finish()
    except OSError as exc:  # reading the trace or writing the recording
        raise MdleError(Diagnostic(None, f"cannot export `{path}` to `{os.fspath(target)}`: "
                                         f"{os_reason(exc)}")) from None
    span = rec.out.time_range
    return ExportReport(rec.path or "", rec.counts(), n, stopped, truncated, state.ended,
                        (span[0] / 1e9, span[1] / 1e9) if span else None, tuple(warnings))


class _Export:
    """Hands each record of a trace to the recording."""

    def __init__(self, rec: RosRecording) -> None:
        self.rec = rec
        self.ended = False
        self._laser: dict[str, Any] | None = None
        self._last_t = 0.0

    @staticmethod
    def cut(raw: bytes) -> bool:
        """Return True when ``raw`` (the last line, with no line end) is a cut-off record."""
        try:
            _loads(raw.decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError):
            return True
        except _BadRecord:
            return False
        return False

    def line(self, raw: bytes) -> None:
        """Export one line of the trace; raises _BadRecord when it cannot be."""
        try:
            text = raw.decode("utf-8").rstrip("\r\n")
        except UnicodeDecodeError as exc:
            raise _BadRecord(f"not UTF-8 text (byte {exc.start})") from None
        if not text.strip():
            return
        try:
            rec = _loads(text)
        except json.JSONDecodeError as exc:
            raise _BadRecord(f"not JSON ({exc.msg})") from None
        if not isinstance(rec, dict) or not isinstance(rec.get("type"), str):
            raise _BadRecord("a record must be a JSON object with a `type`")
        try:
            self._record(rec, text)
        except (KeyError, TypeError, ValueError, OverflowError) as exc:
            if isinstance(exc, _BadRecord):
                raise
            raise _BadRecord(f"bad `{rec['type']}` record: {exc}") from None

    def _record(self, rec: dict[str, Any], text: str) -> None:
        kind = rec["type"]
        r = self.rec
        if kind == "sample":
            t = _time(rec)
            truth = None
            if all(rec.get(k) is not None for k in ("true_x", "true_y", "true_theta")):
                truth = (_number(rec, "true_x"), _number(rec, "true_y"),
                         _number(rec, "true_theta"))
            r.sample(text, t, _number(rec, "x"), _number(rec, "y"), _number(rec, "theta"),
                     _number(rec, "v"), _number(rec, "omega"), _number(rec, "cmd_v"),
                     _number(rec, "cmd_omega"), truth, path=str(rec.get("path") or ""),
                     diag=rec.get("diag") if isinstance(rec.get("diag"), dict) else None)
            self._last_t = t
        elif kind == "scan":
            t = _time(rec)
            ranges = decode_ranges(rec["ranges"])
            if self._laser is not None:
                r.laser(t, self._laser)
                self._laser = None
            r.scan(t, _time(rec, "stamp"), ranges)
        elif kind == "laser":
            for key in ("angle_min", "angle_max", "angle_increment", "range_max"):
                if not math.isfinite(_number(rec, key)):
                    raise _BadRecord(f"`{key}` must be finite")
            count = rec.get("count")
            if isinstance(count, bool) or not isinstance(count, int) or count < 0:
                raise _BadRecord("`count` must be a whole number of beams")
            self._laser = rec
        elif kind == "start":
            r.start(text)
        elif kind == "end":
            t = _time(rec) if rec.get("t") is not None else self._last_t
            r.end(t, text)
            self.ended = True
        elif kind == "header":
            raise _BadRecord("a second `header` record")
        elif rec.get("t") is not None:  # an event, or a timed record of a newer mdle
            t = _time(rec)
            r.event(t, text)
            self._last_t = t
