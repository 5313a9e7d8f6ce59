"""The hand-written CDR encoders and schema texts against two independent implementations.

mcap-ros2-support decodes with the schema text mdle writes into the file; rosbags decodes
with its own Humble and Jazzy definitions. Both must read back exactly what was encoded,
and the schema texts must declare the same fields as rosbags' type stores.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from mdle.ros import cdr
from mdle.ros.markers import obstacle_markers, outlines
from mdle.ros.msgdefs import DEFINITIONS, schema_text


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


@pytest.mark.parametrize("t, yaw", [(0.0, 0.0), (12.5, 0.7), (3.25, -3.1), (1e6, math.pi)])
def test_odometry(t: float, yaw: float, store: str) -> None:
    ns = round(t * 1e9)
    data = cdr.OdometryEncoder()(ns, 1.5, -2.25, yaw, 0.3, -0.1)
    mine, theirs = _decode("nav_msgs/msg/Odometry", data, store)
    for m in (mine, theirs):
        assert (m.header.stamp.sec, m.header.stamp.nanosec) == divmod(ns, 10**9)
        assert (m.header.frame_id, m.child_frame_id) == ("odom", "base_link")
        p = m.pose.pose
        assert (p.position.x, p.position.y, p.position.z) == (1.5, -2.25, 0.0)
        q = p.orientation
        assert (q.x, q.y, q.z, q.w) == (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
        assert (m.twist.twist.linear.x, m.twist.twist.angular.z) == (0.3, -0.1)
        assert list(m.pose.covariance) == [0.0] * 36


def test_transforms_pose_twist_string(store: str) -> None:
    data = cdr.TransformsEncoder([("odom", "base_link"), ("map", "odom")])(
        2_000_000_001, (1.0, 2.0, 0.5), (3.0, -4.0, -1.0))
    mine, theirs = _decode("tf2_msgs/msg/TFMessage", data, store)
    for m in (mine, theirs):
        a, b = m.transforms
        assert (a.header.frame_id, a.child_frame_id, b.header.frame_id, b.child_frame_id) == (
            "odom", "base_link", "map", "odom")
        assert (b.header.stamp.sec, b.header.stamp.nanosec) == (2, 1)
        assert (b.transform.translation.x, b.transform.translation.y) == (3.0, -4.0)
        assert b.transform.rotation.z == math.sin(-0.5)
    mine, theirs = _decode("geometry_msgs/msg/PoseStamped",
                           cdr.PoseStampedEncoder()(7, 1.0, 2.0, 3.0), store)
    assert theirs.header.frame_id == "map" and theirs.pose.orientation.w == math.cos(1.5)
    mine, theirs = _decode("geometry_msgs/msg/Twist", cdr.encode_twist(0.5, -0.25), store)
    assert (theirs.linear.x, theirs.angular.z, mine.linear.x) == (0.5, -0.25, 0.5)
    text = '{"path":"main/é","t":1}'
    mine, theirs = _decode("std_msgs/msg/String", cdr.encode_string(text), store)
    assert mine.data == theirs.data == text


@pytest.mark.parametrize("n", [0, 1, 2, 181, 361])
def test_scan(n: int, store: str) -> None:
    rng = np.random.default_rng(n)
    ranges = rng.uniform(0, 10, n).astype("<f4")
    ranges[::7] = np.inf
    enc = cdr.ScanEncoder("laser", -1.5, 1.5, 0.01, 0.0, 10.0, n)
    mine, theirs = _decode("sensor_msgs/msg/LaserScan", enc(5_500_000_000, ranges), store)
    for m in (mine, theirs):
        assert m.header.frame_id == "laser" and m.header.stamp.sec == 5
        assert (m.angle_min, m.angle_max, m.range_max) == (-1.5, 1.5, 10.0)
        np.testing.assert_array_equal(np.asarray(m.ranges, dtype=np.float32), ranges)
        assert len(m.intensities) == 0
    with pytest.raises(ValueError):
        enc(0, ranges[:-1] if n else np.zeros(1, "<f4"))


def test_markers_of_every_reference_world(store: str) -> None:
    import sim

    for name in sim.list_worlds():
        world = sim.load_world(name)
        lines = outlines(world)
        mine, theirs = _decode("visualization_msgs/msg/MarkerArray",
                               obstacle_markers(world, 0), store)
        assert len(mine.markers) == len(theirs.markers) == len(lines)
        for marker, line in zip(theirs.markers, lines, strict=True):
            assert marker.ns == "obstacles" and marker.type == 4
            assert [(p.x, p.y) for p in marker.points] == line
