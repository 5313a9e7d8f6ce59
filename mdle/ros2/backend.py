"""A ROS 2 robot as an mdle backend: ``scan`` and ``odom`` in, ``cmd_vel`` out.

:class:`Ros2Backend` implements :class:`mdle.core.backend.Backend` on the wall clock (or on
``/clock`` with ``use_sim_time``) over Cyclone DDS, as a ROS 2 node would: it reads
``sensor_msgs/LaserScan`` on ``scan`` and ``nav_msgs/Odometry`` on ``odom`` (sensor-data
QoS, best effort), the laser's mount from ``tf_static`` (or the robot profile), and
writes ``geometry_msgs/Twist`` (or ``TwistStamped``) on ``cmd_vel``, all in the
namespace given. Odometry counts from where the robot was when the backend connected
(REP-105 ``odom`` frame, as the simulator's does), so a plan means the same here.

Safety: a scan or odometry older than its limit (a stopped driver, a lost peer) stops the
robot and ends the run with a :class:`~mdle.core.errors.BackendError`; :meth:`Ros2Backend.close`
(idempotent, safe from ``finally`` blocks) publishes a zero command and waits for the
robot's reliable readers to acknowledge it before leaving. An exit hook does the same if
a program ends without closing it.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from dataclasses import dataclass
from typing import Any, NoReturn

from mdle.core.backend import ClockMode, Command, Observation, RobotLimits, Scan
from mdle.core.errors import BackendError
from mdle.core.exit_hooks import ExitHooks, register_exit_hooks
from mdle.core.pose import Pose

__all__ = ["Ros2Backend", "Ros2Options"]

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Ros2Options:
    """How a :class:`Ros2Backend` meets its robot (seconds unless stated)."""

    namespace: str = ""
    """The robot's namespace, canonical (``""`` or ``/robot1``)."""
    domain: int = 0
    """The DDS domain (ROS_DOMAIN_ID)."""
    twist_stamped: bool = False
    """Write ``geometry_msgs/TwistStamped`` on ``cmd_vel`` instead of ``Twist``."""
    use_sim_time: bool = False
    """Take time from ``/clock`` (a simulator's), as ROS's ``use_sim_time`` does."""
    laser: bool = True
    """Wait for scans and stop when they go stale (False: a robot without a laser)."""
    mount: tuple[float, float, float] | None = None
    """The laser's pose on the robot (x, y, yaw: m, m, rad) when ``tf_static`` has none
    (from ``--robot``); None: ``tf_static`` or, failing it, the robot's centre."""
    first_data_timeout: float = 5.0
    """How long the first odometry (and scan) may take (discovery included)."""
    odom_timeout: float = 0.5
    """The newest odometry may be this old (wall clock); beyond it the robot is stopped."""
    scan_timeout: float = 0.5
    """The newest scan may be this old (wall clock); beyond it the robot is stopped."""
    tf_wait: float = 1.0
    """After the first scan, how long to wait for the mount on ``tf_static``."""
    goodbye_timeout: float = 0.5
    """On close, wait this long at most for the zero command's acknowledgement."""
    handle_sigterm: bool = False
    """Turn SIGTERM into SystemExit while connected (so ``finally`` blocks stop the
    robot), unless a handler is already installed (mdle's command line has one)."""


@dataclass
class _Newest:
    """The newest message of a topic and when it arrived (``time.monotonic()``)."""

    message: Any = None
    arrived: float = -math.inf
    count: int = 0


class Ros2Backend:
    """A ROS 2 robot as a :class:`~mdle.core.backend.Backend` (``clock = ClockMode.WALL``).

    Parameters
    ----------
    limits : RobotLimits
        What the robot can do: commands are clamped to it (a robot profile's, from
        ``--robot``).
    rate : float
        The control rate (Hz) the runtime ticks at; widens the age limits when ticks are
        long.
    options : Ros2Options

    Raises
    ------
    BackendError
        Cyclone DDS is missing, or no odometry (or scan) arrived in time: the message
        names the topic, its type and the domain.
    """

    clock: ClockMode = ClockMode.WALL

    def __init__(self, limits: RobotLimits, *, rate: float = 10.0,
                 options: Ros2Options | None = None) -> None:
        from mdle.ros2.convert import ScanReader
        from mdle.ros2.dds import Node, QosKind
        from mdle.ros2.names import frame_id
        from mdle.ros2.types import Clock, LaserScan, Odometry, TFMessage, Twist, TwistStamped

        if not rate > 0:
            raise BackendError(f"the control rate must be positive, got {rate} Hz")
        self._opt = opt = options or Ros2Options()
        self.limits = limits
        self.rate = rate
        self._odom_timeout = max(opt.odom_timeout, 2.0 / rate)
        self._scan_timeout = max(opt.scan_timeout, 2.0 / rate)
        self._node = Node(opt.domain, opt.namespace)
        node = self._node
        self.description = (f"ROS 2 robot{' ' + opt.namespace if opt.namespace else ''} "
                            f"(domain {opt.domain})")
        self._frame = frame_id(opt.namespace, "base_link")
        cmd_type = TwistStamped if opt.twist_stamped else Twist
        self._cmd = node.writer("cmd_vel", cmd_type, QosKind.RELIABLE)
        self._odom = node.reader("odom", Odometry, QosKind.SENSOR)
        self._scan = node.reader("scan", LaserScan, QosKind.SENSOR) if opt.laser else None
        self._tf_static = node.reader("tf_static", TFMessage, QosKind.LATCHED)
        self._clock_reader = (node.reader("/clock", Clock, QosKind.SENSOR)
                              if opt.use_sim_time else None)
        self._newest = {"odom": _Newest(), "scan": _Newest(), "clock": _Newest()}
        self._statics: dict[str, Any] = {}
        self._scan_reader = ScanReader()
        self._origin: tuple[float, float, float, float, float] | None = None
        self._t0 = time.monotonic()
        self._sim_t0: float | None = None
        self._tick_start: float | None = None
        self._tick_start_sim = 0.0
        self._closed = False
        self._lock = threading.Lock()
        #: The laser's pose on the robot (x, y, yaw), for recordings' frames: from
        #: tf_static, else the options' (the robot profile's), else None.
        self.laser_mount: tuple[float, float, float] | None = opt.mount
        self.laser_timing: tuple[float, float] | None = None
        self.mount_source = "profile" if opt.mount is not None else "none"
        #: Why the robot was lost (stale data), None while it is up (the REPL asks).
        self.failure: str | None = None
        self._exit_hooks: ExitHooks | None = None
        try:
            self._exit_hooks = register_exit_hooks(self, self._opt.handle_sigterm)
            self._await_first_data()
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------------ Backend API

    def observe(self) -> Observation:
        """Return the newest odometry and scan.

        Raises BackendError (after stopping the robot) when either is older than its limit.
        """
        if self._closed:
            raise BackendError(f"the connection to the {self.description} is closed")
        self._poll()
        now = time.monotonic()
        if self._tick_start is None:
            self._tick_start = now
        odom = self._newest["odom"]
        age = now - odom.arrived
        if age > self._odom_timeout:
            self._abort(f"no odometry on {self._node.topic_name('odom')} for {age:.2f} s "
                        f"(limit {self._odom_timeout:.2f} s): the robot's driver stopped or "
                        f"the link to it is lost")
        scan: Scan | None = None
        t = self._now()
        if self._scan is not None:
            newest = self._newest["scan"]
            age = now - newest.arrived
            if age > self._scan_timeout:
                self._abort(f"no scan on {self._node.topic_name('scan')} for {age:.2f} s "
                            f"(limit {self._scan_timeout:.2f} s): the laser stopped sending")
            scan = newest.message
        pose, v, omega = self._odometry(odom.message)
        return Observation(time=t, pose=pose, v=v, omega=omega, scan=scan)

    def command(self, cmd: Command) -> None:
        """Publish ``cmd`` on ``cmd_vel``, clamped to :attr:`limits`."""
        if self._closed:
            raise BackendError(f"the connection to the {self.description} is closed")
        if not (math.isfinite(cmd.v) and math.isfinite(cmd.omega)):
            self._abort(f"refusing a non-finite command (v = {cmd.v}, omega = {cmd.omega})")
        lim = self.limits
        v = min(max(cmd.v, -lim.max_reverse_speed), lim.max_speed)
        w = min(max(cmd.omega, -lim.max_turn_rate), lim.max_turn_rate)
        self._publish(Command(v, w))

    def advance(self, dt: float) -> float:
        """Wait until this tick's deadline (never longer); return the lateness, seconds.

        Ticks lie on a fixed grid from the first observation, on the wall clock, or on
        ``/clock`` with ``use_sim_time`` (then the wait also ends when ``/clock`` has been
        silent for the odometry's age limit: the next observation reports why).
        """
        if self._opt.use_sim_time:
            return self._advance_sim(dt)
        now = time.monotonic()
        start = self._tick_start if self._tick_start is not None else now
        deadline = start + dt
        if deadline > now:
            time.sleep(deadline - now)
            now = time.monotonic()
        lateness = max(0.0, now - deadline)
        self._tick_start = deadline if lateness < dt else now
        return lateness

    def stop(self) -> None:
        """Publish a zero command now (best effort: never raises)."""
        self._tick_start = None
        if self._closed:
            return
        try:
            self._publish(Command(0.0, 0.0))
        except Exception:  # noqa: BLE001 - a stop must not fail the way out
            _log.debug("publishing the stop failed", exc_info=True)

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` has run (the robot stopped and let go of)."""
        return self._closed

    def close(self) -> None:
        """Publish a zero command, wait for its acknowledgement, leave the domain.

        Idempotent; safe from ``finally`` blocks and exit hooks.
        """
        with self._lock:
            if self._closed:
                return
            self.stop()
            self._closed = True
        try:
            from cyclonedds.util import duration

            self._cmd.wait_for_acks(duration(seconds=self._opt.goodbye_timeout))
        except Exception:  # noqa: BLE001 - closing goes on whatever DDS says
            _log.debug("waiting for the stop's acknowledgement failed", exc_info=True)
        if self._exit_hooks is not None:
            self._exit_hooks.release()

    def __enter__(self) -> Ros2Backend:  # noqa: PYI034 (typing.Self needs Python 3.11)
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def stats(self) -> dict[str, int]:
        """Messages received: odometry, scans, clock."""
        return {k: n.count for k, n in self._newest.items()}

    # ------------------------------------------------------------------ data

    def _poll(self) -> None:
        """Take every message waiting; keep the newest of each topic."""
        from mdle.ros2.dds import take

        now = time.monotonic()
        odoms = take(self._odom, 64)
        if odoms:
            self._keep("odom", odoms[-1], now - _waited(odoms[-1]), len(odoms))
        if self._tf_static is not None:
            for m in take(self._tf_static, 16):
                for tf in m.transforms:
                    self._statics[tf.child_frame_id.lstrip("/")] = tf
        if self._clock_reader is not None:
            clocks = take(self._clock_reader, 256)
            if clocks:
                self._keep("clock", clocks[-1], now - _waited(clocks[-1]), len(clocks))
        if self._scan is not None:
            scans = take(self._scan, 16)
            if scans:
                self._newest["scan"].count += len(scans) - 1
                self._keep("scan", self._make_scan(scans[-1]), now - _waited(scans[-1]), 1)

    def _keep(self, topic: str, message: Any, arrived: float, count: int) -> None:
        newest = self._newest[topic]
        newest.message, newest.arrived = message, arrived
        newest.count += count

    def _make_scan(self, m: Any) -> Scan:
        from mdle.ros2.convert import mount_from_transforms, seconds

        odom = self._newest["odom"].message
        if self.mount_source != "tf_static" and odom is not None and self._statics:
            found = mount_from_transforms(self._statics.values(), odom.child_frame_id,
                                          m.header.frame_id)
            if found is not None:
                self.laser_mount, self.mount_source = found, "tf_static"
        if m.scan_time > 0 and self.laser_timing is None:
            self.laser_timing = (float(m.scan_time), float(m.time_increment))
        yaw = self.laser_mount[2] if self.laser_mount is not None else 0.0
        stamp = seconds(m.header.stamp)
        if self._opt.use_sim_time and self._sim_t0 is not None:
            at = stamp - self._sim_t0
        else:  # the sender's wall clock: its age, where the clocks plausibly agree
            age = time.time() - stamp
            at = self._now() - (age if 0.0 <= age < 1.0 else 0.0)
        try:
            return self._scan_reader.scan(m, yaw, at)
        except ValueError as exc:  # a broken laser or driver: stop rather than guess
            self._abort(f"a malformed scan on {self._node.topic_name('scan')}: {exc}")

    def _odometry(self, m: Any) -> tuple[Pose, float, float]:
        """Return the pose relative to the first odometry (REP-105 odom), v and omega."""
        from mdle.ros2.convert import odometry_values

        pose, v, omega = odometry_values(m)
        if not all(math.isfinite(a) for a in (pose.x, pose.y, pose.theta, v, omega)):
            self._abort(f"malformed odometry on {self._node.topic_name('odom')}: pose "
                        f"({pose.x}, {pose.y}, {pose.theta}), speeds ({v}, {omega})")
        if self._origin is None:
            th = pose.theta
            self._origin = (pose.x, pose.y, math.cos(th), math.sin(th), th)
        x0, y0, c, s, th0 = self._origin
        dx, dy = pose.x - x0, pose.y - y0
        th = (pose.theta - th0 + math.pi) % (2.0 * math.pi) - math.pi
        return Pose(c * dx + s * dy, -s * dx + c * dy, th), v, omega

    def _now(self) -> float:
        """Seconds since the start: on ``/clock`` with ``use_sim_time``, else the wall's."""
        if self._opt.use_sim_time:
            from mdle.ros2.convert import seconds

            clock = self._newest["clock"].message
            if clock is None:
                return 0.0
            t = seconds(clock.clock)
            if self._sim_t0 is None:
                self._sim_t0 = t
            return t - self._sim_t0
        return time.monotonic() - self._t0

    def _advance_sim(self, dt: float) -> float:
        self._poll()
        now = self._now()
        start = self._tick_start_sim if self._tick_start is not None else now
        deadline = start + dt
        give_up = time.monotonic() + self._odom_timeout
        while now < deadline - 1e-9 and time.monotonic() < give_up:
            time.sleep(0.002)
            self._poll()
            now = self._now()
        lateness = max(0.0, now - deadline)
        self._tick_start_sim = deadline if lateness < dt else now
        self._tick_start = time.monotonic()
        return lateness

    def _await_first_data(self) -> None:
        opt = self._opt
        deadline = time.monotonic() + opt.first_data_timeout
        wanted = ["odom"] + (["scan"] if self._scan is not None else []) + (
            ["clock"] if opt.use_sim_time else [])
        while True:
            self._poll()
            missing = [k for k in wanted if self._newest[k].message is None]
            if not missing:
                break
            if time.monotonic() > deadline:
                from mdle.ros2.names import dds_topic

                kinds = {"odom": ("odom", "nav_msgs/msg/Odometry"),
                         "scan": ("scan", "sensor_msgs/msg/LaserScan"),
                         "clock": ("/clock", "rosgraph_msgs/msg/Clock")}
                what = ", ".join(
                    f"{self._node.topic_name(kinds[k][0])} ({kinds[k][1]}, DDS topic "
                    f"{dds_topic(self._node.topic_name(kinds[k][0]))})" for k in missing)
                raise BackendError(
                    f"nothing arrived on {what} within {opt.first_data_timeout:g} s in DDS "
                    f"domain {opt.domain}: check that the robot's driver runs, with the "
                    f"same ROS_DOMAIN_ID and namespace, and that CYCLONEDDS_URI (if set) "
                    f"lets the two meet")
            time.sleep(0.01)
        if self._scan is not None and self.mount_source != "tf_static":
            end = time.monotonic() + opt.tf_wait
            while time.monotonic() < end and self.mount_source != "tf_static":
                time.sleep(0.02)
                self._poll()
            if self.laser_mount is None:
                _log.warning("no base_link -> laser transform on %s and no --robot profile: "
                             "taking the laser to sit at the robot's centre, facing forward",
                             self._node.topic_name("tf_static"))
        self._now()  # the simulated clock's origin

    # ------------------------------------------------------------------ helpers

    def _publish(self, cmd: Command) -> None:
        from mdle.ros2.convert import time_of, twist_message
        from mdle.ros2.types import Header, TwistStamped

        twist = twist_message(cmd)
        if self._opt.twist_stamped:
            t = self._now() + (self._sim_t0 or 0.0) if self._opt.use_sim_time else time.time()
            self._cmd.write(TwistStamped(Header(time_of(t), self._frame), twist))
        else:
            self._cmd.write(twist)

    def _abort(self, message: str) -> NoReturn:
        self.failure = message
        self.stop()
        raise BackendError(message)


def _waited(message: Any) -> float:
    """Return how long a sample has waited since it was written (0 if unknown).

    From the writer's timestamp: samples taken late (after an idle REPL prompt) must not
    look fresh. Clocks of two machines may disagree: an age outside [0, 5] s is ignored.
    """
    info = getattr(message, "sample_info", None)
    if info is None or not info.source_timestamp:
        return 0.0
    age = time.time() - info.source_timestamp * 1e-9
    return age if 0.0 <= age <= 5.0 else 0.0
