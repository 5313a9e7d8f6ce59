"""Team speed: one tick of ten robots against one tick of one robot, in the same world.

Run:  python benchmarks/team.py [--ticks 300] [--repeat 7]

The world is a closed room and boxes, 100 segments (the scattered world of
benchmarks/sim.py's scaling series). The robots stand on a ring in the clear middle;
each runs the same wandering plan (cruise until something is within 0.7 m ahead, then
turn for a second, again and again); a second series has every robot send its pose at
every tick as well, as a leader does (90 deliveries a tick for ten robots).
Each robot has a noisy 181-beam LMS-200 scan that sees the other robots.

A tick of a team is: every robot's scheduler ticks (observe, interrupts, control law,
sends), then every robot moves (kinematics, collisions with walls and the others, scans
at the ladar's instants) and the radio delivers. The figure is wall time per team tick,
the median of ``--repeat`` runs of ``--ticks`` ticks, one-robot and ten-robot runs
interleaved; the target (issue 15) is a ten-robot tick at most 10 times a one-robot tick.
The load average is printed: compare figures at similar loads. On a loaded machine,
count instructions instead (repeatable under load): ``--instructions --ticks T`` runs
each team under ``valgrind --tool=callgrind`` for T + 10 and for 10 ticks (``--only N``)
and prints the difference over T, per team tick.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import statistics
import subprocess
import sys
import time

_HERE = os.path.dirname(os.path.abspath(__file__))
sys.path[:] = [p for p in sys.path if os.path.abspath(p or os.curdir) != _HERE]

import numpy as np  # noqa: E402 (after the path fix above)

from mdle.core.pose import Pose  # noqa: E402 (after the path fix above)
from mdle.lang import load_text  # noqa: E402 (after the path fix above)
from mdle.sim.ladar import LMS200  # noqa: E402 (after the path fix above)
from mdle.sim.profiles import robot_profile  # noqa: E402 (after the path fix above)
from mdle.sim.shapes import Rectangle, Wall  # noqa: E402 (after the path fix above)
from mdle.sim.team import TeamSim  # noqa: E402 (after the path fix above)
from mdle.sim.world import RobotPlace, World  # noqa: E402 (after the path fix above)
from mdle.team.run import TeamRun  # noqa: E402 (after the path fix above)

PLAN = """
atom cruise = (go(0.3 m/s), min_range(-30 deg, 30 deg) < 0.7 m, 20 s{send})
atom spin = (turn(60 deg/s), never, 1 s{send})
plan main = ((cruise, spin)..., never, inf)
"""


def world(seed: int = 0) -> World:
    """Return a 100-segment world: a closed room (8 segments) and 23 boxes, a clear middle."""
    rng = np.random.default_rng(seed)
    half = 12.0
    shapes: list[Wall | Rectangle] = [
        Wall(((-half, -half), (half, -half), (half, half), (-half, half)), 0.2, True)]
    while len(shapes) < 24:
        c = rng.uniform(-half + 1, half - 1, 2)
        if np.hypot(*c) < 5.0:
            continue
        shapes.append(Rectangle((float(c[0]), float(c[1])), tuple(rng.uniform(0.3, 1.2, 2)),
                                float(rng.uniform(0, math.pi))))
    w = World("team-100", tuple(shapes))
    assert w.parts.n_segments == 100, w.parts.n_segments
    return w


def team_run(w: World, n: int, seed: int = 1, beacons: bool = False) -> TeamRun:
    """Return a team of ``n`` wandering robots on a ring of radius 2.5 m, ready to tick.

    With ``beacons`` every robot sends its pose at every tick.
    """
    profile = robot_profile("pioneer2dx")
    places = [RobotPlace(f"r{i}", profile, LMS200,
                         Pose(2.5 * math.cos(2 * math.pi * i / n),
                              2.5 * math.sin(2 * math.pi * i / n), 2 * math.pi * i / n))
              for i in range(n)]
    element = load_text(PLAN.format(send=", send(pose)" if beacons else "")).elements["main"]
    run = TeamRun(TeamSim(w, places, seed=seed), {p.name: element for p in places}, 10.0)
    for s in run.schedulers.values():
        s.start()
    return run


def per_tick(w: World, n: int, ticks: int, beacons: bool) -> float:
    """Return the microseconds per team tick of ``n`` robots over ``ticks`` ticks."""
    run = team_run(w, n, beacons=beacons)
    for _ in range(10):  # warm up: first scans, caches
        run.tick()
    t0 = time.perf_counter()
    for _ in range(ticks):
        run.tick()
    return (time.perf_counter() - t0) / ticks * 1e6


def instructions(n: int, ticks: int, beacons: bool) -> int:
    """Return the instructions callgrind counts for ``--only n --ticks ticks``."""
    cmd = ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", sys.executable,
           os.path.abspath(__file__), "--only", str(n), "--ticks", str(ticks)]
    # A fixed hash seed (set and dict orders), one BLAS thread (idle BLAS threads spin for
    # as long as the machine lets them) and no .pyc written (a source changed between two
    # runs would be compiled in only one): the counts repeat from run to run.
    env = {**os.environ, "PYTHONHASHSEED": "0", "OPENBLAS_NUM_THREADS": "1",
           "PYTHONDONTWRITEBYTECODE": "1"}
    out = subprocess.run(cmd + (["--beacons"] if beacons else []), capture_output=True,
                         text=True, check=False, env=env).stderr
    m = re.search(r"Collected\s*:\s*(\d+)", out)
    if m is None:
        raise SystemExit(f"callgrind gave no count:\n{out[-2000:]}")
    return int(m.group(1))


def count(ticks: int) -> None:
    """Print instructions per team tick of one and ten robots, and their ratio.

    Two runs each: the difference of ``ticks + 10`` and 10 ticks, over ``ticks``.
    """
    for beacons in (False, True):
        per = {n: (instructions(n, ticks + 10, beacons) - instructions(n, 10, beacons)) / ticks
               for n in (1, 10)}
        print(("with pose beacons" if beacons else "sensing only") +
              f": one robot {per[1] / 1e3:.1f} k instructions per tick, ten robots "
              f"{per[10] / 1e3:.1f} k, ratio {per[10] / per[1]:.2f} (target <= 10)")


def main() -> None:
    """Print the two series' figures (or run one team untimed, with --only)."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--ticks", type=int, default=300)
    p.add_argument("--repeat", type=int, default=7)
    p.add_argument("--only", type=int, metavar="N",
                   help="just run N robots for --ticks ticks, untimed (for an instruction "
                        "count: run it under valgrind --tool=callgrind at two tick counts "
                        "and take the difference)")
    p.add_argument("--beacons", action="store_true", help="with --only: robots send poses")
    p.add_argument("--instructions", action="store_true",
                   help="count instructions under callgrind instead of timing (slow: "
                        "minutes; repeatable on a loaded machine)")
    args = p.parse_args()
    if args.instructions:
        count(args.ticks)
        return
    w = world()
    if args.only:
        run = team_run(w, args.only, beacons=args.beacons)
        for _ in range(args.ticks):
            run.tick()
        return
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    for beacons in (False, True):
        one, ten = [], []
        for _ in range(args.repeat):
            one.append(per_tick(w, 1, args.ticks, beacons))
            ten.append(per_tick(w, 10, args.ticks, beacons))
        m1, m10 = statistics.median(one), statistics.median(ten)
        print("with every robot sending its pose at every tick:" if beacons else
              "sensing only (no messages):")
        print(f"  one robot:  {m1:8.1f} us per tick (min {min(one):.1f})")
        print(f"  ten robots: {m10:8.1f} us per tick (min {min(ten):.1f})")
        print(f"  ratio: {m10 / m1:.2f} (target <= 10; ratio of minima "
              f"{min(ten) / min(one):.2f})")
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
