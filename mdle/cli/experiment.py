"""``mdle experiment``: reproduce the seed paper's experiments in the simulator.

* ``mdle experiment curvature [--draws N] [--seed S] [--out DIR]``: Table 1 (RMS error of the
  curvature estimators on the trash can and the file cabinet, beside the paper's figures) and
  the plots of Figures 4 and 5.
* ``mdle experiment following [--sensing scan|exact] [--side right|left] [--seed S]``: the
  boundary-following runs of Figures 1-3 and the other test shapes, one line per shape.
* ``mdle experiment random-starts [--runs N] [--seed S] [--duration T]``: seeded random starts
  headed at each obstacle; collisions and the worst clearance per shape.
* ``mdle experiment random-starts --generated [--shapes N] [--starts N] [--blind-side] ...``:
  seeded starts on a collision course with generated obstacles, run on every core; engagement
  and accuracy per shape family (:mod:`mdle.cli.generated_study`).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from mdle.cli import generated_study, output

__all__ = ["add_parser", "run"]

EXPERIMENTS = ("curvature", "following", "random-starts")


def add_parser(subparsers: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """Register ``mdle experiment``."""
    p = subparsers.add_parser(
        "experiment", help="reproduce the paper's experiments (Table 1, Figures 1-5)",
        description="Reproduce the seed paper's experiments in the simulator.")
    p.add_argument("name", choices=EXPERIMENTS, help="which experiment")
    p.add_argument("--draws", type=int, default=200, metavar="N",
                   help="curvature: noisy scans per object (default 200)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--out", type=Path, default=Path("experiment-out"), metavar="DIR",
                   help="curvature: folder for the Figure 4 and 5 plots")
    p.add_argument("--sensing", choices=("scan", "exact"), default="scan",
                   help="following/random-starts: noisy scan or exact rays")
    p.add_argument("--side", choices=("right", "left"), default="right",
                   help="following: which side the boundary is on")
    p.add_argument("--runs", type=int, default=None, metavar="N",
                   help="random-starts (paper shapes): runs per shape (default 50)")
    p.add_argument("--duration", type=float, default=None, metavar="SECONDS",
                   help="following/random-starts: length of each run")
    p.add_argument("--rate", type=float, default=None, metavar="HZ",
                   help="random-starts: control rate (default: 50 Hz scan, 100 Hz exact; "
                        "--generated: 10 Hz)")
    p.add_argument("--v", type=float, default=None, metavar="M/S",
                   help="random-starts: speed (default 1 m/s)")
    generated_study.add_arguments(p)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Run the chosen experiment and print its table."""
    if args.draws < 1 or (args.runs is not None and args.runs < 1):
        print("mdle experiment: --draws and --runs must be at least 1", file=sys.stderr)
        return output.EXIT_USAGE
    misplaced = _misplaced(args)
    if misplaced:
        print(f"mdle experiment {args.name}: {misplaced}", file=sys.stderr)
        return output.EXIT_USAGE
    if args.generated:
        return generated_study.run(args)
    if args.name == "curvature":
        from mdle.experiments.curvature import format_table, plot_figures, run_table

        print(format_table(run_table(args.draws, args.seed)))
        for path in plot_figures(args.out, seed=args.seed):
            print(f"wrote {path}")
        return output.EXIT_OK
    from mdle.experiments.following import SHAPES, random_starts, run_follow, table

    if args.name == "following":
        print(f"{'world':9} {'rc':>4} {'collided':>8} {'min clearance':>13} "
              f"{'mean |d-rc|':>11} {'max |d-rc|':>10}  (second half of the run)")
        for world, rc in SHAPES.items():
            r = run_follow(world, side=args.side, sensing=args.sensing, seed=args.seed,
                           duration=args.duration or 60.0)
            print(f"{world:9} {rc:4.1f} {str(r.collided):>8} {r.min_clearance:13.3f} "
                  f"{r.mean_err:11.3f} {r.max_err:10.3f}")
        return output.EXIT_OK
    runs = []
    for world in SHAPES:
        runs += random_starts(world, 50 if args.runs is None else args.runs, seed=args.seed,
                              side=args.side, sensing=args.sensing,
                              duration=args.duration or 40.0, rate=args.rate,
                              v=1.0 if args.v is None else args.v)
    print(table(runs))
    return output.EXIT_COLLISION if any(r.collided for r in runs) else output.EXIT_OK


#: Options that only the generated study reads.
_GENERATED_ONLY = ("shapes", "starts", "robot", "rc", "kf", "jobs", "csv", "tolerance")


def _misplaced(args: argparse.Namespace) -> str:
    """Say which given option does not apply to this experiment ('' when all do)."""
    def flag(name: str) -> str:
        return "--" + name.replace("_", "-")

    if args.generated and args.name != "random-starts":
        return "--generated only applies to random-starts"
    if args.generated and args.runs is not None:
        return "--runs is for the paper shapes; with --generated use --shapes and --starts"
    if not args.generated:
        given = [n for n in _GENERATED_ONLY if getattr(args, n) is not None]
        given += ["blind_side"] if args.blind_side else []
        if given:
            return f"{flag(given[0])} needs --generated (random-starts on generated obstacles)"
    if args.name != "random-starts":
        for n in ("rate", "v"):
            if getattr(args, n) is not None:
                return f"{flag(n)} only applies to random-starts"
    return ""
