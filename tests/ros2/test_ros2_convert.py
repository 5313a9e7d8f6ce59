import math

import numpy as np
import pytest

from mdle.core.backend import Command, Scan
from mdle.core.pose import Pose
from mdle.ros2 import types as msg
from mdle.ros2.convert import (
    ScanReader,
    mount_from_transforms,
    odometry_message,
    odometry_values,
    scan_message,
    static_transform,
    twist_message,
)
from mdle.rosmsg.cdr import CdrWriter


def test_a_twist_is_byte_for_byte_what_mdles_recordings_write() -> None:
    ours = twist_message(Command(0.3, -0.25)).serialize()
    recorded = CdrWriter().prim("d", 0.3, 0.0, 0.0, 0.0, 0.0, -0.25).bytes()
    assert ours == recorded


def test_an_odometry_message_reads_back_as_the_pose_and_speeds() -> None:
    m = odometry_message(12.5, Pose(1.5, -2.0, 2.9), 0.3, -0.1, "odom", "base_link")
    back = msg.Odometry.deserialize(m.serialize())
    assert (back.header.frame_id, back.child_frame_id) == ("odom", "base_link")
    assert (back.header.stamp.sec, back.header.stamp.nanosec) == (12, 500_000_000)
    pose, v, omega = odometry_values(back)
    assert (pose.x, pose.y, v, omega) == (1.5, -2.0, 0.3, -0.1)
    assert pose.theta == pytest.approx(2.9, abs=1e-12)


def _scan() -> Scan:
    bearings = np.radians(np.linspace(-90.0, 90.0, 181)) + 0.1
    ranges = np.linspace(0.5, 7.0, 181)
    valid = np.ones(181, dtype=bool)
    valid[[0, 50, 180]] = False
    ranges[~valid] = 8.0
    return Scan(ranges, bearings, valid, 3.0, 8.0)


def test_a_scan_goes_out_with_no_return_as_inf_and_comes_back_the_same() -> None:
    scan = _scan()
    m = scan_message(scan, 0.1, "laser", 3.0, 0.1)
    assert math.isinf(m.ranges[50]) and m.range_max == 8.0
    assert m.angle_min == pytest.approx(-math.pi / 2, abs=1e-6)  # the laser's own angles
    back = ScanReader().scan(msg.LaserScan.deserialize(m.serialize()), 0.1, 3.0)
    assert np.array_equal(back.valid, scan.valid)
    np.testing.assert_allclose(back.ranges, scan.ranges, rtol=1e-6)   # float32 on the wire
    np.testing.assert_allclose(back.bearings, scan.bearings, atol=1e-6)
    assert back.max_range == 8.0


def test_beams_outside_the_range_limits_or_not_finite_are_not_valid() -> None:
    m = msg.LaserScan(angle_min=-0.2, angle_max=0.2, angle_increment=0.1, range_min=0.1,
                      range_max=5.0, ranges=[0.05, float("nan"), 2.0, 5.5, float("-inf")])
    scan = ScanReader().scan(m, 0.0, 1.0)
    assert scan.valid.tolist() == [False, False, True, False, False]
    assert scan.ranges.tolist() == [5.0, 5.0, 2.0, 5.0, 5.0]


def test_a_clockwise_laser_is_read_so_that_bearings_increase() -> None:
    m = msg.LaserScan(angle_min=0.2, angle_max=-0.2, angle_increment=-0.1, range_min=0.0,
                      range_max=5.0, ranges=[1.0, 2.0, 3.0, 4.0, 4.5])
    scan = ScanReader().scan(m, 0.0, 1.0)
    np.testing.assert_allclose(scan.bearings, [-0.2, -0.1, 0.0, 0.1, 0.2], atol=1e-7)
    assert scan.ranges.tolist() == [4.5, 4.0, 3.0, 2.0, 1.0]


def test_the_laser_mount_composes_a_chain_of_static_transforms() -> None:
    chain = [static_transform(0.0, "base_link", "laser_mount", (0.2, 0.0, math.pi / 2)),
             static_transform(0.0, "laser_mount", "laser", (0.1, 0.0, 0.1)),
             static_transform(0.0, "base_link", "camera", (0.0, 0.3, 0.0))]
    x, y, yaw = mount_from_transforms(chain, "base_link", "laser") or (0, 0, 0)
    assert (x, y, yaw) == pytest.approx((0.2, 0.1, math.pi / 2 + 0.1))
    assert mount_from_transforms(chain, "base_link", "base_link") == (0.0, 0.0, 0.0)
    assert mount_from_transforms(chain, "base_link", "sonar") is None
    assert mount_from_transforms(chain, "odom", "laser") is None


@pytest.mark.parametrize(("fields", "message"), [
    ({"ranges": []}, "a scan without beams"),
    ({"ranges": [1.0, 2.0], "angle_increment": 0.0}, "a scan of 2 beams from angle"),
    ({"ranges": [1.0], "angle_min": float("nan")}, "a scan of 1 beams from angle nan"),
])
def test_a_scan_no_laser_sends_is_refused(fields: dict[str, object], message: str) -> None:
    m = msg.LaserScan(angle_min=-0.1, angle_increment=0.1, range_max=5.0)
    for key, value in fields.items():
        setattr(m, key, value)
    with pytest.raises(ValueError, match=message):
        ScanReader().scan(m, 0.0, 1.0)
