"""Simulator speed: ladar scans and full simulated ticks, robust to a shared machine.

Run:  python benchmarks/sim.py [--runs 15] [--calls 200]
      python benchmarks/sim.py --timing-only          # the timing model's cost alone
      OPENBLAS_NUM_THREADS=1 PYTHONHASHSEED=0 \
          valgrind --tool=callgrind python benchmarks/sim.py --ticks-only pioneer-p3dx 400

Each figure is measured in ``--runs`` runs of ``--calls`` calls each; a run's figure is
its median call (robust to other processes taking the CPU for a moment). Printed: the
median over the runs, the minimum over the runs (the machine at its quietest), and the
median of the runs' mean calls in parentheses (which includes other processes'
interference). The load average is printed before and after: compare figures only at
similar loads.

Prints the cost of one 181-beam LMS-200 scan (ray cast + noise, as the simulator takes
it) in worlds of 10, 100, 1,000 and 10,000 segments, and of a full simulated tick
(kinematics, scan with noise, collision test and the exact clearance) in the
100-segment world and in the paper's ellipse scene. Targets (issue 3): <= 100 us per
scan at 100 segments, <= 1 ms at 10,000, <= 150 us per tick at 100 segments.

The scaled worlds keep the obstacle density fixed (one 4-segment box per 16 m^2,
inside a closed room) and grow the area, as a building grows; the robot stands in a
clear disc of 3 m at the centre. A second, adversarial series puts every segment
within range (a closed smooth curve sampled finely around the robot).
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

# This file is named like the package it measures: keep its own folder off the path.
# The imports below must follow this (else ``import sim`` finds this very file), hence
# their E402 waivers.
_HERE = os.path.dirname(os.path.abspath(__file__))
sys.path[:] = [p for p in sys.path if os.path.abspath(p or os.curdir) != _HERE]

import numpy as np  # noqa: E402 (after the path fix above)

from mdle.core.backend import Command  # noqa: E402 (after the path fix above)
from mdle.core.pose import Pose  # noqa: E402 (after the path fix above)
from mdle.sim.backend import SimBackend  # noqa: E402 (after the path fix above)
from mdle.sim.catalog import load_world  # noqa: E402 (after the path fix above)
from mdle.sim.ladar import LMS200, Ladar  # noqa: E402 (after the path fix above)
from mdle.sim.profiles import robot_profile  # noqa: E402 (after the path fix above)
from mdle.sim.shapes import Curve, Rectangle, Wall  # noqa: E402 (after the path fix above)
from mdle.sim.world import World  # noqa: E402 (after the path fix above)


def scattered_world(n_segments: int, seed: int = 0) -> World:
    """Build about ``n_segments`` segments: a room (8) plus 4-segment boxes at fixed density."""
    rng = np.random.default_rng(seed)
    boxes = max(0, math.ceil((n_segments - 8) / 4))
    side = max(8.0, 4.0 * math.sqrt(max(boxes, 1)))
    half = side / 2
    room = Wall(((-half, -half), (half, -half), (half, half), (-half, half)), 0.2, True)
    shapes: list[Wall | Rectangle] = [room]
    while len(shapes) - 1 < boxes:
        c = rng.uniform(-half + 1, half - 1, 2)
        if np.hypot(*c) < 3.0 + 1.0:           # keep a clear disc round the robot
            continue
        shapes.append(Rectangle((float(c[0]), float(c[1])), tuple(rng.uniform(0.3, 1.2, 2)),
                                float(rng.uniform(0, math.pi))))
    return World(f"scattered-{n_segments}", tuple(shapes), Pose(0.0, 0.0, 0.0))


def dense_world(n_segments: int) -> World:
    """Build a world with every segment within range: a wavy closed curve round the robot."""
    a = np.linspace(0, 2 * math.pi, 48, endpoint=False)
    r = 5.0 + 0.5 * np.sin(5 * a)
    pts = tuple((float(x), float(y)) for x, y in zip(r * np.cos(a), r * np.sin(a), strict=True))
    length = 2 * math.pi * 5.0 * 1.1
    curve = Curve(pts, thickness=0.2, closed=False, spacing=length / (n_segments / 2))
    return World(f"dense-{n_segments}", (curve,), Pose(0.0, 0.0, 0.0))


@dataclass(frozen=True)
class Timing:
    """Microseconds per call.

    Median and minimum over runs of each run's median call, and the median over runs of
    each run's mean call.
    """

    median: float
    minimum: float
    mean: float

    def __str__(self) -> str:
        return f"{self.median:8.1f} us  (min {self.minimum:7.1f}, mean {self.mean:7.1f})"


def time_calls(fn: Callable[[], object], calls: int, runs: int) -> Timing:
    """Time ``fn`` in ``runs`` runs of ``calls`` calls (after a warm-up run)."""
    for _ in range(min(calls, 20)):
        fn()
    medians, means = [], []
    clock = time.perf_counter
    for _ in range(runs):
        times = []
        for _ in range(calls):
            t0 = clock()
            fn()
            times.append(clock() - t0)
        medians.append(statistics.median(times) * 1e6)
        means.append(statistics.fmean(times) * 1e6)
    return Timing(statistics.median(medians), min(medians), statistics.median(means))


def scan_cost(world: World, calls: int, runs: int) -> Timing:
    """Time one scan as :class:`sim.backend.SimBackend` takes it (ray cast, noise, rounding)."""
    ladar = Ladar(LMS200, np.random.default_rng(0), mount=robot_profile("pioneer2dx").ladar_mount)
    fan = ladar.fan(world.caster)
    headings = np.linspace(-math.pi, math.pi, 64, endpoint=False).tolist()
    k = [0]

    def one() -> None:
        th = headings[k[0] % 64]
        k[0] += 1
        ladar.scan(fan, 0.0, 0.0, th, 0.0)

    return time_calls(one, calls, runs)


def tick_cost(world: World, calls: int, runs: int, robot: str | None = None) -> Timing:
    """Time observe, command, advance(0.1 s): the robot drives ~1 m circles round its start."""
    backend = SimBackend(world, seed=0, robot=robot)
    k = [0]

    def tick() -> None:
        backend.observe()
        k[0] += 1
        backend.command(Command(0.3, 0.3 + 0.05 * math.sin(0.01 * k[0])))
        backend.advance(0.1)

    timing = time_calls(tick, calls, runs)
    assert not backend.observe().truth["collided"], "benchmark robot collided"
    return timing


def interleaved_ratio(world: World, calls: int, rounds: int, robot: str = "pioneer-p3dx",
                      base: str = "pioneer2dx") -> tuple[float, float, float]:
    """Return the timed/untimed tick-cost ratio measured in interleaved rounds.

    Each round times ``calls`` ticks of ``base`` and of ``robot`` back to back (in
    alternating order), so both see the same machine load; the ratio of the two
    medians is taken per round. Returned: the median, the minimum and the maximum over
    rounds.
    """
    backends = {name: SimBackend(world, seed=0, robot=name) for name in (base, robot)}
    k = {name: 0 for name in backends}

    def tick(name: str) -> None:
        b = backends[name]
        b.observe()
        k[name] += 1
        b.command(Command(0.3, 0.3 + 0.05 * math.sin(0.01 * k[name])))
        b.advance(0.1)

    clock = time.perf_counter
    for name in backends:
        for _ in range(20):
            tick(name)
    ratios = []
    for r in range(rounds):
        order = (base, robot) if r % 2 == 0 else (robot, base)
        med = {}
        for name in order:
            times = []
            for _ in range(calls):
                t0 = clock()
                tick(name)
                times.append(clock() - t0)
            med[name] = statistics.median(times)
        ratios.append(med[robot] / med[base])
    return statistics.median(ratios), min(ratios), max(ratios)


def ticks_only(robot: str, n: int) -> None:
    """Run ``n`` ticks of ``robot`` in the 100-segment world (for instruction counts).

    Run it under ``valgrind --tool=callgrind`` with two ``n`` and take the difference
    over the difference of ``n``: the instructions of one tick, startup excluded.
    """
    backend = SimBackend(scattered_world(100), seed=0, robot=robot)
    for i in range(n):
        backend.observe()
        backend.command(Command(0.3, 0.3 + 0.05 * math.sin(0.01 * i)))
        backend.advance(0.1)


def load() -> str:
    """Return the 1, 5 and 15 minute load averages (2 cores here: above 2 means queueing)."""
    return "load average " + ", ".join(f"{x:.2f}" for x in os.getloadavg())


def main() -> None:
    """Parse the command line, time every figure and print the report."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=15, help="runs per figure")
    parser.add_argument("--calls", type=int, default=200, help="calls per run")
    parser.add_argument("--ticks-only", nargs=2, metavar=("ROBOT", "N"),
                        help="only run N ticks of ROBOT (for callgrind instruction counts)")
    parser.add_argument("--timing-only", action="store_true",
                        help="only the timing model's cost (interleaved rounds)")
    parser.add_argument("--robot", default="pioneer-p3dx",
                        help="the timed profile of --timing-only (name or file)")
    args = parser.parse_args()
    if args.ticks_only:
        ticks_only(args.ticks_only[0], int(args.ticks_only[1]))
        return
    if args.timing_only:
        print(load())
        med, lo, hi = interleaved_ratio(scattered_world(100), args.calls, args.runs,
                                        robot=args.robot)
        print(f"timing model cost ({args.robot}), interleaved: x{med:.3f} (median over "
              f"{args.runs} rounds; min x{lo:.3f}, max x{hi:.3f}) (target: <= x1.10)")
        print(load())
        return
    print(f"sim benchmark: {args.runs} runs of {args.calls} calls; median over runs of the "
          f"run's median call (min over runs, median mean call); {load()}")
    print("one 181-beam scan (ray cast + noise), fixed obstacle density "
          "(targets: <= 100 us at 100 segments, <= 1 ms at 10,000):")
    for n in (10, 100, 1000, 10000):
        w = scattered_world(n)
        print(f"  {w.parts.n_segments:6d} segments: {scan_cost(w, args.calls, args.runs)}")
    print("one 181-beam scan, every segment within range (worst case):")
    for n in (100, 1000, 10000):
        w = dense_world(n)
        print(f"  {w.parts.n_segments:6d} segments: {scan_cost(w, args.calls, args.runs)}")
    print("full simulated tick (observe, command, advance 0.1 s: kinematics, scan with noise, "
          "collision test, exact clearance):")
    w = scattered_world(100)
    t = tick_cost(w, args.calls, args.runs)
    print(f"  {w.parts.n_segments:6d} segments: {t}; {1e5 / t.median:.0f}x real time at "
          f"10 Hz (target: <= 150 us)")
    w = scattered_world(100)
    untimed = tick_cost(w, args.calls, args.runs, robot="pioneer2dx")
    timed = tick_cost(w, args.calls, args.runs, robot="pioneer-p3dx")
    print(f"  {w.parts.n_segments:6d} segments, pioneer2dx (no timing model):   {untimed}")
    print(f"  {w.parts.n_segments:6d} segments, pioneer-p3dx (timing model on):  {timed}")
    print(f"  timing model cost: x{timed.median / untimed.median:.3f} (median), "
          f"x{timed.minimum / untimed.minimum:.3f} (min) (target: <= x1.10)")
    med, lo, hi = interleaved_ratio(w, args.calls, args.runs)
    print(f"  timing model cost, interleaved rounds: x{med:.3f} (median; min x{lo:.3f}, "
          f"max x{hi:.3f})")
    w = scattered_world(10000)
    print(f"  {w.parts.n_segments:6d} segments: {tick_cost(w, args.calls, args.runs)}")
    w = load_world("ellipse")
    t = tick_cost(w, args.calls, args.runs)
    print(f"  ellipse scene (1 ellipse, a scan every tick): {t}")
    print(load())


if __name__ == "__main__":
    main()
