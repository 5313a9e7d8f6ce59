"""The ROS 2 options of ``mdle run`` and ``mdle repl`` (``--backend ros2``), and opening it."""

from __future__ import annotations

import argparse
from typing import Any

__all__ = ["add_ros2_options", "check_ros2_options", "open_ros2_backend"]


def add_ros2_options(p: Any) -> None:
    """Add ``--ns``, ``--domain-id``, ``--twist-stamped``, ``--use-sim-time``, ``--no-laser``."""
    p.add_argument("--ns", metavar="NAMESPACE",
                   help="with --backend ros2: the robot's namespace (topics /NS/scan, /NS/odom, "
                        "/NS/cmd_vel)")
    p.add_argument("--domain-id", dest="domain_id", type=int, metavar="N",
                   help="with --backend ros2: the DDS domain (default: $ROS_DOMAIN_ID, else 0)")
    p.add_argument("--twist-stamped", dest="twist_stamped", action="store_true",
                   help="with --backend ros2: publish geometry_msgs/TwistStamped on cmd_vel")
    p.add_argument("--use-sim-time", dest="use_sim_time", action="store_true",
                   help="with --backend ros2: take time from /clock (a simulator's)")
    p.add_argument("--no-laser", dest="no_laser", action="store_true",
                   help="with --backend ros2: the robot has no laser (no scan is awaited)")


def check_ros2_options(args: argparse.Namespace) -> None:
    """Refuse a ROS 2 option given without ``--backend ros2`` (an MdleError naming it)."""
    if args.backend == "ros2":
        return
    for flag, value in (("--ns", args.ns), ("--domain-id", args.domain_id),
                        ("--twist-stamped", args.twist_stamped),
                        ("--use-sim-time", args.use_sim_time), ("--no-laser", args.no_laser)):
        if value not in (None, False):
            from mdle.core.errors import Diagnostic, MdleError

            raise MdleError(Diagnostic(None, f"{flag} is for a ROS 2 robot: it needs "
                                             "--backend ros2",
                                       hint="e.g. --backend ros2 --ns robot1 (docs/ros2.md)"))


def open_ros2_backend(args: argparse.Namespace, rate: float, header: dict[str, Any]) -> Any:
    """Return a connected :class:`~mdle.ros2.backend.Ros2Backend` for the options.

    The robot profile (``--robot``, else the default one) gives the limits commands are
    clamped to and the laser's mount when ``tf_static`` has none. ``header`` (a trace
    header) gets the namespace, domain and profile.

    Raises
    ------
    BackendError
        A bad namespace or domain, no cyclonedds, or nothing arriving from the robot.
    """
    from mdle.ros2.backend import Ros2Backend, Ros2Options
    from mdle.ros2.dds import domain_id, require
    from mdle.ros2.names import namespace
    from mdle.sim.profiles import DEFAULT_ROBOT, robot_profile

    ns = namespace(args.ns)
    domain = domain_id(args.domain_id)
    require("--backend ros2")
    profile = robot_profile(args.robot or DEFAULT_ROBOT)
    mount = None
    if args.robot:
        x, y, th = profile.ladar_mount
        mount = (float(x), float(y), float(th))
    period = profile.scan_period if profile.scan_period is not None else 0.1
    header.update(ros2={"namespace": ns, "domain_id": domain}, robot=args.robot)
    options = Ros2Options(namespace=ns, domain=domain, twist_stamped=args.twist_stamped,
                          use_sim_time=args.use_sim_time, laser=not args.no_laser,
                          mount=mount)
    return Ros2Backend(profile.limits_with(period), rate=rate, options=options)
