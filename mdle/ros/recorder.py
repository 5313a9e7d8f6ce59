"""``mdle run --record``: an observer that writes the run as ROS 2 messages into MCAP.

It makes the same records the trace writer makes (:mod:`mdle.trace`: the same sample
line, event and end records, ``laser`` and ``scan`` records) and hands them to a
:class:`~mdle.ros.topics.RosRecording`, so a recording and the export of the run's trace
hold the same messages. Whatever ends the run (its end, an error, Ctrl-C, SIGTERM), the
scheduler calls :meth:`McapRecorder.on_end` and the file is finished with its summary
and index; :meth:`McapRecorder.close` does it if the run never ended.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from mdle.errors import Diagnostic, MdleError
from mdle.ros.topics import RosRecording
from mdle.runtime.events import Event, RunResult, Sample
from mdle.trace import (
    LaserRecords,
    SampleFormat,
    dumps,
    end_record,
    event_record,
    laser_mount,
    laser_timing,
    scan_ranges,
    start_record,
)

if TYPE_CHECKING:
    from mdle.runtime.scheduler import Scheduler

__all__ = ["McapRecorder", "RecordingError"]


class RecordingError(MdleError):
    """The recording cannot be written (the disk is full, the folder is not empty...)."""


class McapRecorder:
    """Record a run into an MCAP file (or a rosbag2 folder) as it goes.

    Parameters
    ----------
    target : str or path-like
        The ``.mcap`` file, or with ``rosbag`` the folder.
    header : mapping
        The run's trace header (what ``mdle run`` writes).
    world : sim.World or None
        The simulated world, for ``/map``.
    rosbag : bool
        Write a rosbag2 folder.
    **options
        ``chunk_size``, ``max_age``, ``compression`` for the MCAP file (``compression``
        ``""``, none, unless given: ``"lz4"``).

    Raises
    ------
    RecordingError
        The file cannot be created.
    """

    def __init__(self, target: str | os.PathLike[str], header: Mapping[str, Any],
                 world: Any = None, *, rosbag: bool = False, **options: Any) -> None:
        self.target = os.fspath(target)
        # chunks not compressed unless asked: the cheapest to write while a run goes
        options.setdefault("compression", "")
        try:
            self.recording = RosRecording(target, header, world, rosbag=rosbag, **options)
        except OSError as exc:
            raise RecordingError(Diagnostic(None, f"cannot write the recording "
                                                  f"`{self.target}`: {exc.strerror}")) from None
        self._format = SampleFormat()
        self._laser = LaserRecords()
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
        """Publish the event on ``/mdle/events``."""
        if self.error is not None:
            return
        try:
            self.recording.event(event.time, dumps(event_record(event)))
        except OSError as exc:
            raise self._fail(exc) from None

    def on_tick(self, sample: Sample) -> None:
        """Publish a new scan, then the tick's odometry, transforms, command and state."""
        if self.error is not None:
            return
        try:
            scan = sample.scan
            if scan is not None and scan is not self._laser.last:
                laser = self._laser.changed(scan)
                if laser is not None:
                    self.recording.laser(sample.time, laser)
                self.recording.scan(sample.time, scan.stamp, scan_ranges(scan))
            line, values = self._format.line_and_values(sample)
            self.recording.live_sample(line, sample, values)
        except OSError as exc:
            raise self._fail(exc) from None

    def on_end(self, result: RunResult) -> None:
        """Publish the ``end`` record and finish the file (never raises: the run is over)."""
        if self.error is None:
            try:
                self.recording.end(result.termination.time, dumps(end_record(result)))
            except OSError as exc:
                self._fail(exc)
        self.close()

    def close(self) -> None:
        """Finish the file (summary, index, footer) if it is not yet; safe to repeat."""
        if self.recording.finished:
            return
        try:
            self.recording.finish()
        except OSError as exc:
            self._fail(exc)
