"""``mdle run --record``: an observer that writes the run as ROS 2 messages into MCAP.

Ticks are encoded in batches (:data:`BATCH_TICKS`, or :data:`BATCH_AGE` of wall time):
a batch's numbers, scans and records are converted and filled with numpy a column at a
time (:mod:`mdle.record.tick`), and the batch runs with its code and data warm in the CPU's
caches, where one tick at a time would find them evicted by the simulation every tick.
An event flushes the batch first, so the file holds the messages in the trace's order.
A kill loses at most the batch waiting and the open chunk (``docs/trace.md``).

It makes the same records the trace writer makes (:mod:`mdle.record.trace`: the same sample
line, event and end records, ``laser`` and ``scan`` records) and hands them to a
:class:`~mdle.record.topics.RosRecording`, so a recording and the export of the run's trace
hold the same messages. Whatever ends the run (its end, an error, Ctrl-C, SIGTERM), the
scheduler calls :meth:`McapRecorder.on_end` and the file is finished with its summary
and index; :meth:`McapRecorder.close` does it if the run never ended.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Mapping
from itertools import chain
from operator import itemgetter
from typing import TYPE_CHECKING, Any

import numpy as np

from mdle.core.errors import Diagnostic, MdleError
from mdle.record.rounding import round9
from mdle.record.tick import Ticks, times_ns
from mdle.record.topics import RosRecording, sample_values
from mdle.record.trace import (
    LaserRecords,
    SampleFormat,
    dumps,
    end_record,
    event_record,
    laser_mount,
    laser_timing,
    start_record,
)
from mdle.runtime.events import Event, RunResult, Sample

if TYPE_CHECKING:
    from mdle.runtime.scheduler import Scheduler

__all__ = ["BATCH_AGE", "BATCH_TICKS", "LIVE_BATCH_AGE", "McapRecorder", "RecordingError"]

#: Ticks held before they are encoded together.
BATCH_TICKS = 32

#: Longest wall time (s) a tick waits to be encoded (a paced run, hardware at 10 Hz).
BATCH_AGE = 0.5

#: The same with a live view (``--foxglove``): what it shows lags the robot this much at most.
LIVE_BATCH_AGE = 0.1


class RecordingError(MdleError):
    """The recording cannot be written (the disk is full, the folder is not empty...)."""


class McapRecorder:
    """Record a run into an MCAP file (or a rosbag2 folder) as it goes.

    Parameters
    ----------
    target : str or path-like or None
        The ``.mcap`` file, or with ``rosbag`` the folder; None for a live view alone.
    header : mapping
        The run's trace header (what ``mdle run`` writes).
    world : sim.World or None
        The simulated world, for ``/map``.
    rosbag : bool
        Write a rosbag2 folder.
    batch_ticks, batch_age : int, float
        Ticks encoded together, and the longest wall time (s) one waits.
    clock : callable
        Wall clock (injectable for tests).
    **options
        ``chunk_size``, ``max_age``, ``compression`` for the MCAP file (``compression``
        ``""``, none, unless given: ``"lz4"``); ``live`` (live views, batches of
        :data:`LIVE_BATCH_AGE` at most), ``outlet`` and ``robot`` (a team's robot in a
        shared file) as :class:`~mdle.record.topics.RosRecording` takes them.

    Raises
    ------
    RecordingError
        The file cannot be created.
    """

    def __init__(self, target: str | os.PathLike[str] | None, header: Mapping[str, Any],
                 world: Any = None, *, rosbag: bool = False, batch_ticks: int = BATCH_TICKS,
                 batch_age: float = BATCH_AGE, clock: Callable[[], float] = time.monotonic,
                 **options: Any) -> None:
        self.target = os.fspath(target) if target is not None else "the live view"
        # chunks not compressed unless asked: the cheapest to write while a run goes
        options.setdefault("compression", "")
        if options.get("live"):  # a live view: ticks reach it within a tenth of a second
            batch_age = min(batch_age, LIVE_BATCH_AGE)
        try:
            self.recording = RosRecording(target, header, world, rosbag=rosbag, **options)
        except OSError as exc:
            raise RecordingError(Diagnostic(None, f"cannot write the recording "
                                                  f"`{self.target}`: {exc.strerror}")) from None
        self._format = SampleFormat()
        self._laser = LaserRecords()
        self._batch: list[Sample] = []
        self._batch_ticks = max(1, int(batch_ticks))
        self._batch_age = float(batch_age)
        self._clock = clock
        self._flush_at = clock() + self._batch_age
        #: Why the recording failed (None while it is fine).
        self.error: str | None = None

    def _fail(self, exc: OSError) -> RecordingError:
        self.error = f"cannot write the recording `{self.target}`: {exc.strerror or exc}"
        self.recording.abandon()
        return RecordingError(Diagnostic(None, self.error))

    # ------------------------------------------------------------------ observer hooks

    def on_start(self, scheduler: "Scheduler") -> None:
        """Take the ladar mount and timing, and the ``start`` record."""
        self._laser.mount = laser_mount(scheduler.backend)
        self._laser.timing = laser_timing(scheduler.backend, scheduler.rate)
        self.recording.start(dumps(start_record(scheduler)))

    def on_event(self, event: Event) -> None:
        """Publish the ticks waiting, then the event on ``/mdle/events``."""
        if self.error is not None:
            return
        try:
            self._flush()
            self.recording.event(event.time, dumps(event_record(event)))
        except OSError as exc:
            raise self._fail(exc) from None

    def on_tick(self, sample: Sample) -> None:
        """Take a tick; publish the batch once it is full or old enough."""
        if self.error is not None:
            return
        batch = self._batch
        batch.append(sample)
        if len(batch) >= self._batch_ticks or self._clock() >= self._flush_at:
            try:
                self._flush()
            except OSError as exc:
                raise self._fail(exc) from None

    def _flush(self) -> None:
        """Publish the ticks waiting: new scans, odometry, transforms, command, state.

        The batch goes to the file as one :class:`~mdle.record.tick.Ticks`: its scans'
        ranges turned to float32 (+inf without a return) in one numpy operation, its
        numbers in one array. A new beam geometry publishes the ticks before it first.
        Raises OSError when the file cannot be written.
        """
        batch = self._batch
        self._flush_at = self._clock() + self._batch_age
        if not batch:
            return
        self._batch = []
        laser, recording = self._laser, self.recording
        line_and_numbers = self._format.line_and_numbers
        names = recording.diag_names
        none = (math.nan,) * len(names)  # no law recording diagnostics this tick
        every = itemgetter(*names) if len(names) > 1 else None  # a law recording them all
        times: list[float] = []
        lines: list[str] = []
        values: list[tuple[float, ...]] = []
        scans: list[tuple[int, Any]] = []  # (the tick it comes before, the scan)
        paths: list[str] = []
        diags: list[tuple[Any, ...]] = []
        for sample in batch:
            scan = sample.scan
            if scan is not None and scan is not laser.last:
                record = laser.changed(scan)
                if record is not None:
                    _publish(recording, times, lines, values, scans, paths, diags)
                    times, lines, values, scans, paths, diags = [], [], [], [], [], []
                    recording.laser(sample.time, record)
                scans.append((len(times), scan))
            line, numbers = line_and_numbers(sample)
            times.append(sample.time)
            lines.append(line)
            values.append(numbers if numbers is not None and len(numbers) == 10
                          else sample_values(sample, numbers))
            paths.append(sample.path)
            diag = sample.diag
            if not diag:
                diags.append(none)
            elif every is not None and len(diag) == len(names):
                try:
                    diags.append(every(diag))
                except KeyError:  # other names: those it has
                    diags.append(tuple([diag.get(n, math.nan) for n in names]))
            else:
                diags.append(tuple([diag.get(n, math.nan) for n in names]))
        _publish(recording, times, lines, values, scans, paths, diags)

    def on_end(self, result: RunResult) -> None:
        """Publish the ``end`` record and finish the file (never raises: the run is over)."""
        if self.error is None:
            try:
                self._flush()
                self.recording.end(result.termination.time, dumps(end_record(result)))
            except OSError as exc:
                self._fail(exc)
        self.close()

    def close(self) -> None:
        """Finish the file (summary, index, footer) if it is not yet; safe to repeat."""
        if self.recording.finished:
            return
        try:
            if self.error is None:
                self._flush()
            self.recording.finish()
        except OSError as exc:
            self._fail(exc)


def _publish(recording: RosRecording, times: list[float], lines: list[str],
             values: list[tuple[float, ...]], scans: list[tuple[int, Any]],
             paths: list[str], diags: list[tuple[Any, ...]]) -> None:
    """Publish ticks and scans taken from samples (nothing when there are none)."""
    if not (times or scans):
        return
    # the numbers as the trace's lines give them to a reader
    k = len(times)
    numbers = np.fromiter(chain.from_iterable(values), np.float64, 10 * k).reshape(k, 10)
    ticks = Ticks(times_ns(times), round9(numbers), lines)
    ticks.paths = paths
    try:  # numbers and flags (bools) as the law recorded them
        diag = np.array(diags, np.float64).reshape(k, len(recording.diag_names))
    except (TypeError, ValueError):  # anything else: NaN, as the export reads it
        diag = np.array([recording.diagnostics(dict(zip(recording.diag_names, d,
                                                        strict=True))) for d in diags])
    ticks.diag = round9(diag.reshape(k, len(recording.diag_names)))
    if scans:
        m = len(scans)
        ticks.scan_at = [at for at, _ in scans]
        ticks.scan_ns = ticks.ns[ticks.scan_at]  # a scan is seen at the tick it comes with
        ticks.stamps = times_ns([s.stamp for _, s in scans])
        if len({len(s.ranges) for _, s in scans}) != 1:
            raise ValueError("scans of one beam geometry with different numbers of beams")
        # REP-117: a beam without a return is +inf
        valid = np.concatenate([s.valid for _, s in scans]).reshape(m, -1)
        ranges = np.concatenate([s.ranges for _, s in scans]).reshape(m, -1)
        ticks.ranges = np.where(valid, ranges, np.inf).astype("<f4")
    recording.publish(ticks)
