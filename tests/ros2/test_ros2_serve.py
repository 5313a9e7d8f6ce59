"""The simulator as a ROS 2 robot, stepped in this process (DDS on loopback)."""

from __future__ import annotations

import math
import time

import pytest

from mdle import sim
from mdle.ros2 import types as msg
from mdle.ros2.convert import twist_message
from mdle.ros2.dds import Node, QosKind, take
from mdle.ros2.serve import ServeOptions, SimServer


def _server(dds_env: dict[str, str], world: str, **kw: object) -> SimServer:
    options = ServeOptions(domain=int(dds_env["ROS_DOMAIN_ID"]), **kw)  # type: ignore[arg-type]
    return SimServer(sim.load_world(world), options=options)


def test_it_obeys_cmd_vel_publishes_at_its_rates_and_its_watchdog_stops_the_robot(
        dds_env: dict[str, str]) -> None:
    from mdle.core.backend import Command

    server = _server(dds_env, "empty", namespace="/bot", cmd_timeout=0.3)
    peer = Node(server.node.domain)
    cmd = peer.writer("/bot/cmd_vel", msg.Twist, QosKind.RELIABLE)
    odom = peer.reader("/bot/odom", msg.Odometry, QosKind.SENSOR)
    scans = peer.reader("/bot/scan", msg.LaserScan, QosKind.SENSOR)
    clock = peer.reader("/clock", msg.Clock, QosKind.SENSOR)
    robot = server.robots[0]
    end = time.monotonic() + 20
    while robot.commands == 0 and time.monotonic() < end:  # until the two have met
        cmd.write(twist_message(Command(0.3, 0.0)))
        server.step()
        time.sleep(0.01)
    odoms, t0 = robot.published["odom"], server.time
    for i in range(100):  # 1 s of simulated time, a command every 0.1 s
        if i % 10 == 0:
            cmd.write(twist_message(Command(0.3, 0.0)))
        server.step()
        time.sleep(0.001)
    assert robot.backend.observe().v > 0.1
    # the report cycle: the profile's, else every step
    assert robot.published["odom"] - odoms == pytest.approx(1.0 / robot.period, abs=1)
    assert robot.published["scan"] >= 5
    time.sleep(0.5)
    got = take(odom, 100)
    assert got and got[-1].header.frame_id == "bot/odom"
    assert got[-1].child_frame_id == "bot/base_link" and got[-1].pose.pose.position.x > 0
    assert take(scans, 100)[-1].header.frame_id == "bot/laser"
    last = take(clock, 1000)[-1].clock
    assert last.sec + last.nanosec * 1e-9 == pytest.approx(server.time, abs=1e-6)
    assert server.time == pytest.approx(t0 + 1.0)
    # no command for longer than the watchdog's limit: the server stops the robot
    for _ in range(200):
        server.step()
    assert not robot.moving and robot.backend.observe().v == pytest.approx(0.0, abs=1e-6)


def test_a_team_world_serves_each_robot_in_its_own_namespace(dds_env: dict[str, str],
                                                             repo: object) -> None:
    from pathlib import Path

    assert isinstance(repo, Path)
    server = _server(dds_env, str(repo / "plans/team/pair.world.yaml"), namespace="/lab")
    assert [r.ns for r in server.robots] == ["/lab/leader", "/lab/follower"]
    assert server.robots[1].frames["base_link"] == "lab/follower/base_link"
    server.step()
    assert all(r.published["odom"] >= 1 for r in server.robots)


def test_every_endpoint_announces_its_ros2_type_hash_in_user_data(
        dds_env: dict[str, str]) -> None:
    from cyclonedds.builtin import (
        BuiltinDataReader,
        BuiltinTopicDcpsPublication,
        BuiltinTopicDcpsSubscription,
    )
    from cyclonedds.qos import Policy

    from mdle.ros2.typehash import type_hash

    server = _server(dds_env, "empty")
    peer = Node(server.node.domain)
    expected = {("rt/odom", "nav_msgs::msg::dds_::Odometry_"): "nav_msgs/msg/Odometry",
                ("rt/scan", "sensor_msgs::msg::dds_::LaserScan_"): "sensor_msgs/msg/LaserScan",
                ("rt/tf", "tf2_msgs::msg::dds_::TFMessage_"): "tf2_msgs/msg/TFMessage",
                ("rt/clock", "rosgraph_msgs::msg::dds_::Clock_"): "rosgraph_msgs/msg/Clock",
                ("rt/cmd_vel", "geometry_msgs::msg::dds_::Twist_"): "geometry_msgs/msg/Twist"}
    readers = [BuiltinDataReader(peer.participant, kind)
               for kind in (BuiltinTopicDcpsPublication, BuiltinTopicDcpsSubscription)]
    seen: dict[tuple[str, str], bytes | None] = {}
    end = time.monotonic() + 10
    while time.monotonic() < end and not set(expected) <= set(seen):
        for reader in readers:
            for s in reader.take(64):
                data = s.qos[Policy.Userdata]
                seen[(s.topic_name, s.type_name)] = None if data is None else data.data
        time.sleep(0.05)
    for key, ros_type in expected.items():
        assert seen.get(key) == f"typehash={type_hash(ros_type)};".encode(), (key, seen)


def test_odometry_carries_the_covariance_of_the_robots_noise_model(
        dds_env: dict[str, str]) -> None:
    from mdle.core.backend import Command
    from mdle.sim.world_yaml import parse_world

    # a heading drift only (2 deg per sqrt(m)): the path stays smooth, so the reports the
    # reader kept measure the path the model has summed
    world = parse_world("name: noisy\nrobot:\n  profile: ideal\n"
                        "  odometry: {distance: 0, turn: 0, drift: 2}\n")
    server = SimServer(world, options=ServeOptions(domain=int(dds_env["ROS_DOMAIN_ID"]),
                                                   namespace="/bot"))
    peer = Node(server.node.domain)
    cmd = peer.writer("/bot/cmd_vel", msg.Twist, QosKind.RELIABLE)
    odom = peer.reader("/bot/odom", msg.Odometry, QosKind.SENSOR)
    robot = server.robots[0]
    end = time.monotonic() + 20
    while robot.commands == 0 and time.monotonic() < end:
        cmd.write(twist_message(Command(0.5, 0.0)))
        server.step()
        time.sleep(0.01)
    for i in range(100):
        if i % 10 == 0:
            cmd.write(twist_message(Command(0.5, 0.0)))
        server.step()
        time.sleep(0.001)
    time.sleep(0.5)
    got = take(odom, 1000)
    assert len(got) >= 2  # the reader keeps the last few
    first, last = got[0].pose.covariance, got[-1].pose.covariance
    # nearly straight ahead: the path is the distance from the start
    path = math.hypot(got[-1].pose.pose.position.x, got[-1].pose.pose.position.y)
    var_yaw = math.radians(2.0) ** 2 * path
    assert path > 0.3
    assert last[35] == pytest.approx(var_yaw, rel=0.05)
    assert last[0] == last[7] == pytest.approx(var_yaw * path ** 2 / 3, rel=0.1)
    assert last[0] > first[0] >= 0.0
    assert list(got[-1].twist.covariance) == [0.0] * 36  # the measured motion is exact
    # z, roll, pitch and the cross terms stay 0
    assert [c for i, c in enumerate(last) if i not in (0, 7, 35)] == [0.0] * 33
