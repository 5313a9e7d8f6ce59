"""The corridor's doors on a real ARCOS server against the simulator, per condition.

Reads the AMRISim recordings of 2026-11-28 (``tests/data/recordings/amrisim-2026-11-28/``)
and runs the same laws in the simulator with a robot profile over seeds, then prints, per
condition, how often a door swung the robot's heading over 30 deg and the least side
ranges, with the simulator's ratio to the server (the goal: within 1.5x either way). See
:mod:`mdle.experiments.door_swings` for what is measured.

Run: ``python benchmarks/door_swings.py [--seeds 30] [--robot pioneer-p3dx]``.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from mdle.experiments.door_swings import (
    CONDITIONS,
    SWING_LIMIT,
    Summary,
    recorded_doors,
    recordings_of,
    simulated_doors,
    summarise,
)

ROOT = Path(__file__).resolve().parent.parent
RECORDINGS = ROOT / "tests" / "data" / "recordings" / "amrisim-2026-11-28"
PLAN = ROOT / "plans" / "paper" / "fig6-corridor.mdle"
WORLD = ROOT / "plans" / "paper" / "fig6-corridor.world.yaml"


def _row(label: str, s: Summary) -> str:
    return (f"  {label:<22} {s.runs:>4} {s.big:>4}/{s.doors:<4} {s.big_rate * 100:5.1f} %"
            f" {s.median_swing:6.1f} {s.max_swing:6.1f} {s.median_least_side:7.3f}"
            f" {s.least_side:7.3f}")


def _ratio(sim: float, server: float) -> str:
    if not (math.isfinite(sim) and math.isfinite(server)) or sim <= 0 or server <= 0:
        return "  -  "
    return f"x{sim / server:.2f}"


def main() -> None:
    """Print the comparison table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=30, help="simulated runs per condition")
    ap.add_argument("--robot", default="pioneer-p3dx", help="robot profile (name or file)")
    args = ap.parse_args()
    print(f"doors swung over {SWING_LIMIT:g} deg and least side ranges (rc 0.55 m); "
          f"simulator: --robot {args.robot}, seeds 0-{args.seeds - 1}")
    print(f"  {'':<22} {'runs':>4} {'doors > 30':>9} {'rate':>7} {'median':>6} {'max':>6}"
          f" {'side median':>7} {'least':>7}")
    for cond in CONDITIONS:
        print(f"{cond.name}: {cond.description}")
        recorded = recordings_of(cond, RECORDINGS)
        server = summarise([recorded_doors(p) for p in recorded]) if recorded else None
        if server is not None:
            print(_row("server (AMRISim)", server))
        sim = summarise([simulated_doors(cond, seed, PLAN, WORLD, args.robot)
                         for seed in range(args.seeds)])
        print(_row("simulator", sim))
        if server is not None:
            print(f"  {'simulator / server':<22} rate {_ratio(sim.big_rate, server.big_rate)},"
                  f" least side {_ratio(sim.least_side, server.least_side)}, median least "
                  f"side {_ratio(sim.median_least_side, server.median_least_side)}")


if __name__ == "__main__":
    main()
