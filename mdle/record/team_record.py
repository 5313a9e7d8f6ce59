"""A team run recorded in one file (and shown in one live view): ``mdle run --team --record``.

Every robot has a :class:`~mdle.record.recorder.McapRecorder` of its own (its scheduler's
observer), and all of them write into one :class:`~mdle.record.outlet.Outlet`: one MCAP
file or rosbag2 folder, one live view. A robot's topics are ``/NAME/scan``,
``/NAME/odom``, ``/NAME/tf``... and its frames ``NAME/odom``, ``NAME/base_link``,
``NAME/laser``, all under the world's one ``map`` (``map -> NAME/odom`` on
``/NAME/tf``), so a tool shows the robots together; the world's ``/map`` and
``/obstacles`` are written once. Each robot's trace header is the Metadata record
``mdle/NAME``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import Any

from mdle.core.errors import Diagnostic
from mdle.record.mcap_file import McapFile
from mdle.record.outlet import LiveSink, Outlet
from mdle.record.recorder import McapRecorder, RecordingError
from mdle.record.topics import library_name

__all__ = ["TeamRecording"]


class TeamRecording:
    """One recording (a file, a rosbag2 folder, or only live views) of a team's robots.

    Parameters
    ----------
    target : str or path-like or None
        The ``.mcap`` file, or with ``rosbag`` the folder; None: live views only.
    headers : mapping
        Each robot's trace header, by name (the robots are recorded in this order).
    world : sim.World
        The team's world.
    rosbag : bool
        Write a rosbag2 folder.
    live : sequence of LiveSink
        Live views.
    compression : str
        The chunks' compression (``""`` or ``"lz4"``).

    :attr:`recorders` holds each robot's observer; :meth:`close` ends the file once
    every robot's run has ended.

    Raises
    ------
    RecordingError
        The file cannot be created.
    """

    def __init__(self, target: str | os.PathLike[str] | None,
                 headers: Mapping[str, Mapping[str, Any]], world: Any, *,
                 rosbag: bool = False, live: Sequence[LiveSink] = (),
                 compression: str = "") -> None:
        self.target = os.fspath(target) if target is not None else None
        self.rosbag = rosbag
        self.path = self.target
        file = None
        try:
            if self.target is not None:
                if rosbag:
                    from mdle.record.rosbag import prepare_folder

                    self.path = prepare_folder(self.target)
                file = McapFile(self.path or "", library=library_name(),
                                compression=compression)
        except OSError as exc:
            for sink in live:
                sink.close()
            raise RecordingError(Diagnostic(None, f"cannot write the recording "
                                                  f"`{self.target}`: {exc.strerror}")) from None
        self.outlet = Outlet(file, live)
        self.recorders: dict[str, McapRecorder] = {
            name: McapRecorder(self.target, header, world, outlet=self.outlet, robot=name,
                               live=live)
            for name, header in headers.items()}
        self.finished = False

    @property
    def error(self) -> str | None:
        """Why the recording failed (None while it is fine)."""
        return next((r.error for r in self.recorders.values() if r.error is not None), None)

    def close(self) -> None:
        """Finish every robot's messages and the file (summary; ``metadata.yaml``)."""
        if self.finished:
            return
        self.finished = True
        for r in self.recorders.values():
            r.close()
        if self.error is not None:
            self.outlet.close()
            return
        try:
            self.outlet.finish()
            if self.rosbag and self.target is not None and self.path is not None:
                from mdle.record.rosbag import write_metadata

                topics, counts = [], {}
                for r in self.recorders.values():
                    topics += r.recording.topics
                    counts.update(r.recording.counts())
                write_metadata(self.target, os.path.basename(self.path), topics, counts,
                               self.outlet.time_range or (0, 0))
        except OSError as exc:
            self.outlet.close()
            raise RecordingError(Diagnostic(None, f"cannot write the recording "
                                                  f"`{self.target}`: {exc.strerror}")) from None
