"""Simulator speed: ray-cast scans and full simulated ticks (median of several runs).

Run:  python benchmarks/sim.py [--runs 7]

Each figure: the median over the runs of each run's median call, with the median of
the runs' mean calls in parentheses (the mean includes other processes' interference
on a shared machine).

Prints the cost of one 181-beam LMS-200 scan (ray cast + noise) in worlds of 10, 100,
1,000 and 10,000 segments, and of a full simulated tick (kinematics, scan with noise,
collision test) in the 100-segment world. Targets (issue 3): <= 100 us per scan at
100 segments, <= 1 ms at 10,000, <= 150 us per tick at 100 segments.

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

# This file is named like the package it measures: keep its own folder off the path.
_HERE = os.path.dirname(os.path.abspath(__file__))
sys.path[:] = [p for p in sys.path if os.path.abspath(p or os.curdir) != _HERE]

import numpy as np

from mdle.backend import Command, Pose
from sim.backend import SimBackend
from sim.ladar import LMS200, Ladar
from sim.robot import PIONEER2DX
from sim.shapes import Curve, Rectangle, Wall
from sim.world import World


def scattered_world(n_segments: int, seed: int = 0) -> World:
    """About ``n_segments`` segments: a room (8) plus 4-segment boxes at fixed density."""
    rng = np.random.default_rng(seed)
    boxes = max(0, math.ceil((n_segments - 8) / 4))
    side = max(8.0, 4.0 * math.sqrt(max(boxes, 1)))
    half = side / 2
    shapes: list = [Wall(((-half, -half), (half, -half), (half, half), (-half, half)), 0.2, True)]
    while len(shapes) - 1 < boxes:
        c = rng.uniform(-half + 1, half - 1, 2)
        if np.hypot(*c) < 3.0 + 1.0:           # keep a clear disc round the robot
            continue
        shapes.append(Rectangle((float(c[0]), float(c[1])), tuple(rng.uniform(0.3, 1.2, 2)),
                                float(rng.uniform(0, math.pi))))
    return World(f"scattered-{n_segments}", tuple(shapes), Pose(0.0, 0.0, 0.0))


def dense_world(n_segments: int) -> World:
    """Every segment within range: a wavy closed curve sampled around the robot."""
    a = np.linspace(0, 2 * math.pi, 48, endpoint=False)
    r = 5.0 + 0.5 * np.sin(5 * a)
    pts = tuple((float(x), float(y)) for x, y in zip(r * np.cos(a), r * np.sin(a)))
    length = 2 * math.pi * 5.0 * 1.1
    curve = Curve(pts, thickness=0.2, closed=False, spacing=length / (n_segments / 2))
    return World(f"dense-{n_segments}", (curve,), Pose(0.0, 0.0, 0.0))


def median_us(fn, repeat: int, runs: int) -> tuple[float, float]:
    """(median over runs of each run's median call, median over runs of each run's mean),
    microseconds. The median call is robust to the other processes on a shared machine;
    the mean includes their interference."""
    fn()
    medians, means = [], []
    for _ in range(runs):
        times = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            fn()
            times.append(time.perf_counter() - t0)
        medians.append(statistics.median(times) * 1e6)
        means.append(statistics.fmean(times) * 1e6)
    return statistics.median(medians), statistics.median(means)


def scan_cost(world: World, runs: int) -> tuple[float, float]:
    ladar = Ladar(LMS200, np.random.default_rng(0), mount=PIONEER2DX.ladar_mount)
    caster = world.caster
    headings = np.linspace(-math.pi, math.pi, 64, endpoint=False)
    k = [0]

    def one() -> None:
        th = float(headings[k[0] % 64])
        k[0] += 1
        ox, oy = ladar.origin(0.0, 0.0, th)
        hits = caster.cast(np.array((ox, oy)), ladar.world_angles(th), LMS200.max_range,
                           detail=False, rel=ladar.rel)
        ladar.measure(hits, th, 0.0)

    return median_us(one, 200, runs)


def tick_cost(world: World, runs: int) -> tuple[float, float]:
    backend = SimBackend(world, seed=0)
    k = [0]

    def tick() -> None:
        backend.observe()
        k[0] += 1
        backend.command(Command(0.3, 0.3 + 0.05 * math.sin(0.01 * k[0])))  # ~1 m circles
        backend.advance(0.1)

    us = median_us(tick, 200, runs)
    assert not backend.observe().truth["collided"], "benchmark robot collided"
    return us


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=7, help="runs per figure (median)")
    args = parser.parse_args()
    print(f"sim benchmark: {args.runs} runs of 200 calls; median call (mean call), microseconds")
    print("one 181-beam scan (ray cast + noise), fixed obstacle density "
          "(targets: <= 100 us at 100 segments, <= 1 ms at 10,000):")
    for n in (10, 100, 1000, 10000):
        w = scattered_world(n)
        med, mean = scan_cost(w, args.runs)
        print(f"  {w.parts.n_segments:6d} segments: {med:8.1f} us  ({mean:.1f})")
    print("one 181-beam scan, every segment within range (worst case):")
    for n in (100, 1000, 10000):
        w = dense_world(n)
        med, mean = scan_cost(w, args.runs)
        print(f"  {w.parts.n_segments:6d} segments: {med:8.1f} us  ({mean:.1f})")
    w = scattered_world(100)
    med, mean = tick_cost(w, args.runs)
    print(f"full simulated tick (observe, command, advance 0.1 s: kinematics, scan with noise, "
          f"collision test), {w.parts.n_segments} segments: {med:.1f} us  ({mean:.1f}); "
          f"{1e5 / med:.0f}x real time at 10 Hz (target: <= 150 us)")


if __name__ == "__main__":
    main()
