"""A batch of ticks' ROS 2 messages as ready MCAP Message records, filled with numpy.

Every tick a run publishes its odometry (``/odom``), transforms (``/tf``), command
(``/cmd_vel``), in simulation the true pose (``/ground_truth``), the body's outline
(``/footprint``), the law's diagnostics (``/mdle/diagnostics``), the trace's sample line
(``/mdle/state``) and, when the ladar has a new one, a scan (``/scan``). Frame names and
beam geometry are constant, so every byte of these Message records (the MCAP record
header and the CDR message each) is at an offset known in advance, except the state
line's text, which comes last in a tick. :class:`TickEncoder` therefore lays a tick's
fixed records out once as a row (:class:`Rows`: a template of the constant bytes and the
numpy fields of the variable ones), fills a whole batch of rows a column at a time, and
joins each tick's scan, row and text into one block that the MCAP file adds with its
index entries at once (:meth:`~mdle.record.mcap_file.McapFile.add_block`). Records keep the
order a tick at a time writer gives them: a tick's scan, then its other messages.

Fields that are always zero (z, the quaternion's x and y, a planar twist's other axes)
are zeros of the template; the footprint's outline is constant, and the odometry's
covariances are columns filled per batch (:mod:`mdle.rosmsg.covariance`). The records'
bytes are exactly what a field-by-field CDR writer makes (tests decode them with
mcap-ros2-support and rosbags); sines and cosines come from :mod:`math`, as that writer's would.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from itertools import chain
from typing import Any

import numpy as np

from mdle.record.mcap_file import McapFile
from mdle.record.outlet import Outlet
from mdle.rosmsg.cdr import Layout

__all__ = ["Rows", "TickEncoder", "Ticks"]

_HEAD = struct.Struct("<BQHIQQ")  # MCAP Message record: opcode, length, channel, sequence,
_OP = 0x05                        # log time, publish time (31 bytes)
_NS = 1_000_000_000
_FLOAT32 = np.dtype("<f4")


def _stamp(lay: Layout, name: str) -> Layout:
    """Add a ``builtin_interfaces/Time`` (fields ``sec`` and ``nsec``)."""
    return lay.field("sec", "i").field("nsec", "I") if not name else \
        lay.field(name + ".sec", "i").field(name + ".nsec", "I")


def _planar_pose(lay: Layout, name: str) -> Layout:
    """Add a Pose or Transform of a planar pose: fields ``NAME.xy`` and ``NAME.q`` (z, w)."""
    return lay.field(name + ".xy", "d", 2).zeros("d", 3).field(name + ".q", "d", 2)


def _planar_twist(lay: Layout) -> Layout:
    """Add a Twist: fields ``v`` (linear.x) and ``omega`` (angular.z)."""
    return lay.field("v", "d").zeros("d", 4).field("omega", "d")


class Rows:
    """Message records of fixed size side by side, one row of them per tick.

    :meth:`message` appends a record: the MCAP header (its ``seq`` and ``times`` (log and
    publish time) fields, and with ``open_end`` its ``length``) and the message laid out by a
    :class:`~mdle.rosmsg.cdr.Layout`, its fields named ``PREFIX.NAME``.
    """

    def __init__(self) -> None:
        self.template = bytearray()
        self.fields: dict[str, tuple[Any, int]] = {}
        #: (channel, offset of its record in the row), in order
        self.records: list[tuple[int, int]] = []
        self._dtype: np.dtype[Any] | None = None
        self._row = np.zeros(0, np.uint8)

    def message(self, prefix: str, channel: int, body: Layout, open_end: bool = False) -> None:
        """Append a record on ``channel``.

        With ``open_end`` the row's bytes end inside it (a string's text follows the
        row) and its record ``length`` is a field.
        """
        at = len(self.template)
        data = body.template
        self.template += _HEAD.pack(_OP, 22 + len(data), channel, 0, 0, 0)
        self.fields[f"{prefix}.seq"] = ("<u4", at + 11)
        self.fields[f"{prefix}.times"] = (("<u8", 2), at + 15)  # log and publish time
        if open_end:
            self.fields[f"{prefix}.length"] = ("<u8", at + 1)
        for name, (kind, offset) in body.fields.items():
            self.fields[f"{prefix}.{name}"] = (kind, at + 31 + offset)
        self.template += data
        self.records.append((channel, at))

    def batch(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Return ``k`` rows of the template: as one structured array, and as bytes."""
        if self._dtype is None or self._dtype.itemsize != len(self.template):
            names = list(self.fields)
            self._dtype = np.dtype({"names": names,
                                    "formats": [self.fields[n][0] for n in names],
                                    "offsets": [self.fields[n][1] for n in names],
                                    "itemsize": len(self.template)})
            self._row = np.frombuffer(bytes(self.template), np.uint8)
        raw = np.tile(self._row, k)
        return raw.view(self._dtype), raw


@dataclass
class Ticks:
    """A batch of ticks to publish, in order.

    ``ns`` the ticks' times (ns); ``values`` their numbers (k x 10: x, y, theta, v,
    omega, cmd_v, cmd_omega and the true x, y, theta, NaN when unknown); ``lines`` their
    trace sample lines; and the new scans: ``scan_at`` the tick each comes before
    (``len(ns)``: after the last), ``scan_ns`` when it was seen, ``stamps`` when it was
    taken (ns), ``ranges`` (m x beams, little-endian float32, +inf without a return).
    """

    ns: np.ndarray
    values: np.ndarray
    lines: list[str]
    scan_at: list[int] = field(default_factory=list)
    scan_ns: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    stamps: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    ranges: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), _FLOAT32))
    #: the ticks' diagnostics (k x the encoder's names, NaN where not recorded), or None
    diag: np.ndarray | None = None
    #: the ticks' running element paths (for ``/mdle/active``), or None
    paths: list[str] | None = None
    #: the odometry's pose and twist covariances (k x 36 each), or None: the encoder's
    covariance: tuple[np.ndarray, np.ndarray] | None = None


def times_ns(seconds: Iterable[float]) -> np.ndarray:
    """Return times (s) as integer nanoseconds, never below 0 (as :func:`to_ns` rounds)."""
    t = np.asarray(seconds, dtype=np.float64) * 1e9
    if not np.isfinite(t).all():
        raise ValueError("a time that is not a finite number")
    return np.maximum(np.rint(t), 0.0).astype(np.int64)


def _trig(f: Any, x: np.ndarray) -> np.ndarray:
    """``f`` (math.sin or math.cos) of each element, exactly as :mod:`math` gives it."""
    return np.fromiter(map(f, x.tolist()), np.float64, len(x))


class TickEncoder:
    """Write batches of ticks (:class:`Ticks`) into an MCAP file.

    Parameters
    ----------
    out : McapFile or Outlet
        The file, or the outlet that hands the messages to the file and live views.
    odom, tf, cmd, state, truth, scan : int
        Channel ids (``truth`` 0 on a robot: no ``/ground_truth`` and no ``map -> odom``).
    frames : (map, odom, base)
        Frame names.
    """

    def __init__(self, out: McapFile | Outlet, odom: int, tf: int, cmd: int, state: int, truth: int,
                 scan: int, frames: tuple[str, str, str], *, footprint: int = 0,
                 outline: Sequence[tuple[float, float]] = (), diagnostics: int = 0,
                 diag_names: Sequence[str] = ()) -> None:
        self._out = out
        map_, odom_f, base = frames
        self.simulation = bool(truth)
        self.scan_channel = scan
        self.diag_names = tuple(diag_names) if diagnostics else ()
        rows = Rows()
        # nav_msgs/Odometry: header, child frame, pose + covariance, twist + covariance
        lay = _stamp(Layout(), "").string(odom_f).string(base)
        _planar_pose(lay, "pose").field("pose_cov", "d", 36)
        _planar_twist(lay).field("twist_cov", "d", 36)
        rows.message("odom", odom, lay)
        # tf2_msgs/TFMessage: odom -> base_link, in simulation map -> odom after it
        lay = _stamp(Layout().prim("I", 2 if truth else 1), "").string(odom_f).string(base)
        _planar_pose(lay, "pose")
        if truth:
            _planar_pose(_stamp(lay, "map").string(map_).string(odom_f), "map")
        rows.message("tf", tf, lay)
        rows.message("cmd", cmd, _planar_twist(Layout()))  # geometry_msgs/Twist
        if truth:  # geometry_msgs/PoseStamped in map
            rows.message("truth", truth, _planar_pose(_stamp(Layout(), "").string(map_),
                                                      "pose"))
        self._extra: list[str] = []  # the optional records' names
        if footprint:  # geometry_msgs/PolygonStamped in base_link: only the stamp varies
            lay = _stamp(Layout(), "").string(base).count(len(outline))
            for x, y in outline:
                lay.prim("f", x, y, 0.0)
            rows.message("footprint", footprint, lay)
            self._extra.append("footprint")
        if diagnostics:  # mdle_msgs/Diagnostics: the stamp and a float64 per name
            lay = _stamp(Layout(), "").string(base)
            if self.diag_names:
                lay.field("values", "d", len(self.diag_names))
            rows.message("diag", diagnostics, lay)
            self._extra.append("diag")
        # std_msgs/String: its length, the text after the row
        rows.message("state", state, Layout().field("n", "I"), open_end=True)
        self._rows = rows
        #: the odometry's covariances (36 each, row-major x y z roll pitch yaw) used
        #: when a batch brings none: all 0 unless set (:mod:`mdle.rosmsg.covariance`)
        self.covariance = (np.zeros(36), np.zeros(36))
        self._scan: Rows | None = None
        self.count = 0  # beams of a scan

    def geometry(self, frame: str, angle_min: float, angle_max: float, angle_increment: float,
                 range_min: float, range_max: float, count: int, scan_time: float = 0.0,
                 time_increment: float = 0.0) -> None:
        """Set the beam geometry of the scans that follow (``sensor_msgs/LaserScan``).

        Angles in radians in the scan's frame, ranges in metres, times in seconds; no
        intensities.
        """
        lay = _stamp(Layout(), "").string(frame).prim(
            "f", angle_min, angle_max, angle_increment, time_increment, scan_time,
            range_min, range_max).prim("I", count)
        if count:
            lay.field("ranges", "f", count)
        lay.zeros("I")  # no intensities
        rows = Rows()
        rows.message("scan", self.scan_channel, lay)
        self._scan = rows
        self.count = count

    def check(self, ranges: np.ndarray) -> None:
        """Raise ValueError unless ``ranges`` fit the geometry (little-endian float32)."""
        if self._scan is None:
            raise ValueError("a scan before any `laser` record (the beam geometry)")
        if ranges.shape[-1:] != (self.count,):
            raise ValueError(f"a scan of {ranges.shape[-1] if ranges.ndim else 0} beams, "
                             f"the laser has {self.count}")
        if ranges.dtype != _FLOAT32:
            raise ValueError("scan ranges must be little-endian float32")

    def write(self, ticks: Ticks) -> None:
        """Add the batch to the file: each tick's scans, then its other records."""
        k, m = len(ticks.ns), len(ticks.scan_at)
        out = self._out
        # the strings with their NUL
        texts = [f"{line}\x00".encode() for line in ticks.lines]
        scan_size = len(self._scan.template) if self._scan is not None else 0
        scan_parts: list[bytes] = [b""] * (k + 1)  # the scans that come before each tick
        if m:
            self.check(ticks.ranges)
            assert self._scan is not None
            scans, raw = self._scan.batch(m)
            first = out.count(self.scan_channel)
            scans["scan.seq"] = np.arange(first, first + m)
            scans["scan.times"] = ticks.scan_ns[:, None]
            scans["scan.sec"], scans["scan.nsec"] = np.divmod(ticks.stamps, _NS)
            if self.count:
                scans["scan.ranges"] = ticks.ranges
            records = raw.view(f"V{scan_size}").tolist()
            if ticks.scan_at == list(range(k)):  # a new scan every tick
                scan_parts[:k] = records
            else:
                for at, data in zip(ticks.scan_at, records, strict=True):
                    scan_parts[at] += data
        size = len(self._rows.template)
        rows, raw = self._rows.batch(k)
        text_n = np.fromiter(map(len, texts), np.int64, k)
        self._fill(rows, ticks, text_n)
        # where each tick's records begin in the block, and its row
        scan_bytes = np.bincount(np.asarray(ticks.scan_at, np.int64), minlength=k + 1) \
            * scan_size
        starts = np.zeros(k + 1, np.int64)
        np.cumsum(scan_bytes[:k] + size + text_n, out=starts[1:])
        row_at = starts[:k] + scan_bytes[:k]
        index = [(channel, ticks.ns, row_at + offset) for channel, offset in self._rows.records
                 if k]
        if m:
            tick = np.asarray(ticks.scan_at, np.int64)
            nth = np.arange(m) - np.searchsorted(tick, tick)  # of the scans before its tick
            index.append((self.scan_channel, ticks.scan_ns, starts[tick] + nth * scan_size))
        data = b"".join(chain.from_iterable(zip(scan_parts, raw.view(f"V{size}").tolist(),
                                                texts, strict=False)))
        times = [t for t in (ticks.ns, ticks.scan_ns) if len(t)]
        if times:
            out.add_block(data + scan_parts[k], index, min(int(t.min()) for t in times),
                          max(int(t.max()) for t in times))

    def _fill(self, rows: np.ndarray, ticks: Ticks, lengths: np.ndarray) -> None:
        """Fill the variable fields of a batch's rows."""
        ns = ticks.ns
        k = len(ns)
        v = ticks.values
        x, y, theta = v[:, 0], v[:, 1], v[:, 2]
        seq = np.arange(self._out.count(self._rows.records[0][0]),
                        self._out.count(self._rows.records[0][0]) + k)
        sec, nsec = np.divmod(ns, _NS)
        half = 0.5 * theta
        xy = v[:, 0:2]
        q = np.column_stack((_trig(math.sin, half), _trig(math.cos, half)))
        names = ["odom", "tf", "cmd", "state", *self._extra]
        if self.simulation:
            names.append("truth")
        for name in self._extra:
            rows[name + ".sec"], rows[name + ".nsec"] = sec, nsec
        if self.diag_names:
            diag = ticks.diag
            rows["diag.values"] = np.nan if diag is None else diag
        cov = ticks.covariance if ticks.covariance is not None else self.covariance
        rows["odom.pose_cov"], rows["odom.twist_cov"] = cov
        times = ns[:, None]
        for name in names:
            rows[name + ".seq"] = seq
            rows[name + ".times"] = times
        for name in ("odom", "tf"):
            rows[name + ".sec"], rows[name + ".nsec"] = sec, nsec
            rows[name + ".pose.xy"], rows[name + ".pose.q"] = xy, q
        rows["odom.v"], rows["odom.omega"] = v[:, 3], v[:, 4]
        rows["cmd.v"], rows["cmd.omega"] = v[:, 5], v[:, 6]
        rows["state.n"] = lengths
        rows["state.length"] = 30 + lengths
        if self.simulation:
            tx, ty, tth = v[:, 7], v[:, 8], v[:, 9]
            # map -> odom: the true pose composed with the inverse of the odometry pose
            phi = tth - theta
            c, s = _trig(math.cos, phi), _trig(math.sin, phi)
            half_phi, half_t = 0.5 * phi, 0.5 * tth
            rows["tf.map.sec"], rows["tf.map.nsec"] = sec, nsec
            rows["tf.map.xy"] = np.column_stack((tx - c * x + s * y, ty - s * x - c * y))
            rows["tf.map.q"] = np.column_stack((_trig(math.sin, half_phi),
                                                _trig(math.cos, half_phi)))
            rows["truth.sec"], rows["truth.nsec"] = sec, nsec
            rows["truth.pose.xy"] = v[:, 7:9]
            rows["truth.pose.q"] = np.column_stack((_trig(math.sin, half_t),
                                                    _trig(math.cos, half_t)))
