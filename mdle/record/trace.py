"""Run traces as JSON lines: a writer (an observer of the scheduler) and a reader.

Over 500 lines: the trace format in one place, the writer and the reader of the same
records, which must agree field by field (and the laser records both use).

One JSON object per line, each with a ``type``: one ``header`` (program, world, seed,
versions), an ``event`` for every element start and end, a ``sample`` per tick, and an
``end`` record with the run's result. The header, events and the end record reach the file
(the operating system) at once, samples in batches within :data:`FLUSH_PERIOD` of wall
time; the writer flushes whenever the run ends, whatever the cause (error, Ctrl-C,
SIGTERM), so only a process killed outright (SIGKILL, a crash of the interpreter
itself) can lose samples, at most the last ``flush_period`` seconds of them. The file
only ever holds whole records: a write that fails (disk full, file size limit) or is cut
by a signal is taken back to the end of the last whole record, the writer reports a
:class:`TraceWriteError` (which ends the run), and it still tries to write the end
record. The reader accepts a trace whose last line was cut short. Non-finite numbers (NaN, inf) are
written as ``null`` so the file is strict JSON. The schema is documented in ``docs/trace.md``.
"""

from __future__ import annotations

import base64
import json
import math
import os
import platform
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from importlib import metadata
from math import isfinite
from typing import IO, TYPE_CHECKING, Any, NamedTuple

from mdle.core.backend import Scan
from mdle.core.errors import Diagnostic, MdleError, Span
from mdle.core.userfile import UserFileError, open_user_file, os_reason
from mdle.runtime.events import Collision, Event, RunResult, Sample

if TYPE_CHECKING:
    import numpy as np

    from mdle.runtime.scheduler import Scheduler

__all__ = ["TRACE_FORMAT", "TRACE_VERSION", "FLUSH_PERIOD", "TraceWriter", "Trace", "TraceError",
           "TraceWriteError", "SampleFormat", "LaserRecords", "read_jsonl_trace", "versions",
           "decode_ranges", "dumps", "start_record", "event_record", "end_record", "scan_ranges",
           "encode_ranges", "LaserMount", "LaserTiming", "laser_mount", "laser_timing"]

TRACE_FORMAT = "mdle-trace"
TRACE_VERSION = 1

#: Longest wall time (s) a sample record waits in memory before it is written out. A
#: paced run (hardware at 10 Hz, ``--realtime``) ticks slower than this, so every tick is
#: written as it happens; a fast simulated run writes in batches of many ticks, one
#: ``write(2)`` per batch instead of one per record (about 2 us each).
FLUSH_PERIOD = 0.02


class TraceError(MdleError):
    """A trace file cannot be read: not JSON lines, not an mdle trace, or a newer version."""


class TraceWriteError(MdleError):
    """A trace file cannot be written any more (disk full, I/O error, file size limit).

    ``path`` is the file, ``records`` how many whole records were written before.
    """

    def __init__(self, path: str, reason: str, records: int) -> None:
        super().__init__(Diagnostic(None, f"cannot write the trace `{path}`: {reason} "
                                          f"({records} whole records written before)"))
        self.path = path
        self.records = records


def versions() -> dict[str, str]:
    """Versions of mdle, Python and the numeric libraries, for the trace header."""
    out = {"python": platform.python_version()}
    for dist in ("mdle", "numpy", "shapely"):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            pass
    return out


def _clean(value: Any) -> Any:
    """JSON-safe copy: non-finite floats become None, tuples become lists."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Mapping):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if hasattr(value, "item"):  # numpy scalars
        return _clean(value.item())
    return value


def dumps(record: Mapping[str, Any]) -> str:
    """Return a record as one line of strict JSON (non-finite numbers as null)."""
    return _dumps(record)


def _dumps(record: Mapping[str, Any]) -> str:
    return json.dumps(_clean(record), allow_nan=False, separators=(",", ":"))


def start_record(scheduler: "Scheduler") -> dict[str, Any]:
    """Return the ``start`` record of a run."""
    return {"type": "start", "element": scheduler.element.label, "rate": scheduler.rate,
            "until": scheduler.until}


def event_record(event: Event) -> dict[str, Any]:
    """Return the ``event`` record of an element's start or end."""
    p = event.pose
    record = {"type": "event", "t": event.time, "kind": event.kind.value, "path": event.path,
              "level": event.level, "element": event.element,
              "cause": event.cause.value if event.cause is not None else None,
              "x": p.x, "y": p.y, "theta": p.theta}
    if event.fired is not None:  # an end by interrupt: which of its conditions held
        record["fired"] = event.fired
    return record


def collision_record(c: Collision) -> dict[str, Any]:
    """Return the ``collision`` record of a contact."""
    return {"type": "collision", "t": c.time, "obstacle": c.obstacle, "kind": c.kind,
            "index": c.index, "x": c.x, "y": c.y, "path": c.path}


def end_record(result: RunResult) -> dict[str, Any]:
    """Return the ``end`` record of a run."""
    t = result.termination
    return {
        "type": "end", "path": t.path, "cause": t.cause.value, "t": t.time,
        "ticks": result.ticks, "duration": result.duration, "distance": result.distance,
        "min_clearance": result.min_clearance, "collided": result.collided,
        "fault": result.fault, "reason": result.reason, "max_lateness": result.max_lateness,
        "collision": None if result.collision is None else {
            k: v for k, v in collision_record(result.collision).items() if k != "type"},
        "terminations": [{"path": x.path, "level": x.level, "cause": x.cause.value,
                          "t": x.time, **({"fired": x.fired} if x.fired else {})}
                         for x in result.terminations]}


#: Bytes kept free beside a trace for its end record (a file removed when the end record
#: is written): a disk that fills during a run, by the trace or by anything else, still
#: takes the record that says how the run ended.
RESERVE_BYTES = 16 * 1024


def _make_reserve(path: str) -> str | None:
    """Create the reserve file beside ``path``; None when it cannot be made (no matter)."""
    folder, name = os.path.split(os.path.abspath(path))
    reserve = os.path.join(folder, f".{name}.reserve")
    try:
        fd = os.open(reserve, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except OSError:  # already there (another run's), or no room: run without one
        return None
    try:
        os.write(fd, bytes(RESERVE_BYTES))
    except OSError:
        os.close(fd)
        _drop_reserve(reserve)
        return None
    os.close(fd)
    return reserve


def _drop_reserve(reserve: str | None) -> None:
    if reserve is not None:
        try:
            os.unlink(reserve)
        except OSError:
            pass


class TraceWriter:
    """Write a run's trace as JSON lines, flushing events at once and samples in batches.

    Parameters
    ----------
    path : str or path-like
        The file to create (overwritten).
    header : mapping
        What the run is: ``program`` (file, element), ``world``, ``seed``, ``rate``,
        ``backend``... Merged into the header record after ``format``, ``version`` and
        ``versions``.
    flush_period : float
        Longest wall time (s) a sample waits in memory before it is written; 0 writes
        every record as it comes. Events, the header and the end record are always
        written at once.
    clock : callable
        Wall clock for the flush period, s (injectable for tests).

    The writer is an observer: pass it to :func:`mdle.runtime.run` or a
    :class:`~mdle.runtime.Scheduler`. :meth:`close` is called by ``on_end``; call it
    yourself if the run never started.

    Writing is all or nothing per batch of whole records: when a write fails the file is
    cut back to its last whole record, :attr:`error` keeps the :class:`TraceWriteError`,
    which the hook that met it raises (ending the run); later records are dropped, except
    that ``on_end`` tries once more to write the end record. ``on_end`` and
    :meth:`close` never raise; read :attr:`error` after the run.

    Raises
    ------
    OSError
        The file cannot be created.
    TraceWriteError
        The header cannot be written (the file is left empty).
    """

    def __init__(self, path: str | os.PathLike[str], header: Mapping[str, Any] | None = None,
                 *, flush_period: float = FLUSH_PERIOD,
                 clock: Callable[[], float] = time.monotonic) -> None:
        if not flush_period >= 0.0:
            raise ValueError(f"flush_period must be >= 0 s, got {flush_period!r}")
        self.path = os.fspath(path)
        # unbuffered file, batching of our own: every write(2) carries whole lines only,
        # so a trace cut off by a kill still parses up to its last complete record
        self._file: IO[bytes] | None = open(self.path, "wb", buffering=0)
        self._pending: list[str] = []
        self._period = float(flush_period)
        self._clock = clock
        self._flush_at = 0.0  # clock() by which queued samples are written
        self._format = SampleFormat()
        self._laser = LaserRecords()
        self._size = 0  # bytes of whole records in the file
        self._records = 0  # whole records in the file
        #: The write failure that stopped this writer (None while all is well).
        self.error: TraceWriteError | None = None
        #: True once the end record is in the file.
        self.ended = False
        self._reserve = _make_reserve(self.path)
        head: dict[str, Any] = {"type": "header", "format": TRACE_FORMAT,
                                "version": TRACE_VERSION, "versions": versions()}
        head.update(header or {})
        try:
            self._write(_dumps(head))
        except BaseException:
            self.close()
            raise

    def _write(self, line: str) -> None:
        """Queue ``line`` and write everything queued now."""
        self._pending.append(line)
        self.flush()

    def flush(self) -> None:
        """Write every queued record to the file now (the run's end does it too).

        Raises
        ------
        TraceWriteError
            The write failed (the file was cut back to its last whole record).
        """
        pending = self._pending
        if pending:
            try:
                if self._file is not None and self.error is None:
                    self._write_whole(("\n".join(pending) + "\n").encode(), len(pending))
            finally:
                # A Ctrl-C is raised at the earliest after write() returns: clearing in
                # `finally` writes no record twice, and drops none that was not written.
                pending.clear()
        self._flush_at = self._clock() + self._period

    def _write_whole(self, data: bytes, records: int) -> None:
        """Write ``data`` (whole records) entirely, or leave the file as it was."""
        assert self._file is not None
        view = memoryview(data)
        done = False
        try:
            while view:  # a regular file takes it all at once, short of a full disk
                n = self._file.write(view)
                if not n:
                    raise OSError(0, "the file takes no more data")
                view = view[n:]
            done = True
        except OSError as exc:
            self._cut_back()
            reason = exc.strerror or str(exc)
            self.error = TraceWriteError(self.path, reason, self._records)
            raise self.error from None
        finally:
            if done:
                self._size += len(data)
                self._records += records
            elif self.error is None:  # cut by a signal between two partial writes
                self._cut_back()

    def _cut_back(self) -> None:
        """Truncate the file to its last whole record (best effort)."""
        if self._file is None:
            return
        try:
            os.ftruncate(self._file.fileno(), self._size)
            self._file.seek(self._size)
        except OSError:
            pass

    # ------------------------------------------------------------------ observer hooks

    def on_start(self, scheduler: "Scheduler") -> None:
        """Record the element and rate the run uses."""
        self._laser.mount = laser_mount(scheduler.backend)
        self._laser.timing = laser_timing(scheduler.backend, scheduler.rate)
        self._write(_dumps(start_record(scheduler)))

    def on_event(self, event: Event) -> None:
        """Write an ``event`` record."""
        self._write(_dumps(event_record(event)))

    def on_tick(self, sample: Sample) -> None:
        """Queue a ``sample`` record; write the queue once it is ``flush_period`` old."""
        if self.error is not None:
            return
        scan = sample.scan
        if scan is not None and scan is not self._laser.last:
            self._pending.extend(self._laser.lines(sample.time, scan))
        self._pending.append(self._format(sample))
        if sample.contact is not None:  # written at once, like an event
            self._write(_dumps(collision_record(sample.contact)))
        if self._clock() >= self._flush_at:
            self.flush()

    def on_message(self, record: Mapping[str, Any]) -> None:
        """Queue a ``message`` record (a team run: what the robot sent or received)."""
        if self.error is None and not self.ended:
            self._pending.append(_dumps(record))

    def on_end(self, result: RunResult) -> None:
        """Write the ``end`` record and close the file (never raises: see :attr:`error`).

        After a write failure the records still queued are dropped and the end record
        alone is tried once more (the failed batch was cut off, which may have made room).
        """
        record = end_record(result)
        if self.error is not None and not record["fault"]:
            record["fault"] = str(self.error)
        line = _dumps(record)
        try:
            if self.error is None:
                try:
                    self._write(line)
                    self.ended = self._file is not None
                except TraceWriteError:
                    pass
            if not self.ended and self._file is not None:
                # the reserve beside the trace makes room on a full disk for this record
                _drop_reserve(self._reserve)
                self._reserve = None
                self._pending.clear()
                self._write_whole((line + "\n").encode(), 1)
                self.ended = True
        except TraceWriteError:
            pass
        finally:
            self.close()

    def close(self) -> None:
        """Flush and close the file (safe to call more than once; never raises).

        A failure to write what was queued is kept in :attr:`error`.
        """
        if self._file is not None:
            try:
                self.flush()
            except TraceWriteError:
                pass
            finally:
                try:
                    self._file.close()
                except OSError:
                    pass
                self._file = None
        self._pending.clear()
        _drop_reserve(getattr(self, "_reserve", None))  # absent if __init__ failed early
        self._reserve = None

    def __del__(self) -> None:
        # a writer dropped without close() still writes what it queued
        try:
            self.close()
        except Exception:  # noqa: BLE001 - nothing can be reported from a finalizer
            pass

    def __enter__(self) -> "TraceWriter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class SampleFormat:
    """Format samples as the trace's ``sample`` records, one JSON line each: the one formatter.

    Every value has one rule, whatever else the sample holds (docs/trace.md, "Numbers"):

    * ``t``: the shortest decimal that reads back as the same double (``repr``);
    * every other number (pose, speeds, command, lateness, scan age, clearance, true pose,
      each diagnostic): 9 significant digits (``%.9g``); a flag among the diagnostics is
      a number, 1 or 0;
    * NaN and the infinities, in any field: ``null`` (strict JSON);
    * a diagnostic that is not a number: its JSON value.

    A line is one ``%`` format of a template made once per shape of line (path, flags,
    which optional fields, diagnostic names). When every number is finite the template
    formats the floats itself; otherwise the same template, made with ``%s`` slots, takes
    each value already written by the rule above. Both come from :meth:`_template`, so
    they give the same text for the same values. The trace writer and the MCAP recorder
    share it: ``/mdle/state`` carries exactly the trace's line, and the recorder's
    numbers are the line's (rounded by :func:`mdle.record.rounding.round9` as a reader of
    the line gets them, NaN where the line has ``null``).
    """

    def __init__(self) -> None:
        self._paths: dict[str, str] = {}
        self._lines: dict[tuple[Any, ...], str] = {}

    def quoted(self, path: str) -> str:
        """Return ``path`` as a JSON string (cached)."""
        q = self._paths.get(path)
        if q is None:
            q = self._paths[path] = json.dumps(path)
        return q

    def __call__(self, sample: Sample) -> str:
        """Return the ``sample`` record of one tick, without a line end."""
        return self.line_and_numbers(sample)[0]

    def line_and_numbers(self, s: Sample) -> tuple[str, tuple[float, ...] | None]:
        """Return the sample line and the numbers it writes with 9 significant digits.

        The numbers are (x, y, theta, v, omega, cmd_v, cmd_omega, true_x, true_y,
        true_theta) as the sample has them (the true pose left out when the sample has
        none; a reader of the line gets each rounded to 9 significant digits), or None
        when a value of the line is not a finite number (the line then writes each value
        by the same rule, and the MCAP recorder takes the numbers from the sample).
        """
        # the fields in Sample's order (mypy checks the names against the class)
        (t, x, y, theta, v, omega, cmd_v, cmd_omega, path, lateness, scan_age, stalled,
         diag, clearance, collided, tx, ty, tth) = s[:18]
        truth = (tx, ty, tth) if tx is not None and ty is not None and tth is not None else None
        key = (path, not stalled, scan_age is None, clearance is None,
               None if collided is None else not collided, truth is not None,
               tuple(diag) if diag else ())
        numbers: tuple[float, ...] = (x, y, theta, v, omega, cmd_v, cmd_omega)
        # every number of the line but the time, in the line's order
        values: list[Any] = [x, y, theta, v, omega, cmd_v, cmd_omega, lateness]
        if scan_age is not None:
            values.append(scan_age)
        if clearance is not None:
            values.append(clearance)
        if truth is not None:
            values += truth
            numbers += truth
        if diag:
            values += diag.values()
        try:
            # a sum of finite numbers is finite (short of overflow, which goes the slow
            # way and gives the same text)
            fast = isfinite(t + sum(values))
        except (TypeError, OverflowError):  # a value that is not a number, or a huge int
            fast = False
        if fast:
            template = self._lines.get(key)
            if template is None:
                template = self._lines[key] = self._template(key, "%r", "%.9g")
            return template % (float(t), *values), numbers
        template = self._lines.get((key, "text"))
        if template is None:
            template = self._lines[(key, "text")] = self._template(key, "%s", "%s")
        return template % (_time_text(t), *[_number(v) for v in values]), None

    def _template(self, key: tuple[Any, ...], time: str, number: str) -> str:
        """Make the ``%`` template of one shape of sample line.

        ``time`` is the slot of ``t``, ``number`` the slot of every other number.
        """
        path, running, no_age, no_clearance, not_collided, has_truth, names = key
        n = number
        parts = ['{"type":"sample","t":', time, ',"x":', n, ',"y":', n, ',"theta":', n,
                 ',"v":', n, ',"omega":', n, ',"cmd_v":', n, ',"cmd_omega":', n,
                 ',"path":', self.quoted(path).replace("%", "%%"), ',"lateness":', n,
                 ',"stalled":', "false" if running else "true"]
        if not no_age:
            parts += [',"scan_age":', n]
        if not no_clearance:
            parts += [',"clearance":', n]
        if not_collided is not None:
            parts.append(',"collided":false' if not_collided else ',"collided":true')
        if has_truth:
            parts += [',"true_x":', n, ',"true_y":', n, ',"true_theta":', n]
        if names:
            parts.append(',"diag":{%s}' % ",".join(
                [self.quoted(k).replace("%", "%%") + ":" + n for k in names]))
        return "".join(parts) + "}"


class LaserMount(NamedTuple):
    """The ladar's pose in the robot frame: m, m, rad."""

    x: float = 0.0
    y: float = 0.0
    theta: float = 0.0


class LaserTiming(NamedTuple):
    """Seconds between scans and between two beams of a scan (0: unknown)."""

    scan_time: float = 0.0
    time_increment: float = 0.0


def laser_mount(backend: object) -> LaserMount:
    """Return a backend's ladar pose in the robot frame (x, y, theta), (0, 0, 0) if unknown."""
    mount = getattr(backend, "laser_mount", None)
    try:
        x, y, th = (float(m) for m in mount)  # type: ignore[union-attr]
    except (TypeError, ValueError):
        return LaserMount()
    return LaserMount(x, y, th)


def laser_timing(backend: object, rate: float) -> LaserTiming:
    """Return (scan_time, time_increment) in seconds for a backend's scans, 0 when unknown.

    ``scan_time`` is the time between scans: the backend's ``laser_timing`` period, or
    the tick (``1 / rate``) for a backend that takes a scan at every tick (period 0);
    ``time_increment`` the time between two beams of a scan (0 for a simulated scan,
    taken at one instant).
    """
    timing = getattr(backend, "laser_timing", None)
    try:
        period, increment = (float(v) for v in timing)  # type: ignore[union-attr]
    except (TypeError, ValueError):
        return LaserTiming()
    if not (math.isfinite(period) and period >= 0 and math.isfinite(increment)
            and increment >= 0):
        return LaserTiming()
    if period == 0.0 and rate > 0:
        period = 1.0 / rate
    return LaserTiming(period, increment)


def scan_ranges(scan: "Scan") -> "np.ndarray":
    """Return a scan's ranges as little-endian float32, +inf on invalid beams (REP-117)."""
    import numpy as np

    return np.where(scan.valid, scan.ranges, np.inf).astype("<f4")


def encode_ranges(scan: "Scan") -> str:
    """Return a scan's ranges as base64 little-endian float32, +inf on invalid beams."""
    return base64.b64encode(scan_ranges(scan).tobytes()).decode("ascii")


def decode_ranges(text: str) -> "np.ndarray":
    """Decode a ``scan`` record's ``ranges`` (base64 float32) to a float32 array.

    Raises ValueError when the text is not base64 of whole float32 values.
    """
    import numpy as np

    if not isinstance(text, str):
        raise ValueError("`ranges` must be a base64 string")
    raw = base64.b64decode(text.encode("ascii"), validate=True)
    if len(raw) % 4:
        raise ValueError(f"`ranges` holds {len(raw)} bytes, not whole float32 values")
    return np.frombuffer(raw, dtype="<f4")


class LaserRecords:
    """Make the trace's ``laser`` and ``scan`` records from the scans a run sees.

    A ``laser`` record (the beam geometry in the ``laser`` frame, REP-103) comes before
    the first scan and again whenever the geometry changes; a ``scan`` record for every
    new scan. ``mount`` is the ladar's pose in the robot frame.
    """

    def __init__(self, mount: LaserMount | None = None,
                 timing: LaserTiming | None = None) -> None:
        self.mount = mount if mount is not None else LaserMount()
        self.timing = timing if timing is not None else LaserTiming()
        self.last: Scan | None = None
        self._geometry: tuple[Any, ...] | None = None
        self._bearings: Any = None
        self._max_range = math.nan

    def laser(self, scan: "Scan") -> dict[str, Any]:
        """Return the ``laser`` record for ``scan``'s beams."""
        b = scan.bearings
        n = len(b)
        a0 = float(b[0]) - self.mount.theta if n else 0.0
        a1 = float(b[-1]) - self.mount.theta if n else 0.0
        return {"type": "laser", "frame": "laser", "mount": list(self.mount),
                "angle_min": a0, "angle_max": a1,
                "angle_increment": (a1 - a0) / (n - 1) if n > 1 else 0.0, "count": n,
                "range_min": 0.0, "range_max": float(scan.max_range),
                "scan_time": self.timing.scan_time,
                "time_increment": self.timing.time_increment}

    def changed(self, scan: "Scan") -> dict[str, Any] | None:
        """Return the ``laser`` record when ``scan``'s geometry is new, else None.

        Also remembers ``scan`` as the last one seen.
        """
        self.last = scan
        b = scan.bearings
        if b is self._bearings and scan.max_range == self._max_range:
            return None  # the same beams as the last scan (the usual case: shared arrays)
        self._bearings, self._max_range = b, scan.max_range
        geometry = (len(b), float(b[0]) if len(b) else 0.0, float(b[-1]) if len(b) else 0.0,
                    float(scan.max_range), self.mount, self.timing)
        if geometry == self._geometry:
            return None
        self._geometry = geometry
        return self.laser(scan)

    def lines(self, t: float, scan: "Scan") -> list[str]:
        """Return the records for a scan first seen at ``t`` as JSON lines (fast)."""
        laser = self.changed(scan)
        stamp = float(scan.stamp)
        if not (isfinite(t) and isfinite(stamp)):
            recs = self.records_after(laser, t, scan)
            return [_dumps(r) for r in recs]
        # base64 needs no escaping: the record is formatted directly
        line = '{"type":"scan","t":%r,"stamp":%r,"ranges":"%s"}' % (
            float(t), stamp, encode_ranges(scan))
        return [_dumps(laser), line] if laser is not None else [line]

    def records_after(self, laser: dict[str, Any] | None, t: float, scan: "Scan"
                      ) -> list[dict[str, Any]]:
        """Return the ``laser`` record (if any) and the ``scan`` record as dicts."""
        scan_rec = {"type": "scan", "t": t, "stamp": scan.stamp, "ranges": encode_ranges(scan)}
        return [laser, scan_rec] if laser is not None else [scan_rec]

    def records(self, t: float, scan: "Scan") -> list[dict[str, Any]]:
        """Return the records for a scan first seen at tick time ``t``."""
        return self.records_after(self.changed(scan), t, scan)


def _number(value: Any) -> str:
    """Write a number with 9 significant digits, NaN and infinities as ``null``.

    Anything that is not a number (a diagnostic may be) as its JSON value.
    """
    try:
        return "%.9g" % value if isfinite(value) else "null"
    except (TypeError, ValueError, OverflowError):  # not a float, or an int beyond one
        return _dumps(value)


def _time_text(value: Any) -> str:
    """Write a tick's time in full (the shortest repr that reads back), ``null`` if not finite."""
    try:
        return repr(float(value)) if isfinite(value) else "null"
    except (TypeError, ValueError, OverflowError):
        return _dumps(value)


@dataclass(frozen=True)
class Trace:
    """A trace read back: the header, the event and sample records, and the end record.

    ``end`` is None when the run was cut off before it could be written (a crash);
    ``truncated`` is True when the last line was incomplete. ``lasers`` and ``scans`` hold
    the ``laser`` and ``scan`` records (:func:`decode_ranges` decodes a scan's ranges);
    ``extra`` any other record (``start``...).
    """

    path: str
    header: Mapping[str, Any]
    events: tuple[Mapping[str, Any], ...]
    samples: tuple[Mapping[str, Any], ...]
    end: Mapping[str, Any] | None = None
    truncated: bool = False
    extra: tuple[Mapping[str, Any], ...] = field(default=())
    lasers: tuple[Mapping[str, Any], ...] = field(default=())
    scans: tuple[Mapping[str, Any], ...] = field(default=())

    def column(self, name: str) -> "np.ndarray":
        """Return a sample field as a float array, shape (len(samples),); missing/null is NaN.

        ``diag.NAME`` reads a control-law diagnostic (``diag.curvature``).
        """
        import numpy as np

        if name.startswith("diag."):
            key = name[5:]
            vals = [(s.get("diag") or {}).get(key) for s in self.samples]
        else:
            vals = [s.get(name) for s in self.samples]
        return np.array([np.nan if v is None else float(v) for v in vals], dtype=float)

    def paths(self) -> list[str]:
        """Return the active path of each sample."""
        return [str(s.get("path", "")) for s in self.samples]

    def collisions(self) -> list[Mapping[str, Any]]:
        """Return the ``collision`` records, in time order."""
        return [r for r in self.extra if r.get("type") == "collision"]

    def diag_names(self) -> list[str]:
        """Every diagnostic name any sample carries, sorted."""
        names: set[str] = set()
        for s in self.samples:
            names.update(s.get("diag") or ())
        return sorted(names)


def _records(path: str) -> Iterator[tuple[int, bytes]]:
    try:
        raw = open_user_file(path)
    except UserFileError as err:
        raise TraceError(Diagnostic(None, f"cannot read trace `{path}`: {err.reason}")) \
            from None
    with raw as f:
        try:
            for n, line in enumerate(f, 1):
                yield n, line
        except OSError as err:
            raise TraceError(Diagnostic(None, f"cannot read trace `{path}`: "
                                              f"{os_reason(err)}")) from None


def _decode(line: bytes) -> tuple[str | None, str]:
    """Return the line as text, or None and what is wrong with it."""
    try:
        return line.decode("utf-8"), ""
    except UnicodeDecodeError as exc:
        return None, (f"not UTF-8 text (byte 0x{line[exc.start]:02x} at column "
                      f"{exc.start + 1})")


def _parse(text: str) -> tuple[Any, str]:
    """Return the JSON value of a line, or None and what is wrong with it."""
    try:
        return json.loads(text), ""
    except json.JSONDecodeError as exc:
        return None, f"not JSON ({exc.msg})"
    except RecursionError:
        return None, "not a trace record (JSON nested too deeply)"


#: Fields mdle reads from each kind of record, by the JSON type they must have (a
#: missing field or null is always accepted: readers treat it as unknown).
_NUMBERS: dict[str, tuple[str, ...]] = {
    "sample": ("t", "x", "y", "theta", "v", "omega", "cmd_v", "cmd_omega", "lateness",
               "scan_age", "clearance", "true_x", "true_y", "true_theta"),
    "event": ("t", "x", "y", "theta"),
    "end": ("t", "duration", "distance", "min_clearance", "max_lateness"),
    "scan": ("t", "stamp"),
    "laser": ("angle_min", "angle_max", "angle_increment", "range_min", "range_max",
              "scan_time", "time_increment"),
    "header": ("rate", "until"),
}
_STRINGS: dict[str, tuple[str, ...]] = {
    "sample": ("path",), "event": ("kind", "path", "cause", "element"),
    "end": ("path", "cause", "fault", "reason"), "scan": ("ranges",),
}
_INTEGERS: dict[str, tuple[str, ...]] = {"event": ("level",), "end": ("ticks",),
                                         "header": ("seed",)}
_BOOLEANS: dict[str, tuple[str, ...]] = {"sample": ("stalled", "collided"),
                                         "end": ("collided",)}
_OBJECTS: dict[str, tuple[str, ...]] = {"sample": ("diag",),
                                        "header": ("versions",)}
_HEADER_STRINGS = (("program", ("file", "element", "entry")), ("world", ("name", "spec")))


def _type_error(rec: Mapping[str, Any], kind: str) -> str | None:
    """Return what is wrong with the types of a record's fields (None: nothing)."""
    for key in _NUMBERS.get(kind, ()):
        v = rec.get(key)
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float))):
            return _wrong(kind, key, "a number", v)
    for key in _INTEGERS.get(kind, ()):
        v = rec.get(key)
        if v is not None and (isinstance(v, bool) or not isinstance(v, int)):
            return _wrong(kind, key, "a whole number", v)
    for key in _STRINGS.get(kind, ()):
        v = rec.get(key)
        if v is not None and not isinstance(v, str):
            return _wrong(kind, key, "a string", v)
    for key in _BOOLEANS.get(kind, ()):
        v = rec.get(key)
        if v is not None and not isinstance(v, bool):
            return _wrong(kind, key, "true or false", v)
    for key in _OBJECTS.get(kind, ()):
        v = rec.get(key)
        if v is not None and not isinstance(v, dict):
            return _wrong(kind, key, "an object", v)
    if kind == "sample" and rec.get("diag"):
        for name, v in rec["diag"].items():
            if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float))):
                return _wrong(kind, f"diag.{name}", "a number", v)
    if kind == "end" and not isinstance(rec.get("terminations", []), list):
        return _wrong(kind, "terminations", "a list", rec["terminations"])
    if kind == "header":
        for part, keys in _HEADER_STRINGS:
            sub = rec.get(part)
            if not isinstance(sub, dict):  # a free-form note: readers ignore it
                continue
            for key in keys:
                v = sub.get(key)
                if v is not None and not isinstance(v, str):
                    return _wrong(kind, f"{part}.{key}", "a string", v)
    return None


def _wrong(kind: str, key: str, what: str, value: Any) -> str:
    shown = json.dumps(value)
    if len(shown) > 40:
        shown = shown[:37] + "..."
    return f"`{key}` of the {kind} record must be {what}, not {shown}"


def read_jsonl_trace(path: str | os.PathLike[str]) -> Trace:
    """Read a trace written by :class:`TraceWriter` (JSON lines).

    :func:`mdle.record.load.read_trace` reads any recorded run, MCAP files too.

    Raises
    ------
    TraceError
        The file is missing, is not an mdle trace, has a newer version, or has a bad line
        other than a cut-off last line (the message names the file and line).
    """
    path = os.fspath(path)
    header: dict[str, Any] | None = None
    events: list[Mapping[str, Any]] = []
    samples: list[Mapping[str, Any]] = []
    extra: list[Mapping[str, Any]] = []
    scans: list[Mapping[str, Any]] = []
    lasers: list[Mapping[str, Any]] = []
    end: Mapping[str, Any] | None = None
    truncated = False
    bad: tuple[int, str] | None = None
    try:
        for n, raw_line in _records(path):
            if bad is not None:  # a bad line that was not the last one
                raise _error(path, bad[0], bad[1])
            line, problem = _decode(raw_line)
            rec = None
            if line is not None:
                if not line.strip():
                    continue
                rec, problem = _parse(line)
            if problem:
                if raw_line.endswith(b"\n"):
                    raise _error(path, n, problem)
                bad = (n, problem)  # a last line cut short: accepted, marked truncated
                continue
            if not isinstance(rec, dict) or not isinstance(rec.get("type"), str):
                raise _error(path, n, "a record must be a JSON object with a `type`")
            kind = rec["type"]
            if header is None:
                if kind != "header" or rec.get("format") != TRACE_FORMAT:
                    raise _error(path, n, f"not an mdle trace (the first record must be a "
                                          f"`header` with format `{TRACE_FORMAT}`)")
                version = rec.get("version", 0)
                if isinstance(version, bool) or not isinstance(version, int):
                    raise _error(path, n, _wrong("header", "version", "a whole number",
                                                 version))
                if version > TRACE_VERSION:
                    raise _error(path, n, f"trace version {rec['version']} is newer than "
                                          f"this mdle reads ({TRACE_VERSION})")
            wrong = _type_error(rec, kind)
            if wrong is not None:
                raise _error(path, n, wrong)
            if header is None:
                header = rec
            elif kind == "sample":
                samples.append(rec)
            elif kind == "event":
                events.append(rec)
            elif kind == "end":
                end = rec
            elif kind == "scan":
                scans.append(rec)
            elif kind == "laser":
                lasers.append(rec)
            else:
                extra.append(rec)
    except OSError as exc:
        raise TraceError(Diagnostic(None, f"cannot read trace `{path}`: {exc.strerror}")) \
            from None
    if bad is not None:
        truncated = True
    if header is None:
        raise _error(path, 1, "empty file: not an mdle trace")
    return Trace(path, header, tuple(events), tuple(samples), end, truncated, tuple(extra),
                 tuple(lasers), tuple(scans))


def _error(path: str, line: int, message: str) -> TraceError:
    return TraceError(Diagnostic(Span(path, line, 1, line, 1), message))
