"""``mdle sim serve --ros2``: the embedded simulator as a ROS 2 robot (or a team).

Exit codes: 0 at ``--until``, 1 errors in the world or options (or no cyclonedds), 2
usage, 130 Ctrl-C, 143 SIGTERM; every robot is stopped on the way out.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from mdle.cli.options import add_simulation_options, seconds

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> None:
    """Register ``mdle sim`` and ``mdle sim serve``."""
    p = subparsers.add_parser(
        "sim", help="the simulator as a robot for other programs (mdle sim serve --ros2)",
        description="Serve the embedded simulator to other programs.")
    sub = p.add_subparsers(dest="action", metavar="ACTION")
    s = sub.add_parser(
        "serve", help="serve a simulated world's robots over ROS 2",
        description="Run a simulated world in real time as a ROS 2 robot: it publishes "
                    "scan, odom, tf, tf_static and /clock and obeys cmd_vel. A world with a "
                    "robots: section serves every robot, each in the namespace of its name. "
                    "Needs pip install 'mdle[ros2]'; no ROS installation.",
        epilog="Example: `mdle sim serve --ros2 --world corridor` in one terminal, "
               "`mdle run plan.mdle --backend ros2 --use-sim-time` in another (docs/ros2.md).")
    s.add_argument("--ros2", action="store_true", required=True,
                   help="speak ROS 2 (DDS, with ROS 2's topic and type names)")
    s.add_argument("--world", metavar="NAME|FILE", default=None,
                   help="the world: a reference world name or a YAML file (default: default)")
    add_simulation_options(s)
    s.add_argument("--ns", metavar="NAMESPACE",
                   help="namespace of the robot's topics and frames (a team's robots go "
                        "under it, each in its own name)")
    s.add_argument("--domain-id", dest="domain_id", type=int, metavar="N",
                   help="the DDS domain (default: $ROS_DOMAIN_ID, else 0)")
    s.add_argument("--twist-stamped", dest="twist_stamped", action="store_true",
                   help="read geometry_msgs/TwistStamped on cmd_vel")
    s.add_argument("--speed", type=float, default=1.0, metavar="FACTOR",
                   help="simulated seconds per wall second (default 1: real time)")
    s.add_argument("--step", type=float, default=0.01, metavar="S",
                   help="simulated seconds per step (default 0.01)")
    s.add_argument("--cmd-timeout", dest="cmd_timeout", type=float, default=0.5, metavar="S",
                   help="stop a robot that got no cmd_vel for this many seconds "
                        "(default 0.5; 0: never)")
    s.add_argument("--until", type=seconds, metavar="SECONDS",
                   help="stop after this many simulated seconds (default: until Ctrl-C)")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Serve until ``--until`` or a signal; returns the exit code."""
    if getattr(args, "action", None) != "serve":
        print("mdle sim: say what to do: mdle sim serve --ros2 [--world W]", file=sys.stderr)
        return 2
    from mdle import sim
    from mdle.ros2.dds import domain_id, require
    from mdle.ros2.names import namespace
    from mdle.ros2.serve import ServeOptions, SimServer

    ns = namespace(args.ns)
    domain = domain_id(args.domain_id)
    require("mdle sim serve --ros2")
    world = sim.load_world(args.world or sim.DEFAULT_WORLD)
    options = ServeOptions(domain=domain, namespace=ns, step=args.step, speed=args.speed,
                           cmd_timeout=args.cmd_timeout, twist_stamped=args.twist_stamped)
    server = SimServer(world, seed=args.seed, robot=args.robot, sensing=args.sensing,
                       options=options)
    try:
        names = ", ".join(r.ns or "/" for r in server.robots)
        print(f"serving world `{world.name}` on ROS 2 domain {domain}: "
              f"{len(server.robots)} robot(s) at {names}", flush=True)
        server.run(until=args.until)
    finally:
        server.close()
    return 0
