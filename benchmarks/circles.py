"""Worlds of many circles: load time and memory from 2,000 to 200,000 circles (issues 26, 27).

Run:  python benchmarks/circles.py [--counts 2000 20000 200000] [--profile]

Each count is written as a world file (circles of 0.1 to 0.5 m scattered over a square
of about 4 m per circle, none within 2 m of the start) and loaded in a fresh process:
:func:`sim.world_yaml.read_world` (which checks the start), then one scan. Prints the
file's size, the CPU time (user + system) and the peak memory (max RSS) of that process.
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

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


def _load(path: str, profile: bool) -> None:
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


def main() -> None:
    """Write and load each count in a fresh process."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--counts", type=int, nargs="+", default=[2000, 20000, 200000])
    ap.add_argument("--profile", action="store_true")
    ap.add_argument("--load", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.load:
        _load(a.load, a.profile)
        return
    with tempfile.TemporaryDirectory() as tmp:
        for n in a.counts:
            path = Path(tmp) / f"circles{n}.yaml"
            write_world(path, n)
            mb = path.stat().st_size / 1e6
            print(f"{n:>7} circles ({mb:.1f} MB): ", end="", flush=True)
            cmd = [sys.executable, __file__, "--load", str(path)]
            subprocess.run(cmd + (["--profile"] if a.profile else []), check=False)


if __name__ == "__main__":
    main()
