"""The hand-packed CDR messages and schema texts against two independent implementations.

mcap-ros2-support decodes with the schema text mdle writes into the file; rosbags decodes
with its own Humble and Jazzy definitions. Both must read back exactly what was encoded,
and the schema texts must declare the same fields as rosbags' type stores.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mdle.record.markers import PathPieces, obstacle_markers, outlines, path_marker
from mdle.rosmsg.msgdefs import DEFINITIONS, schema_text


def _decode(name: str, data: bytes, store: str) -> tuple[Any, Any]:
    from mcap_ros2._dynamic import generate_dynamic
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE if store == "humble" else Stores.ROS2_JAZZY)
    mine = generate_dynamic(name, schema_text(name))[name](data)
    theirs = ts.deserialize_cdr(data, name)
    # rosbags serialises it back to the very same bytes
    assert bytes(ts.serialize_cdr(theirs, name)) == data
    return mine, theirs


def test_schema_texts_declare_the_type_stores_fields(store: str) -> None:
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE if store == "humble" else Stores.ROS2_JAZZY)
    for name in DEFINITIONS:
        parsed = get_types_from_msg(DEFINITIONS[name], name)[name]
        consts, fields = parsed
        theirs_consts, theirs_fields = ts.fielddefs[name]
        assert [f[0] for f in fields] == [f[0] for f in theirs_fields], name
        for (fname, ftype), (_, ttype) in zip(fields, theirs_fields, strict=True):
            assert repr(ftype).replace("Nodetype.", "") == repr(ttype).replace(
                "Nodetype.", "") or ftype == ttype, (name, fname)
        assert {c[0] for c in consts} <= {c[0] for c in theirs_consts}


def _records(tmp_path: Path, write: Any) -> dict[str, list[tuple[int, int, bytes]]]:
    """Write records with ``write(McapFile, channels)``; return (log time, sequence, data)
    of each message by topic, read back with the mcap library's strict reader."""
    from mcap.reader import make_reader

    from mdle.record.mcap_file import McapFile
    from tests.ros.conftest import mcap_doctor

    path = tmp_path / "m.mcap"
    out = McapFile(path, chunk_size=300)  # several chunks: indexes across chunks
    types = {"/odom": "nav_msgs/msg/Odometry", "/tf": "tf2_msgs/msg/TFMessage",
             "/cmd_vel": "geometry_msgs/msg/Twist",
             "/ground_truth": "geometry_msgs/msg/PoseStamped",
             "/mdle/state": "std_msgs/msg/String", "/scan": "sensor_msgs/msg/LaserScan"}
    channels = {t: out.channel(t, out.schema(name, "ros2msg", schema_text(name).encode()))
                for t, name in types.items()}
    write(out, channels)
    out.finish()
    mcap_doctor(path)  # the strict validation, every message decoded
    found: dict[str, list[tuple[int, int, bytes]]] = {}
    with open(path, "rb") as f:
        for _, channel, m in make_reader(f, validate_crcs=True).iter_messages(
                log_time_order=True):
            found.setdefault(channel.topic, []).append((m.log_time, m.sequence, m.data))
    return found


def _encoder(out: Any, ch: dict[str, int], simulation: bool = True) -> Any:
    from mdle.record.tick import TickEncoder

    return TickEncoder(out, ch["/odom"], ch["/tf"], ch["/cmd_vel"], ch["/mdle/state"],
                       ch["/ground_truth"] if simulation else 0, ch["/scan"],
                       ("map", "odom", "base_link"))


def _ticks(*ticks: tuple[Any, ...], scans: tuple[Any, ...] = ()) -> Any:
    """A batch of ticks (ns, x, y, theta, v, omega, cmd_v, cmd_omega, truth, line) and
    scans (the tick each comes before, ns, stamp, float32 ranges)."""
    from mdle.record.tick import Ticks

    batch = Ticks(np.array([t[0] for t in ticks], np.int64),
                  np.array([(*t[1:8], *(t[8] or (math.nan,) * 3)) for t in ticks],
                           np.float64).reshape(-1, 10),
                  [t[9] for t in ticks])
    if scans:
        batch.scan_at = [s[0] for s in scans]
        batch.scan_ns = np.array([s[1] for s in scans], np.int64)
        batch.stamps = np.array([s[2] for s in scans], np.int64)
        batch.ranges = np.stack([s[3] for s in scans])
    return batch


@pytest.mark.parametrize("t, yaw", [(0.0, 0.0), (12.5, 0.7), (3.25, -3.1), (1e6, math.pi)])
def test_a_simulated_tick(tmp_path: Path, t: float, yaw: float, store: str) -> None:
    ns = round(t * 1e9)
    truth = (3.0, -4.0, yaw + 0.25)
    line = '{"path":"main/é","t":1}'

    def write(out: Any, ch: dict[str, int]) -> None:
        enc = _encoder(out, ch)
        # the third tick is the one checked; sequences count on across batches and chunks
        rows = [(ns + k, 1.5, -2.25, yaw, 0.3, -0.1, 0.5, -0.25, truth, line * k)
                for k in range(3)]
        enc.write(_ticks(*rows[:2]))
        enc.write(_ticks(rows[2]))
    found = _records(tmp_path, write)
    assert sorted(found) == ["/cmd_vel", "/ground_truth", "/mdle/state", "/odom", "/tf"]
    for topic, msgs in found.items():
        assert [(m[0], m[1]) for m in msgs] == [(ns + k, k) for k in range(3)], topic
    at = ns + 2
    for m in (_decode("nav_msgs/msg/Odometry", found["/odom"][2][2], store)):
        assert (m.header.stamp.sec, m.header.stamp.nanosec) == divmod(at, 10**9)
        assert (m.header.frame_id, m.child_frame_id) == ("odom", "base_link")
        p = m.pose.pose
        assert (p.position.x, p.position.y, p.position.z) == (1.5, -2.25, 0.0)
        q = p.orientation
        assert (q.x, q.y, q.z, q.w) == (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
        assert (m.twist.twist.linear.x, m.twist.twist.angular.z) == (0.3, -0.1)
        tw = m.twist.twist
        assert (tw.linear.y, tw.linear.z, tw.angular.x, tw.angular.y) == (0.0,) * 4
        assert list(m.pose.covariance) == [0.0] * 36 == list(m.twist.covariance)
    for m in _decode("tf2_msgs/msg/TFMessage", found["/tf"][2][2], store):
        a, b = m.transforms
        assert (a.header.frame_id, a.child_frame_id, b.header.frame_id, b.child_frame_id) == (
            "odom", "base_link", "map", "odom")
        assert (b.header.stamp.sec, b.header.stamp.nanosec) == divmod(at, 10**9)
        assert (a.transform.translation.x, a.transform.translation.y) == (1.5, -2.25)
        assert a.transform.rotation.z == math.sin(yaw / 2)
        # map -> odom composed with odom -> base_link is the true pose
        phi = 2 * math.atan2(b.transform.rotation.z, b.transform.rotation.w)
        tr = b.transform.translation
        assert math.isclose(tr.x + math.cos(phi) * 1.5 + math.sin(phi) * 2.25, 3.0)
        assert math.isclose(tr.y + math.sin(phi) * 1.5 - math.cos(phi) * 2.25, -4.0)
        assert math.isclose(math.remainder(phi + yaw - truth[2], math.tau), 0.0,
                            abs_tol=1e-12)
    for m in _decode("geometry_msgs/msg/PoseStamped", found["/ground_truth"][2][2], store):
        assert m.header.frame_id == "map" and m.pose.orientation.w == math.cos(truth[2] / 2)
        assert (m.pose.position.x, m.pose.position.y) == (3.0, -4.0)
    for m in _decode("geometry_msgs/msg/Twist", found["/cmd_vel"][2][2], store):
        assert (m.linear.x, m.linear.y, m.angular.z) == (0.5, 0.0, -0.25)
    for m in _decode("std_msgs/msg/String", found["/mdle/state"][2][2], store):
        assert m.data == line * 2


def test_a_robot_tick(tmp_path: Path, store: str) -> None:
    found = _records(tmp_path, lambda out, ch: _encoder(out, ch, False).write(_ticks(
        (7, 1.0, 2.0, 3.0, 0.1, 0.2, 0.3, 0.4, (9.0, 9.0, 9.0), ""))))
    assert sorted(found) == ["/cmd_vel", "/mdle/state", "/odom", "/tf"]  # no ground truth
    for m in _decode("tf2_msgs/msg/TFMessage", found["/tf"][0][2], store):
        (only,) = m.transforms  # odom -> base_link alone: no map on a robot
        assert (only.header.frame_id, only.child_frame_id) == ("odom", "base_link")
        assert only.transform.rotation.w == math.cos(1.5)
    for m in _decode("std_msgs/msg/String", found["/mdle/state"][0][2], store):
        assert m.data == ""


def test_a_simulated_sample_without_its_true_pose(tmp_path: Path, store: str) -> None:
    found = _records(tmp_path, lambda out, ch: _encoder(out, ch).write(_ticks(
        (8, 1.0, 2.0, 3.0, 0.1, 0.2, 0.3, 0.4, None, "x"))))
    # NaN (unknown, as the trace's nulls say), not a made-up pose
    for m in _decode("geometry_msgs/msg/PoseStamped", found["/ground_truth"][0][2], store):
        assert all(math.isnan(v) for v in (m.pose.position.x, m.pose.position.y,
                                           m.pose.orientation.z, m.pose.orientation.w))
    for m in _decode("tf2_msgs/msg/TFMessage", found["/tf"][0][2], store):
        assert m.transforms[0].transform.translation.x == 1.0
        assert math.isnan(m.transforms[1].transform.translation.x)


@pytest.mark.parametrize("n", [0, 1, 2, 181, 361])
def test_scan(tmp_path: Path, n: int, store: str) -> None:
    rng = np.random.default_rng(n)
    ranges = rng.uniform(0, 10, n).astype("<f4")
    ranges[::7] = np.inf

    def write(out: Any, ch: dict[str, int]) -> None:
        enc = _encoder(out, ch)
        with pytest.raises(ValueError, match="before any `laser`"):
            enc.check(ranges)
        enc.geometry("laser", -1.5, 1.5, 0.01, 0.0, 10.0, n, 0.1, 1e-4)
        enc.write(_ticks(scans=((0, 6_000_000_000, 5_500_000_000, ranges),)))
        with pytest.raises(ValueError):
            enc.check(ranges[:-1] if n else np.zeros(1, "<f4"))
        with pytest.raises(ValueError):
            enc.check(ranges.astype(">f4"))
    ((log_time, seq, data),) = _records(tmp_path, write)["/scan"]
    assert (log_time, seq) == (6_000_000_000, 0)
    for m in _decode("sensor_msgs/msg/LaserScan", data, store):
        assert m.header.frame_id == "laser" and m.header.stamp.sec == 5
        assert m.header.stamp.nanosec == 500_000_000
        assert (m.angle_min, m.angle_max, m.range_max) == (-1.5, 1.5, 10.0)
        assert m.scan_time == np.float32(0.1) and m.time_increment == np.float32(1e-4)
        np.testing.assert_array_equal(np.asarray(m.ranges, dtype=np.float32), ranges)
        assert len(m.intensities) == 0


def test_scans_not_at_every_tick(tmp_path: Path, store: str) -> None:
    """Two scans before one tick, none before others, one after the last: each in its
    place in the stream, indexed there, its sequence and times its own."""
    from mcap.records import Channel, Message
    from mcap.stream_reader import StreamReader

    scans = [np.full(3, v, "<f4") for v in (1.0, 2.0, 3.0, 4.0)]

    def write(out: Any, ch: dict[str, int]) -> None:
        enc = _encoder(out, ch)
        enc.geometry("laser", -1.0, 1.0, 1.0, 0.0, 5.0, 3)
        ticks = [(10 * k, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, None, "é" * k) for k in range(3)]
        enc.write(_ticks(*ticks, scans=((1, 5, 4, scans[0]), (1, 9, 8, scans[1]),
                                        (3, 25, 24, scans[2]))))
        enc.write(_ticks(scans=((0, 30, 29, scans[3]),)))
    found = _records(tmp_path, write)
    assert [(t, q) for t, q, _ in found["/scan"]] == [(5, 0), (9, 1), (25, 2), (30, 3)]
    for (_, _, data), want in zip(found["/scan"], scans, strict=True):
        for m in _decode("sensor_msgs/msg/LaserScan", data, store):
            np.testing.assert_array_equal(np.asarray(m.ranges, np.float32), want)
    for k, (_, _, data) in enumerate(found["/mdle/state"]):
        for m in _decode("std_msgs/msg/String", data, store):
            assert m.data == "é" * k
    order = []
    with open(tmp_path / "m.mcap", "rb") as f:
        topics = {}
        for r in StreamReader(f).records:
            if isinstance(r, Channel):
                topics[r.id] = r.topic
            elif isinstance(r, Message) and topics[r.channel_id] in ("/scan", "/odom"):
                order.append((topics[r.channel_id], r.log_time))
    # the stream as a tick-at-a-time writer makes it: a tick's scans, then its records
    assert order == [("/odom", 0), ("/scan", 5), ("/scan", 9), ("/odom", 10), ("/odom", 20),
                     ("/scan", 25), ("/scan", 30)]


def test_markers_of_every_reference_world(store: str) -> None:
    from mdle import sim

    for name in sim.list_worlds():
        world = sim.load_world(name)
        lines = outlines(world)
        mine, theirs = _decode("visualization_msgs/msg/MarkerArray",
                               obstacle_markers(world, 0), store)
        assert len(mine.markers) == len(theirs.markers) == len(lines)
        for marker, line in zip(theirs.markers, lines, strict=True):
            assert marker.ns == "obstacles" and marker.type == 4
            assert [(p.x, p.y) for p in marker.points] == line


def test_path_pieces_are_the_general_writers_bytes(store: str) -> None:
    rng = np.random.default_rng(4)
    for frame in ("odom", "leader/odom", "o"):
        pieces = PathPieces(frame)
        for n in (1, 2, 7, 11):
            xy = rng.normal(scale=5.0, size=(n, 2))
            points = [(float(x), float(y)) for x, y in xy]
            ns = int(rng.integers(0, 2**40))
            data = pieces.piece(ns, n * 3, xy)
            assert data == path_marker(ns, frame, n * 3, points)
            mine, theirs = _decode("visualization_msgs/msg/Marker", data, store)
            assert (theirs.header.frame_id, theirs.id, theirs.type, theirs.ns) == (
                frame, n * 3, 4, "path")
            assert [(p.x, p.y, p.z) for p in theirs.points] == [(x, y, 0.0) for x, y in points]
            assert len(mine.points) == n
