"""Worlds of many circles: load time and memory from 2,000 to 200,000 circles (issues 26, 27).

Run:  python benchmarks/circles.py [--counts 2000 20000 200000] [--profile] [--scans]

Each count is written as a world file (circles of 0.1 to 0.5 m scattered over a square
of about 4 m per circle, none within 2 m of the start) and loaded in a fresh process:
:func:`sim.world_yaml.read_world` (which checks the start), then one scan. Prints the
file's size, the CPU time (user + system) and the peak memory (max RSS) of that process.

``--scans`` then times, in that process, a ladar's scan (181 beams over 180 degrees, 8 m)
from 40 places along a line through the circles, with the circles in a grid
(:class:`sim.faceindex.BoxGrid`, the default above 256 circles) and testing every circle:
the median over 5 interleaved rounds of each round's median, and the time to build the
grid; then a clearance query (the body's distance to the nearest circle) from the same
places, the same way.
"""

from __future__ import annotations

import argparse
import math
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np


def write_world(path: Path, n: int, seed: int = 0) -> None:
    """Write a world of ``n`` circles to ``path`` (flow style, one circle a line)."""
    rng = np.random.default_rng(seed)
    side = 2.0 * np.sqrt(n)
    xy = rng.uniform(-side, side, size=(2 * n + 16, 2))
    xy = xy[np.hypot(xy[:, 0], xy[:, 1]) > 2.0][:n]
    r = rng.uniform(0.1, 0.5, size=n)
    lines = ["name: circles", "start: {x: 0, y: 0, theta: 0}", "obstacles:"]
    lines += [f"  - {{type: circle, center: [{x:.3f}, {y:.3f}], radius: {q:.3f}}}"
              for (x, y), q in zip(xy, r, strict=True)]
    path.write_text("\n".join(lines) + "\n")


def _scans(world: Any) -> None:
    """Print a scan's cost with the circles' grid and without it, and the grid's build."""
    from mdle.sim.raycast import RayCaster

    t0 = time.process_time()
    grid = RayCaster(world.parts).arc_grid
    build = time.process_time() - t0
    assert grid is not None, "more than 256 circles are indexed"
    rel = np.linspace(0.0, math.pi, 181)
    fans = {"grid": RayCaster(world.parts).fan(rel, 8.0),
            "every circle": RayCaster(world.parts, curve_grids=False).fan(rel, 8.0)}
    xmin, ymin, xmax, ymax = world.bounds
    places = [(xmin + (xmax - xmin) * f, ymin + (ymax - ymin) * f, 3.0 * f)
              for f in np.linspace(0.05, 0.95, 40).tolist()]
    rounds: dict[str, list[float]] = {name: [] for name in fans}
    for _ in range(5):
        for name, fan in fans.items():
            times = []
            for x, y, first in places:
                t = time.perf_counter()
                fan.cast(x, y, first)
                times.append(time.perf_counter() - t)
            rounds[name].append(statistics.median(times))
    got = {name: statistics.median(v) * 1e6 for name, v in rounds.items()}
    print(f"  scan: {got['grid']:.1f} us with the grid (built in {build * 1e3:.0f} ms), "
          f"{got['every circle']:.1f} us testing every circle "
          f"(x{got['every circle'] / got['grid']:.0f})")
    from mdle.sim.collision import Collider

    colliders = {"grid": Collider(world.parts, 0.25),
                 "every circle": Collider(world.parts, 0.25, curve_grids=False)}
    rounds = {name: [] for name in colliders}
    for _ in range(5):
        for name, collider in colliders.items():
            times = []
            for x, y, _ in places:
                t = time.perf_counter()
                collider.clearance(x, y)
                times.append(time.perf_counter() - t)
            rounds[name].append(statistics.median(times))
    got = {name: statistics.median(v) * 1e6 for name, v in rounds.items()}
    print(f"  clearance: {got['grid']:.1f} us with the grid, {got['every circle']:.1f} us "
          f"measuring to every circle (x{got['every circle'] / got['grid']:.0f})")


def _load(path: str, profile: bool, scans: bool = False) -> None:
    """Load one world in this process and print CPU seconds and peak RSS (MB)."""
    from mdle.sim.world_yaml import read_world

    def work() -> None:
        w = read_world(path)
        w.cast((0.0, 0.0), np.linspace(-np.pi / 2, np.pi / 2, 181), 8.0)

    t0 = time.process_time()
    if profile:
        import cProfile
        import pstats

        prof = cProfile.Profile()
        prof.runcall(work)
        pstats.Stats(prof).sort_stats("cumulative").print_stats(25)
    else:
        work()
    cpu = time.process_time() - t0
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"cpu {cpu:.2f} s  max RSS {rss:.0f} MB")
    if scans:
        _scans(read_world(path))


def main() -> None:
    """Write and load each count in a fresh process."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--counts", type=int, nargs="+", default=[2000, 20000, 200000])
    ap.add_argument("--profile", action="store_true")
    ap.add_argument("--scans", action="store_true",
                    help="also time scans with the circles' grid and without it")
    ap.add_argument("--load", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.load:
        _load(a.load, a.profile, a.scans)
        return
    with tempfile.TemporaryDirectory() as tmp:
        for n in a.counts:
            path = Path(tmp) / f"circles{n}.yaml"
            write_world(path, n)
            mb = path.stat().st_size / 1e6
            print(f"{n:>7} circles ({mb:.1f} MB): ", end="", flush=True)
            cmd = [sys.executable, __file__, "--load", str(path)]
            subprocess.run(cmd + (["--profile"] if a.profile else [])
                           + (["--scans"] if a.scans else []), check=False)


if __name__ == "__main__":
    main()
