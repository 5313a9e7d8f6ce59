"""``mdle sim serve --ros2``: the embedded simulator as a ROS 2 robot (or a team of them).

:class:`SimServer` steps a :class:`~mdle.sim.SimBackend` (or, for a world with a
``robots:`` section, every robot of a :class:`~mdle.sim.team.TeamSim`, each in the
namespace of its name) in simulated time paced to the wall clock, and speaks ROS 2 as a
robot's driver does:

* it obeys ``cmd_vel`` (``geometry_msgs/Twist``, or ``TwistStamped``), stopping the
  robot when no command came for ``cmd_timeout`` wall seconds (a driver's watchdog);
* it publishes ``odom`` (``nav_msgs/Odometry``, with the covariances of the profile's
  odometry noise, :mod:`mdle.rosmsg.covariance`) and ``tf`` (``odom -> base_link``) at the
  robot's report cycle, ``scan`` (``sensor_msgs/LaserScan``) at each new scan of the
  ladar, ``tf_static`` (``base_link -> laser``, the profile's mount) once, latched, and
  ``/clock`` (``rosgraph_msgs/Clock``) at every step.

The simulator's timing model (command latency, report cycle, scan latency) applies as in
``mdle run``, so a plan run over ``--backend ros2`` against it meets the same robot, plus
the transport's own delay.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mdle.core.backend import STOP, Command, Scan
from mdle.core.errors import BackendError
from mdle.rosmsg.covariance import OdometryCovariance

__all__ = ["ServeOptions", "SimServer"]


@dataclass(frozen=True)
class ServeOptions:
    """How :class:`SimServer` runs (seconds unless stated)."""

    domain: int = 0
    """The DDS domain (ROS_DOMAIN_ID)."""
    namespace: str = ""
    """Canonical namespace of a lone robot; a team's robots go under it, each in its name."""
    step: float = 0.01
    """Simulated seconds per step (the physics between two looks at ``cmd_vel``)."""
    speed: float = 1.0
    """Simulated seconds per wall second (1: real time)."""
    cmd_timeout: float = 0.5
    """Stop a robot that got no ``cmd_vel`` for this many wall seconds (0: never)."""
    twist_stamped: bool = False
    """Read ``geometry_msgs/TwistStamped`` on ``cmd_vel`` instead of ``Twist``."""


@dataclass
class _Served:
    """One robot on the wire: its backend, namespace, endpoints and what it last did."""

    name: str
    ns: str
    backend: Any
    cmd: Any
    odom: Any
    scan: Any
    tf: Any
    tf_static: Any
    frames: dict[str, str]
    period: float
    next_report: float = 0.0
    last_scan: Scan | None = None
    last_command: float = -math.inf
    moving: bool = False
    commands: int = 0
    published: dict[str, int] = field(default_factory=lambda: {"odom": 0, "scan": 0})
    #: the odometry's covariances, grown from the robot's odometry noise as it drives
    covariance: OdometryCovariance = field(default_factory=lambda: OdometryCovariance({}))


def _covariance(backend: Any) -> OdometryCovariance:
    """Return the odometry covariances of a simulated robot, from its profile's noise."""
    noise = backend.profile.odometry
    return OdometryCovariance({"distance": float(noise.distance), "turn": float(noise.turn),
                               "drift": float(noise.drift)})


class SimServer:
    """A simulated world's robots on ROS 2.

    Parameters
    ----------
    world : World
    seed, robot, sensing
        As :class:`~mdle.sim.SimBackend` takes them (``robot`` only for a lone robot).
    options : ServeOptions

    Raises
    ------
    BackendError
        Cyclone DDS is missing or the domain cannot be joined.
    WorldError
        A robot overlaps an obstacle (or another robot) at its start.
    """

    def __init__(self, world: Any, *, seed: int | None = None, robot: str | None = None,
                 sensing: str = "scan", options: ServeOptions | None = None) -> None:
        from mdle.ros2.dds import Node, QosKind
        from mdle.ros2.types import Clock
        from mdle.sim import SimBackend

        self.options = opt = options or ServeOptions()
        if not (math.isfinite(opt.step) and 0 < opt.step <= 1):
            raise BackendError(f"the simulation step must be in (0, 1] s, got {opt.step:g}")
        if not (math.isfinite(opt.speed) and 0 < opt.speed <= 100):
            raise BackendError(f"the speed must be in (0, 100], got {opt.speed:g}")
        if not (math.isfinite(opt.cmd_timeout) and opt.cmd_timeout >= 0):
            raise BackendError(f"the command timeout must be 0 (never) or more seconds, got "
                               f"{opt.cmd_timeout:g}")
        self.world = world
        self.team: Any = None
        self.node = Node(opt.domain, "")
        self.time = 0.0
        robots: list[tuple[str, str, Any]] = []
        if world.robots:
            from mdle.sim.team import TeamSim

            self.team = TeamSim(world, world.robots, seed=world.seed if seed is None else seed,
                                sensing=sensing)
            for m in self.team.members:
                robots.append((m.name, f"{opt.namespace}/{m.name}", m))
        else:
            kwargs: dict[str, Any] = {"seed": seed, "sensing": sensing}
            if robot:
                kwargs["robot"] = robot
            robots.append(("robot", opt.namespace, SimBackend(world, **kwargs)))
        self.robots = [self._serve(name, ns, backend) for name, ns, backend in robots]
        self._clock = self.node.writer("/clock", Clock, QosKind.CLOCK)
        for r in self.robots:
            self._publish_static(r)
            self._publish_state(r, force=True)

    def _serve(self, name: str, ns: str, backend: Any) -> _Served:
        from mdle.ros2.dds import QosKind
        from mdle.ros2.names import frame_id, ros_topic
        from mdle.ros2.types import LaserScan, Odometry, TFMessage, Twist, TwistStamped

        node = self.node
        frames = {k: frame_id(ns, k) for k in ("odom", "base_link", "laser")}
        cmd_type = TwistStamped if self.options.twist_stamped else Twist
        sip = backend.profile.sip_cycle
        return _Served(
            name, ns, backend,
            cmd=node.reader(ros_topic(ns, "cmd_vel"), cmd_type, QosKind.RELIABLE),
            odom=node.writer(ros_topic(ns, "odom"), Odometry, QosKind.RELIABLE),
            scan=node.writer(ros_topic(ns, "scan"), LaserScan, QosKind.SENSOR),
            tf=node.writer(ros_topic(ns, "tf"), TFMessage, QosKind.RELIABLE),
            tf_static=node.writer(ros_topic(ns, "tf_static"), TFMessage, QosKind.LATCHED),
            frames=frames, period=sip if sip > 0 else self.options.step,
            covariance=_covariance(backend))

    # ------------------------------------------------------------------ the loop

    def step(self) -> None:
        """Read the commands, move the robots one step, publish what is due."""
        from mdle.ros2.convert import time_of
        from mdle.ros2.types import Clock

        opt = self.options
        wall = time.monotonic()
        for r in self.robots:
            self._read_commands(r, wall)
        dt = opt.step
        if self.team is not None:
            self.team.step(dt)
        else:
            self.robots[0].backend.advance(dt)
        self.time += dt
        self._clock.write(Clock(time_of(self.time)))
        for r in self.robots:
            self._publish_state(r)

    def run(self, until: float | None = None,
            keep_going: Callable[[], bool] = lambda: True) -> None:
        """Step paced to the wall clock (at ``speed``) until ``until`` s or told to stop."""
        opt = self.options
        start = time.monotonic()
        t0 = self.time
        while keep_going() and (until is None or self.time < until - 1e-9):
            self.step()
            due = start + (self.time - t0) / opt.speed
            lag = due - time.monotonic()
            if lag > 0:
                time.sleep(lag)
            elif lag < -1.0:  # far behind (a loaded machine): do not race to catch up
                start -= lag

    def close(self) -> None:
        """Stop every robot (their drivers' last act)."""
        for r in self.robots:
            r.backend.stop()

    # ------------------------------------------------------------------ helpers

    def _read_commands(self, r: _Served, wall: float) -> None:
        from mdle.ros2.dds import take

        got = take(r.cmd, 64)
        if got:
            m = got[-1]
            tw = m.twist if self.options.twist_stamped else m
            r.backend.command(Command(float(tw.linear.x), float(tw.angular.z)))
            r.last_command = wall
            r.moving = tw.linear.x != 0.0 or tw.angular.z != 0.0
            r.commands += len(got)
        elif (r.moving and self.options.cmd_timeout > 0
              and wall - r.last_command > self.options.cmd_timeout):
            r.backend.command(STOP)  # the driver's watchdog: the controller went quiet
            r.moving = False

    def _publish_static(self, r: _Served) -> None:
        from mdle.ros2.convert import static_transform
        from mdle.ros2.types import TFMessage

        mount = r.backend.laser_mount
        r.tf_static.write(TFMessage([static_transform(self.time, r.frames["base_link"],
                                                      r.frames["laser"], mount)]))

    def _publish_state(self, r: _Served, force: bool = False) -> None:
        from mdle.ros2.convert import odometry_message, scan_message
        from mdle.ros2.types import TFMessage, Transform, TransformStamped, Vector3

        obs = r.backend.observe()
        if force or self.time >= r.next_report - 1e-9:  # a report is due
            r.next_report += r.period
            pose = np.array([[obs.pose.x, obs.pose.y, obs.pose.theta]])
            cov = r.covariance.batch(pose) or r.covariance.constant
            odom = odometry_message(self.time, obs.pose, obs.v, obs.omega, r.frames["odom"],
                                    r.frames["base_link"], pose_covariance=cov[0].ravel(),
                                    twist_covariance=cov[1].ravel())
            r.odom.write(odom)
            p = odom.pose.pose
            r.tf.write(TFMessage([TransformStamped(
                odom.header, r.frames["base_link"],
                Transform(Vector3(p.position.x, p.position.y, 0.0), p.orientation))]))
            r.published["odom"] += 1
        scan = obs.scan
        if scan is not None and scan is not r.last_scan:
            r.last_scan = scan
            period = r.backend.laser_timing[0]
            r.scan.write(scan_message(scan, r.backend.laser_mount[2], r.frames["laser"],
                                      scan.stamp, period))
            r.published["scan"] += 1
