"""Trace records to ROS 2 messages: the topics, frames and timestamps of a recording.

:class:`RosRecording` takes the trace's records one by one (the live recorder hands
them over as the run makes them, the exporter as it reads a trace) and writes the ROS
messages they become into an MCAP file (:class:`~mdle.record.mcap_file.McapFile`), or a
rosbag2 folder (the MCAP file and ``metadata.yaml``). Frames follow REP-105: ``map``
(the simulated world), ``odom`` (where odometry counts from), ``base_link`` (the
robot: x forward, y left, REP-103) and ``laser`` (the ladar, at the profile's mount).

Timestamps are the run's clock in nanoseconds (simulated time from 0, or the robot's
clock): a message's log time is the tick at which the run saw it, a scan's header
stamp the instant it was taken. ``docs/trace.md`` lists the topics.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import metadata
from typing import Any

import numpy as np

from mdle.record.describe import diagnostic_names, footprint
from mdle.record.markers import PathPieces, obstacle_markers
from mdle.record.mcap_file import McapFile
from mdle.record.outlet import LiveSink, Outlet
from mdle.record.tick import TickEncoder, Ticks, times_ns
from mdle.rosmsg import cdr
from mdle.rosmsg.covariance import OdometryCovariance
from mdle.rosmsg.msgdefs import DIAGNOSTICS, diagnostics_definition, schema_text

__all__ = ["BATCH", "FRAMES", "TOPICS", "Topic", "RosRecording",
           "footprint", "library_name", "sample_values", "to_ns"]

#: Frame names (REP-105).
FRAMES = {"map": "map", "odom": "odom", "base": "base_link", "laser": "laser"}

_VOLATILE, _LATCHED = 2, 1  # QoS durability: VOLATILE, TRANSIENT_LOCAL


@dataclass(frozen=True)
class Topic:
    """A topic mdle writes: name, message type, QoS durability, and when it is written.

    ``simulation``: only for a simulated run; ``shared``: once per file, whatever the
    robots (a team's world); ``footprint``: only when the body is known.
    """

    name: str
    type: str
    latched: bool = False
    simulation: bool = False
    what: str = ""
    shared: bool = False
    footprint: bool = False


#: Every topic, in the order they are registered (a team's robots' under ``/NAME``).
TOPICS: tuple[Topic, ...] = (
    Topic("/scan", "sensor_msgs/msg/LaserScan", what="each new ladar scan, frame laser"),
    Topic("/odom", "nav_msgs/msg/Odometry", what="odometry each tick, odom -> base_link"),
    Topic("/tf", "tf2_msgs/msg/TFMessage",
          what="odom -> base_link each tick; map -> odom in simulation"),
    Topic("/tf_static", "tf2_msgs/msg/TFMessage", latched=True,
          what="base_link -> laser (the ladar mount)"),
    Topic("/cmd_vel", "geometry_msgs/msg/Twist", what="the command sent each tick"),
    Topic("/ground_truth", "geometry_msgs/msg/PoseStamped", simulation=True,
          what="true pose each tick, frame map"),
    Topic("/footprint", "geometry_msgs/msg/PolygonStamped", footprint=True,
          what="the body's outline each tick, frame base_link"),
    Topic("/path", "visualization_msgs/msg/Marker",
          what="the odometry path, a piece every 10 ticks, frame odom"),
    Topic("/map", "nav_msgs/msg/OccupancyGrid", latched=True, simulation=True, shared=True,
          what="the obstacles as an occupancy grid, frame map (once)"),
    Topic("/obstacles", "visualization_msgs/msg/MarkerArray", latched=True, simulation=True,
          shared=True, what="the obstacles' outlines, frame map (once)"),
    Topic("/mdle/events", "std_msgs/msg/String",
          what="start, event and end trace records as JSON"),
    Topic("/mdle/active", "std_msgs/msg/String", latched=True,
          what="the running element's path, at each change (latched: the current state)"),
    Topic("/mdle/diagnostics", DIAGNOSTICS,
          what="the control law's diagnostics each tick, a float64 field each"),
    Topic("/mdle/state", "std_msgs/msg/String", what="the trace's sample record each tick"),
)

#: Ticks in a piece of ``/path``.
PATH_TICKS = 10

def qos_yaml(latched: bool) -> str:
    """Return ``offered_qos_profiles`` as ``ros2 bag record`` (Humble) writes it."""
    never = "    sec: 9223372036\n    nsec: 854775807\n"
    return ("- history: 3\n  depth: 0\n  reliability: 1\n"
            f"  durability: {_LATCHED if latched else _VOLATILE}\n"
            f"  deadline:\n{never}  lifespan:\n{never}  liveliness: 1\n"
            f"  liveliness_lease_duration:\n{never}"
            "  avoid_ros_namespace_conventions: false")


def to_ns(t: float) -> int:
    """Return seconds as integer nanoseconds (never below 0: MCAP times are unsigned)."""
    ns = round(t * 1e9)
    return ns if ns > 0 else 0


def library_name() -> str:
    """Return the writer's name for the MCAP header (mdle and mcap versions)."""
    parts = []
    for dist in ("mdle", "mcap"):
        try:
            parts.append(f"{dist}/{metadata.version(dist)}")
        except metadata.PackageNotFoundError:
            parts.append(dist)
    return " ".join(parts)


def _seconds(record: Mapping[str, Any], key: str) -> float:
    """Return a ``laser`` record's optional timing (s): 0 when absent (unknown), else >= 0."""
    value = float(record.get(key) or 0.0)
    if not (math.isfinite(value) and value >= 0.0):
        raise ValueError(f"`{key}` must be a finite number of seconds, not below 0")
    return value


_UNKNOWN = (math.nan, math.nan, math.nan)  # a simulated sample without its true pose

#: Ticks handed over one at a time (an export) published together.
BATCH = 64


def sample_values(s: Any, numbers: tuple[float, ...] | None) -> tuple[float, ...]:
    """Return a sample's ten numbers for :class:`~mdle.record.tick.Ticks`, not yet rounded.

    ``numbers`` are the line's as :meth:`mdle.record.trace.SampleFormat.line_and_numbers` gives
    them (seven without a true pose), or None (a number not finite: they are taken from
    the sample). An unknown true pose is NaN.
    """
    if numbers is None:
        truth = _UNKNOWN
        if s.true_x is not None and s.true_y is not None and s.true_theta is not None:
            truth = (s.true_x, s.true_y, s.true_theta)
        return (s.x, s.y, s.theta, s.v, s.omega, s.cmd_v, s.cmd_omega, *truth)
    return numbers if len(numbers) == 10 else numbers[:7] + _UNKNOWN


class RosRecording:
    """Turn trace records into ROS 2 messages in an MCAP file (or a rosbag2 folder).

    Parameters
    ----------
    target : str or path-like or None
        The ``.mcap`` file; with ``rosbag``, the folder to create (it must not exist or
        be empty), which gets ``NAME_0.mcap`` and ``metadata.yaml``. None: no file (a
        live view only). Ignored with ``outlet``.
    header : mapping
        The trace header (stored in the file as the Metadata record ``mdle``, with key
        ``header``); a header with a ``world`` marks a simulated run (``/ground_truth``,
        ``/map``, ``/obstacles``, ``map -> odom``), one with a ``radius`` gets
        ``/footprint``, one with ``odometry`` (the noise model) honest covariances.
    world : sim.World or None
        The simulated world, for ``/map`` and ``/obstacles``.
    rosbag : bool
        Write a rosbag2 folder.
    live : sequence of LiveSink
        Live views that get every message too (``--foxglove``).
    outlet : Outlet or None
        Share another recording's file and live views (a team's robots): this
        recording does not finish it.
    robot : str or None
        A team robot's name: its topics are ``/NAME/...``, its frames ``NAME/odom``,
        ``NAME/base_link``, ``NAME/laser`` (``map`` is the world's, shared), its header
        the Metadata record ``mdle/NAME``.
    chunk_size, max_age, compression : see :class:`~mdle.record.mcap_file.McapFile`.

    Feed it :meth:`start`, :meth:`event`, :meth:`laser`, :meth:`scan`, :meth:`sample` and
    :meth:`end` in the trace's order; :meth:`finish` ends the file.
    """

    def __init__(self, target: str | os.PathLike[str] | None, header: Mapping[str, Any],
                 world: Any = None, *, rosbag: bool = False, live: Sequence[LiveSink] = (),
                 outlet: Outlet | None = None, robot: str | None = None,
                 **file_options: Any) -> None:
        from mdle.record.trace import dumps

        self.target = os.fspath(target) if target is not None else None
        self.rosbag = rosbag and outlet is None
        self.path: str | None = self.target
        self._owns = outlet is None
        if outlet is None:
            file = None
            if self.target is not None:
                if rosbag:
                    from mdle.record.rosbag import prepare_folder

                    self.path = prepare_folder(self.target)
                file = McapFile(self.path or "", library=library_name(), **file_options)
            outlet = Outlet(file, live)
        self.out = outlet
        self.simulation = header.get("world") is not None or header.get("backend") == "sim"
        prefix = f"/{robot}" if robot else ""
        self.frames = {key: (f"{robot}/{name}" if robot and key != "map" else name)
                       for key, name in FRAMES.items()}
        radius = header.get("radius")
        outline = footprint(float(radius)) if isinstance(radius, (int, float)) \
            and not isinstance(radius, bool) and math.isfinite(radius) and radius > 0 else []
        self.diag_names = diagnostic_names()
        extra = {DIAGNOSTICS: diagnostics_definition(self.diag_names)}
        self.channels: dict[str, int] = {}  # by the topic's base name (``/scan``)
        self.topics: list[Topic] = []       # as registered (team: ``/NAME/scan``)
        for topic in TOPICS:
            if (topic.simulation and not self.simulation) or (topic.footprint and not outline):
                continue
            name = topic.name if topic.shared else prefix + topic.name
            if topic.shared and outlet.has(name):
                continue  # another robot of the file has it
            sid = outlet.schema(topic.type, "ros2msg",
                                schema_text(topic.type, extra).encode())
            self.channels[topic.name] = outlet.channel(
                name, sid, metadata={"offered_qos_profiles": qos_yaml(topic.latched)},
                latched=topic.latched)
            self.topics.append(Topic(name, topic.type, topic.latched, topic.simulation,
                                     topic.what, topic.shared, topic.footprint))
        outlet.metadata(f"mdle/{robot}" if robot else "mdle", {"header": dumps(header)})
        ch = self.channels
        self._scan_ch = ch["/scan"]
        self._static_ch, self._events_ch = ch["/tf_static"], ch["/mdle/events"]
        self._active_ch = ch["/mdle/active"]
        self._path_ch = ch["/path"]
        self._path: list[tuple[float, float]] = []  # the piece of path not yet published
        self._path_ns: list[int] = []               # the times of its points
        self._path_pieces = 0
        self._pieces = PathPieces(self.frames["odom"])
        self._ticks = TickEncoder(outlet, ch["/odom"], ch["/tf"], ch["/cmd_vel"],
                                  ch["/mdle/state"], ch.get("/ground_truth", 0), self._scan_ch,
                                  (self.frames["map"], self.frames["odom"], self.frames["base"]),
                                  footprint=ch.get("/footprint", 0), outline=outline,
                                  diagnostics=ch["/mdle/diagnostics"],
                                  diag_names=self.diag_names)
        odometry = header.get("odometry") if self.simulation else None
        self._covariance = OdometryCovariance(odometry)
        self._ticks.covariance = self._covariance.constant
        # ticks and scans handed over one at a time (an export), published in batches
        self._waiting: list[tuple[float, str, tuple[float, ...], str, np.ndarray]] = []
        self._waiting_scans: list[tuple[int, float, float, np.ndarray]] = []
        self._mount: tuple[float, float, float] | None = None
        self._world = world
        self._pending: list[str] = []  # start records waiting for a time
        self._started = False
        self._active: str | None = None
        self.finished = False

    # ------------------------------------------------------------------ records

    def _timed(self, ns: int) -> None:
        """Publish what waits for the first time stamp: the world, pending starts."""
        if not self._started:
            self._started = True
            if self._world is not None and "/map" in self.channels:
                from mdle.record.occupancy import occupancy_grid

                self.out.add(self.channels["/map"], ns, occupancy_grid(self._world, ns))
            if self._world is not None and "/obstacles" in self.channels:

                self.out.add(self.channels["/obstacles"], ns,
                             obstacle_markers(self._world, ns))
        if self._pending:
            for line in self._pending:
                self.out.add(self._events_ch, ns, cdr.encode_string(line))
            self._pending.clear()

    def start(self, line: str) -> None:
        """Take a ``start`` record (JSON text); published at the next record's time."""
        self._pending.append(line)

    def event(self, t: float, line: str) -> None:
        """Publish an ``event`` (or ``end``, or other timed) record on ``/mdle/events``."""
        self.flush()
        ns = to_ns(t)
        self._timed(ns)
        self.out.add(self._events_ch, ns, cdr.encode_string(line))

    def laser(self, t: float, record: Mapping[str, Any]) -> None:
        """Take a ``laser`` record: the scan geometry and, if new, ``base_link -> laser``."""
        values = [float(m) for m in record.get("mount") or (0.0, 0.0, 0.0)]
        if len(values) != 3 or not all(math.isfinite(m) for m in values):
            raise ValueError("`mount` must be three finite numbers")
        mount = (values[0], values[1], values[2])
        frame = str(record.get("frame") or "laser")
        geometry = (self.frames["laser"] if frame == "laser" else frame,
                    float(record["angle_min"]), float(record["angle_max"]),
                    float(record["angle_increment"]), float(record.get("range_min", 0.0)),
                    float(record["range_max"]), int(record["count"]),
                    _seconds(record, "scan_time"), _seconds(record, "time_increment"))
        self.flush()  # the scans so far have the geometry they came with
        self._ticks.geometry(*geometry)
        if mount != self._mount:
            self._mount = mount
            ns = to_ns(t)
            self._timed(ns)
            msg = cdr.CdrWriter().count(1).header(ns, self.frames["base"]).string(
                geometry[0]).pose(mount[0], mount[1], mount[2]).bytes()
            self.out.add(self._static_ch, ns, msg)

    def scan(self, t: float, stamp: float, ranges: np.ndarray) -> None:
        """Take a scan seen at tick ``t``, taken at ``stamp`` (published with the ticks).

        ``ranges`` are little-endian float32, +inf where a beam had no return.
        """
        self._ticks.check(ranges)
        self._waiting_scans.append((len(self._waiting), t, stamp, ranges))

    def diagnostics(self, diag: Mapping[str, Any] | None) -> np.ndarray:
        """Return a sample's diagnostics as this recording's row of numbers (NaN: none)."""
        row = np.full(len(self.diag_names), np.nan)
        if diag:
            for i, name in enumerate(self.diag_names):
                value = diag.get(name)
                if isinstance(value, (int, float)):  # a flag is a bool: 0 or 1
                    row[i] = float(value)
        return row

    def sample(self, line: str, t: float, x: float, y: float, theta: float, v: float,
               omega: float, cmd_v: float, cmd_omega: float,
               truth: tuple[float, float, float] | None, *, path: str = "",
               diag: Mapping[str, Any] | None = None) -> None:
        """Take one tick: odometry, transforms, command, true pose and the state line.

        Numbers as the trace holds them (the live recorder rounds them the same way);
        ``path`` the running element, ``diag`` the law's diagnostics. Ticks are
        published in batches of :data:`BATCH`, and before any other record.
        """
        self._waiting.append((t, line, (x, y, theta, v, omega, cmd_v, cmd_omega,
                                        *(truth if truth is not None else _UNKNOWN)),
                              path, self.diagnostics(diag)))
        if len(self._waiting) >= BATCH:
            self.flush()

    def flush(self) -> None:
        """Publish the ticks and scans waiting."""
        ticks, scans = self._waiting, self._waiting_scans
        if not (ticks or scans):
            return
        self._waiting, self._waiting_scans = [], []
        batch = Ticks(times_ns([w[0] for w in ticks]),
                      np.array([w[2] for w in ticks], np.float64).reshape(-1, 10),
                      [w[1] for w in ticks])
        batch.paths = [w[3] for w in ticks]
        batch.diag = np.array([w[4] for w in ticks], np.float64).reshape(
            -1, len(self.diag_names))
        if scans:
            batch.scan_at = [at for at, _, _, _ in scans]
            batch.scan_ns = times_ns([t for _, t, _, _ in scans])
            batch.stamps = times_ns([s for _, _, s, _ in scans])
            batch.ranges = np.stack([r for _, _, _, r in scans])
        self.publish(batch)

    def publish(self, ticks: Ticks) -> None:
        """Publish a batch of ticks (a :class:`~mdle.record.tick.Ticks`), after those waiting.

        A change of the running element (``ticks.paths``) goes on ``/mdle/active`` at the
        tick it happens, before the batch's records.
        """
        self.flush()
        if not (len(ticks.ns) or ticks.scan_at):
            return
        if not self._started or self._pending:
            first = ticks.scan_ns[0] if ticks.scan_at and ticks.scan_at[0] == 0 \
                else ticks.ns[0]
            self._timed(int(first))
        if ticks.paths is not None:
            for i, path in enumerate(ticks.paths):
                if path != self._active:
                    self._active = path
                    self.out.add(self._active_ch, int(ticks.ns[i]), cdr.encode_string(path))
        if len(ticks.ns):
            ticks.covariance = self._covariance.batch(ticks.values[:, 0:3])
        self._ticks.write(ticks)
        self._add_path(ticks)
        self.out.tick()

    def _add_path(self, ticks: Ticks) -> None:
        """Publish ``/path`` pieces of :data:`PATH_TICKS` ticks (after their ticks).

        The pieces are counted in ticks, so the recording and the export of its trace
        (batched differently) publish the same ones.
        """
        xy = ticks.values[:, 0:2]
        known = np.isfinite(xy).all(axis=1)
        self._path.extend(map(tuple, xy[known].tolist()))
        self._path_ns.extend(ticks.ns[known].tolist())
        while len(self._path) > PATH_TICKS:
            self._publish_path(PATH_TICKS + 1)

    def _publish_path(self, size: int | None = None) -> None:
        """Publish the first ``size`` points waiting (all: None) as a piece.

        The next piece starts at this one's last point.
        """
        n = len(self._path) if size is None else size
        if n > 1:
            ns = self._path_ns[n - 1]
            self.out.add(self._path_ch, ns,
                         self._pieces.piece(ns, self._path_pieces, np.array(self._path[:n])))
            self._path_pieces += 1
            del self._path[:n - 1]
            del self._path_ns[:n - 1]

    def end(self, t: float, line: str) -> None:
        """Publish the ``end`` record."""
        self.event(t, line)

    # ------------------------------------------------------------------ the end

    def counts(self) -> dict[str, int]:
        """Messages written per topic so far (by the names in the file)."""
        by_id = self.out.channel_counts()
        return {t.name: by_id.get(self.channels[_base(t.name, t.shared, self.frames)], 0)
                for t in self.topics}

    def finish(self) -> None:
        """End the file (summary, index, footer); a rosbag2 folder gets ``metadata.yaml``.

        A recording that shares another's outlet only publishes what waits.
        """
        if self.finished:
            return
        self.flush()
        self._publish_path()  # the last piece, however short
        self.finished = True
        if not self._owns:
            return
        self.out.finish()
        if self.rosbag and self.target is not None and self.path is not None:
            from mdle.record.rosbag import write_metadata

            span = self.out.time_range or (0, 0)
            write_metadata(self.target, os.path.basename(self.path), self.topics,
                           self.counts(), span)

    def abandon(self) -> None:
        """Close the file as it stands (after a failure: nothing more can be written)."""
        self.finished = True
        if self._owns:
            self.out.close()


def _base(name: str, shared: bool, frames: Mapping[str, str]) -> str:
    """Return a registered topic's base name (``/leader/scan`` -> ``/scan``)."""
    if shared:
        return name
    robot = frames["odom"].rpartition("/")[0]
    return name[len(robot) + 1:] if robot else name
