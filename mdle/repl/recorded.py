"""A recorded run (a trace or an MCAP recording) back as runtime records, for ``:load``.

:func:`recorded_run` turns a :class:`~mdle.record.trace.Trace` into the samples, events and
result a run in the REPL would have made, scans included, so the REPL's path, map, plot
and trace show it as if it had run in the session.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from mdle.core.backend import Scan
from mdle.core.pose import Pose
from mdle.record.trace import Trace, decode_ranges
from mdle.runtime import Cause, RunResult, Sample, Termination
from mdle.runtime.events import Event, EventKind

__all__ = ["RecordedRun", "recorded_run"]


@dataclass(frozen=True)
class RecordedRun:
    """A run read back: what ran (``label``), its samples, events and result."""

    label: str
    samples: tuple[Sample, ...]
    events: tuple[Event, ...]
    result: RunResult


def _f(value: Any, default: float = math.nan) -> float:
    try:
        return float(value) if value is not None else default
    except (TypeError, ValueError):
        return default


def _cause(text: Any) -> Cause:
    try:
        return Cause(text)
    except ValueError:
        return Cause.STOPPED


def _scans(trace: Trace) -> list[tuple[float, Scan]]:
    """Each scan with the tick time that first saw it, rebuilt as the robot saw it."""
    import numpy as np

    out: list[tuple[float, Scan]] = []
    lasers = list(trace.lasers)
    laser: Mapping[str, Any] | None = lasers[0] if lasers else None
    bearings = None
    for rec in trace.scans:
        if laser is None:
            break
        ranges = decode_ranges(rec["ranges"]).astype(float)
        n = len(ranges)
        if bearings is None or len(bearings) != n:
            mount = laser.get("mount") or (0.0, 0.0, 0.0)
            a0 = _f(laser.get("angle_min"), 0.0) + _f(mount[2], 0.0)
            bearings = a0 + _f(laser.get("angle_increment"), 0.0) * np.arange(n)
            bearings.setflags(write=False)
        max_range = _f(laser.get("range_max"), 10.0)
        valid = np.isfinite(ranges)
        ranges = np.where(valid, ranges, max_range)
        ranges.setflags(write=False)
        valid.setflags(write=False)
        out.append((_f(rec.get("t"), 0.0),
                    Scan(ranges, bearings, valid, _f(rec.get("stamp"), 0.0), max_range)))
    return out


def recorded_run(trace: Trace) -> RecordedRun:
    """Rebuild the run in ``trace``.

    A trace cut short (no ``end`` record) ends as stopped at its last tick.
    """
    scans = _scans(trace)
    samples: list[Sample] = []
    k = -1
    for s in trace.samples:
        t = _f(s.get("t"), 0.0)
        while k + 1 < len(scans) and scans[k + 1][0] <= t + 1e-9:
            k += 1
        truth = s.get("true_x") is not None
        samples.append(Sample(
            t, _f(s.get("x")), _f(s.get("y")), _f(s.get("theta")), _f(s.get("v"), 0.0),
            _f(s.get("omega"), 0.0), _f(s.get("cmd_v"), 0.0), _f(s.get("cmd_omega"), 0.0),
            str(s.get("path", "")), _f(s.get("lateness"), 0.0),
            None if s.get("scan_age") is None else _f(s.get("scan_age")),
            bool(s.get("stalled")),
            {str(key): _f(v) for key, v in (s.get("diag") or {}).items()},
            None if s.get("clearance") is None else _f(s.get("clearance")),
            None if s.get("collided") is None else bool(s.get("collided")),
            _f(s.get("true_x")) if truth else None, _f(s.get("true_y")) if truth else None,
            _f(s.get("true_theta")) if truth else None,
            scans[k][1] if k >= 0 else None))
    events = tuple(
        Event(_f(e.get("t"), 0.0), EventKind(e["kind"]), str(e.get("path", "")),
              int(e.get("level", 0)), str(e.get("element", "")),
              Pose(_f(e.get("x"), 0.0), _f(e.get("y"), 0.0), _f(e.get("theta"), 0.0)),
              None if e.get("cause") is None else _cause(e.get("cause")))
        for e in trace.events if e.get("kind") in ("start", "end"))
    label = str((trace.header.get("program") or {}).get("element") or "recorded")
    end = trace.end
    last_t = samples[-1].time if samples else 0.0
    first_t = samples[0].time if samples else 0.0
    terms: Sequence[Termination]
    if end is not None:
        terms = tuple(Termination(str(x.get("path", "")), int(x.get("level", 0)),
                                  _cause(x.get("cause")), _f(x.get("t"), last_t))
                      for x in end.get("terminations") or ())
        root = Termination(str(end.get("path", label)), 0, _cause(end.get("cause")),
                           _f(end.get("t"), last_t))
        result = RunResult(root, tuple(terms), events, int(end.get("ticks", len(samples))),
                           _f(end.get("duration"), last_t - first_t),
                           _f(end.get("distance"), 0.0),
                           None if end.get("min_clearance") is None
                           else _f(end.get("min_clearance")),
                           bool(end.get("collided")), end.get("fault"),
                           _f(end.get("max_lateness"), 0.0))
    else:
        root = Termination(label, 0, Cause.STOPPED, last_t)
        clear = [s.clearance for s in samples if s.clearance is not None]
        result = RunResult(root, (root,), events, len(samples), last_t - first_t,
                           sum(math.hypot(b.x - a.x, b.y - a.y)
                               for a, b in zip(samples, samples[1:], strict=False)),
                           min(clear) if clear else None,
                           any(bool(s.collided) for s in samples), None, 0.0)
    return RecordedRun(label, tuple(samples), events, result)
