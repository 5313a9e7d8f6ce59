"""The backend against a fake ROS 2 robot in this process (DDS on loopback)."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Iterator
from typing import Any

import pytest

from mdle.core.backend import Command, RobotLimits
from mdle.core.errors import BackendError
from mdle.ros2 import types as msg
from mdle.ros2.backend import Ros2Backend, Ros2Options
from mdle.ros2.convert import odometry_message, static_transform
from mdle.ros2.dds import Node, QosKind, take
from mdle.ros2.names import ros_topic

LIMITS = RobotLimits(0.5, 0.2, 1.0)
NS = "/r1"


class FakeRobot:
    """A ROS 2 robot's driver: odometry and scans at 50 Hz, the laser's mount latched."""

    def __init__(self, domain: int, stamped: bool = False) -> None:
        node = self.node = Node(domain, "")
        self.odom = node.writer(ros_topic(NS, "odom"), msg.Odometry, QosKind.RELIABLE)
        self.scan = node.writer(ros_topic(NS, "scan"), msg.LaserScan, QosKind.SENSOR)
        # kept: a latched message lives as long as its writer
        self.tf = node.writer(ros_topic(NS, "tf_static"), msg.TFMessage, QosKind.LATCHED)
        self.cmd = node.reader(ros_topic(NS, "cmd_vel"),
                               msg.TwistStamped if stamped else msg.Twist, QosKind.RELIABLE)
        # base_link -> mount (turned 90 deg) -> laser (turned back by 60 deg): yaw 30 deg
        self.tf.write(msg.TFMessage([
            static_transform(0.0, "r1/base_link", "r1/mount", (0.1, 0.0, math.pi / 2)),
            static_transform(0.0, "r1/mount", "r1/laser", (0.0, 0.0, -math.pi / 3))]))
        self.pose = (5.0, 3.0, math.pi / 2)
        self.scans = True
        self.commands: list[Any] = []
        self._halt = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        from mdle.core.pose import Pose

        while not self._halt.is_set():
            t = time.time()
            self.odom.write(odometry_message(t, Pose(*self.pose), 0.0, 0.0, "r1/odom",
                                             "r1/base_link"))
            if self.scans:
                self.scan.write(msg.LaserScan(
                    msg.Header(msg.Time(int(t), 0), "r1/laser"), -math.pi / 2, math.pi / 2,
                    math.pi / 2, 0.0, 0.1, 0.05, 8.0, [1.0, 2.0, 3.0]))
            self.commands += take(self.cmd, 64)
            self._halt.wait(0.02)

    def close(self) -> None:
        self._halt.set()
        self._thread.join(timeout=5)
        self.commands += take(self.cmd, 64)


@pytest.fixture
def robot(dds_env: dict[str, str]) -> Iterator[FakeRobot]:
    r = FakeRobot(int(dds_env["ROS_DOMAIN_ID"]))
    yield r
    r.close()


def _backend(dds_env: dict[str, str], **kw: Any) -> Ros2Backend:
    return Ros2Backend(LIMITS, options=Ros2Options(namespace=NS,
                                                   domain=int(dds_env["ROS_DOMAIN_ID"]), **kw))


def test_odometry_counts_from_the_start_and_the_mount_comes_from_tf_static(
        robot: FakeRobot, dds_env: dict[str, str]) -> None:
    with _backend(dds_env) as backend:
        obs = backend.observe()
        assert (obs.pose.x, obs.pose.y, obs.pose.theta) == pytest.approx((0, 0, 0), abs=1e-12)
        assert backend.mount_source == "tf_static"
        assert backend.laser_mount == pytest.approx((0.1, 0.0, math.pi / 6))
        assert obs.scan is not None
        assert obs.scan.bearings == pytest.approx([-math.pi / 3, math.pi / 6, 2 * math.pi / 3])
        robot.pose = (5.0, 4.0, math.pi / 2 + 0.2)  # 1 m ahead of where it started, turned
        time.sleep(0.2)
        pose = backend.observe().pose
        assert (pose.x, pose.y, pose.theta) == pytest.approx((1.0, 0.0, 0.2), abs=1e-9)


def test_commands_are_clamped_and_a_stale_scan_stops_the_robot(
        robot: FakeRobot, dds_env: dict[str, str]) -> None:
    backend = _backend(dds_env)
    try:
        backend.command(Command(3.0, -5.0))
        robot.scans = False
        time.sleep(0.8)
        with pytest.raises(BackendError, match="no scan on /r1/scan for"):
            backend.observe()
        assert backend.failure is not None
    finally:
        backend.close()
    time.sleep(0.2)
    robot.close()
    sent = [(c.linear.x, c.angular.z) for c in robot.commands]
    assert sent[0] == (0.5, -1.0)     # the limits' speed and turn rate
    assert sent[-1] == (0.0, 0.0)


def test_odometry_that_is_not_a_number_stops_the_robot(robot: FakeRobot,
                                                       dds_env: dict[str, str]) -> None:
    with _backend(dds_env) as backend:
        backend.observe()
        robot.pose = (math.nan, 3.0, 0.0)
        time.sleep(0.2)
        with pytest.raises(BackendError, match=r"malformed odometry on /r1/odom: pose \(nan"):
            backend.observe()


def test_twist_stamped_commands_carry_the_robot_frame(dds_env: dict[str, str]) -> None:
    robot = FakeRobot(int(dds_env["ROS_DOMAIN_ID"]), stamped=True)
    try:
        with _backend(dds_env, twist_stamped=True) as backend:
            backend.command(Command(0.2, 0.1))
        time.sleep(0.2)
    finally:
        robot.close()
    first, last = robot.commands[0], robot.commands[-1]
    assert first.header.frame_id == "r1/base_link" and first.header.stamp.sec > 0
    assert (first.twist.linear.x, first.twist.angular.z) == (0.2, 0.1)
    assert (last.twist.linear.x, last.twist.angular.z) == (0.0, 0.0)
