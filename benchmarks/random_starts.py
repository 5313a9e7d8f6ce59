"""Random starts per shape (issue 4): collisions and worst clearance, the long version.

    python benchmarks/random_starts.py [--runs 50] [--duration 40] [--sensing scan|exact]

Starts 8 m from each obstacle's centre, headed at it +-17 deg (the wall: anywhere 1-6 m above
it, heading -11 to -169 deg), seeded; the ideal unicycle at 1 m/s; control at the rate
control-law.md suggests (50 Hz scan, 100 Hz exact), on every core with a progress bar on
standard error. Prints one line per shape, then what the columns mean.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

# A script's folder comes first on sys.path: keep benchmarks/*.py (benchmarks/sim.py, say)
# from shadowing the packages of the same name, and put the checkout's root last instead,
# so `python benchmarks/random_starts.py` works from a checkout where mdle is not installed
# (where it is, the installed mdle, with its compiled fan cast, wins).
_HERE = Path(__file__).resolve().parent
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != _HERE] + [str(_HERE.parent)]

# After the sys.path fix: a run imports ``sim``, which benchmarks/sim.py would shadow.
from mdle.cli.sweep import progress_bar  # noqa: E402 (see above)
from mdle.experiments.following import (  # noqa: E402
    SHAPES,
    random_start_tasks,
    run_many,
    table,
)
from mdle.sweep.executors import default_jobs  # noqa: E402


def main() -> None:
    """Print one line per shape."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=50)
    parser.add_argument("--duration", type=float, default=40.0)
    parser.add_argument("--sensing", choices=("scan", "exact"), default="scan")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--shapes", nargs="*", default=list(SHAPES))
    args = parser.parse_args()
    t0 = time.perf_counter()
    tasks = []
    for world in args.shapes:
        tasks += random_start_tasks(world, args.runs, seed=args.seed, sensing=args.sensing,
                                    duration=args.duration)
    jobs = default_jobs()  # every core, one progress bar over all the runs (stderr)
    runs = run_many(tasks, jobs=jobs, progress=progress_bar(f"{jobs} processes"))
    print(table(runs))
    worst = min(runs, key=lambda r: r.min_clearance)
    print(f"worst run: {worst.world} seed {worst.seed}, clearance {worst.min_clearance:.3f} m; "
          f"{len(runs)} runs in {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
