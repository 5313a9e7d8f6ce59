"""The ROS 2 backend's DDS cost per control tick, and Cyclone's loopback delivery.

One tick of ``--backend ros2`` decodes the newest ``LaserScan`` (181 beams) and
``Odometry`` into mdle's values and encodes a ``Twist``; the target is well under 1 ms,
so at 10 Hz the DDS work takes under 1 % of a tick. For comparison it also times a
``Twist`` written by mdle's own CDR writer (the recordings' encoder), and a ``Twist``
written and taken back through Cyclone in this process (all on loopback: the Cyclone
configuration of :func:`mdle.ros2.dds.loopback_config`, a domain of its own).

Run: ``python benchmarks/ros2.py [--cycles N]`` (needs ``pip install '.[ros2]'``).
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from collections.abc import Callable

import numpy as np

from mdle.core.backend import Command, Scan
from mdle.core.pose import Pose
from mdle.ros2.dds import loopback_config
from mdle.rosmsg.cdr import CdrWriter


def _per_call_us(fn: Callable[[], object], cycles: int) -> float:
    t0 = time.perf_counter()
    for _ in range(cycles):
        fn()
    return (time.perf_counter() - t0) / cycles * 1e6


def tick_costs(cycles: int) -> dict[str, float]:
    """Microseconds per call of each piece of a tick's DDS work."""
    from mdle.ros2 import types as msg
    from mdle.ros2.convert import (
        ScanReader,
        odometry_message,
        odometry_values,
        scan_message,
        twist_message,
    )

    bearings = np.radians(np.linspace(-90.0, 90.0, 181))
    scan = Scan(np.linspace(1.0, 7.0, 181), bearings, np.ones(181, dtype=bool), 0.0, 8.0)
    scan_bytes = scan_message(scan, 0.0, "laser", 0.0, 0.1).serialize()
    odom_bytes = odometry_message(1.0, Pose(1.0, 2.0, 0.5), 0.3, 0.1, "odom",
                                  "base_link").serialize()
    reader = ScanReader()
    return {
        "scan encode": _per_call_us(
            lambda: scan_message(scan, 0.0, "laser", 0.0, 0.1).serialize(), cycles),
        "scan decode": _per_call_us(
            lambda: reader.scan(msg.LaserScan.deserialize(scan_bytes), 0.0, 0.0), cycles),
        "odometry decode": _per_call_us(
            lambda: odometry_values(msg.Odometry.deserialize(odom_bytes)), cycles),
        "twist encode": _per_call_us(
            lambda: twist_message(Command(0.3, 0.1)).serialize(), cycles),
        "twist, mdle's CDR writer": _per_call_us(
            lambda: CdrWriter().prim("d", 0.3, 0.0, 0.0, 0.0, 0.0, 0.1).bytes(), cycles),
    }


def loopback_us(samples: int) -> list[float]:
    """Microseconds from writing a Twist to taking it, ``samples`` times, in one process."""
    from mdle.ros2 import types as msg
    from mdle.ros2.dds import Node, QosKind, take

    node = Node(200)
    writer = node.writer("bench", msg.Twist, QosKind.RELIABLE)
    reader = node.reader("bench", msg.Twist, QosKind.RELIABLE)
    time.sleep(0.5)  # discovery of the two endpoints
    out = []
    for _ in range(samples):
        t0 = time.perf_counter()
        writer.write(msg.Twist())
        while not take(reader, 10):
            pass
        out.append((time.perf_counter() - t0) * 1e6)
    return out


def main() -> None:
    """Print the costs."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=3000)
    args = parser.parse_args()
    os.environ["CYCLONEDDS_URI"] = loopback_config()
    costs = tick_costs(args.cycles)
    for name, us in costs.items():
        print(f"{name:<26} {us:8.1f} us")
    tick = costs["scan decode"] + costs["odometry decode"] + costs["twist encode"]
    print(f"a tick's DDS work          {tick:8.1f} us ({tick / 1e3:.2f} % of a 100 ms tick)")
    ratio = costs["twist encode"] / costs["twist, mdle's CDR writer"]
    print(f"twist: Cyclone / mdle's    {ratio:8.2f}x")
    lat = sorted(loopback_us(400))
    print(f"loopback write -> take     median {statistics.median(lat):.0f} us, "
          f"95th percentile {lat[int(0.95 * len(lat))]:.0f} us")


if __name__ == "__main__":
    main()
