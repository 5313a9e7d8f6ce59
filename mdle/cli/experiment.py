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

``following`` and ``random-starts`` run on the sweep engine (:mod:`mdle.sweep`): every core
(``--jobs N``), a progress bar on standard error, and with ``--resume`` a results table in
``OUT/NAME/results.csv`` (``OUT/random-starts-generated`` for ``--generated``) that an
interrupted experiment picks up again.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from mdle.cli import generated_study
from mdle.cli.options import hertz
from mdle.console import output
from mdle.core.errors import MdleError

__all__ = ["add_parser", "run"]

EXPERIMENTS = ("curvature", "following", "random-starts", "navigation")


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
    p.add_argument("--rate", type=hertz, default=None, metavar="HZ",
                   help="random-starts: control rate (default: 50 Hz scan, 100 Hz exact; "
                        "--generated: 10 Hz)")
    p.add_argument("--v", type=float, default=None, metavar="M/S",
                   help="random-starts: speed (default 1 m/s)")
    p.add_argument("--resume", action="store_true",
                   help="following/random-starts: keep each run's row in OUT/NAME/results.csv "
                        "and skip the runs already there")
    p.add_argument("--nav-plan", type=Path, default=None, metavar="FILE",
                   help="navigation: the plan to run (default plans/nav/bug2.mdle, here)")
    generated_study.add_arguments(p)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Run the chosen experiment and print its table."""
    if (args.draws < 1 or (args.runs is not None and args.runs < 1)
            or (args.jobs is not None and args.jobs < 1)):
        print("mdle experiment: --draws, --runs and --jobs must be at least 1",
              file=sys.stderr)
        return output.EXIT_USAGE
    if args.name == "navigation":  # its own options: mdle/cli/navigation.py
        from mdle.cli.navigation import run_navigation_study

        return run_navigation_study(args)
    misplaced = _misplaced(args)
    if misplaced:
        print(f"mdle experiment {args.name}: {misplaced}", file=sys.stderr)
        return output.EXIT_USAGE
    if args.name == "curvature" or getattr(args, "resume", False):
        from mdle.core.userfile import UserFileError, writable_folder

        try:  # before the computing: its results go there
            writable_folder(args.out)
        except UserFileError as err:
            raise MdleError(f"--out: {err}") from None
    if args.generated:
        return generated_study.run(args)
    if args.name == "curvature":
        from mdle.cli.progress import steps
        from mdle.experiments.curvature import (
            OBJECTS,
            ROWS,
            format_table,
            plot_figures,
            run_table,
        )

        with steps("Table 1", len(OBJECTS) * len(ROWS)) as step:
            result = run_table(args.draws, args.seed, step=step)
        print(format_table(result))
        for path in plot_figures(args.out, seed=args.seed):
            print(f"wrote {path}")
        return output.EXIT_OK
    from mdle.cli.tables import metres, print_table, yes_no
    from mdle.experiments.following import (
        SHAPES,
        TABLE_NOTES,
        follow_task,
        random_start_tasks,
        table_rows,
    )

    out = args.out / args.name if args.resume else None
    if args.name == "following":
        tasks = [follow_task(world, side=args.side, sensing=args.sensing, seed=args.seed,
                             duration=args.duration or 60.0, index=i)
                 for i, world in enumerate(SHAPES)]
        runs = _run(tasks, args, out)
        print_table(sys.stdout, f"boundary following, {args.sensing} sensing, {args.side} side, "
                    f"{args.duration or 60.0:g} s runs",
                    [("world", "left"), ("rc (m)", "right"), ("collided", "left"),
                     ("min clearance (m)", "right"), ("mean |d - rc| (m)", "right"),
                     ("max |d - rc| (m)", "right")],
                    [(r.world, f"{r.rc:g}", yes_no(r.collided), metres(r.min_clearance),
                      metres(r.mean_err), metres(r.max_err)) for r in runs],
                    ["d: true distance from the robot's centre to the nearest boundary; "
                     "|d - rc| over the second half of the run (the approach left out)",
                     "min clearance: the smallest gap between the robot's body and an "
                     "obstacle over the whole run"])
        return output.EXIT_COLLISION if any(r.collided for r in runs) else output.EXIT_OK
    tasks = []
    for world in SHAPES:
        tasks += random_start_tasks(world, 50 if args.runs is None else args.runs,
                                    seed=args.seed, side=args.side, sensing=args.sensing,
                                    duration=args.duration or 40.0, rate=args.rate,
                                    v=1.0 if args.v is None else args.v)
    runs = _run(tasks, args, out)
    print_table(sys.stdout, f"random starts, {args.sensing} sensing, {args.side} side",
                [("world", "left"), ("sensing", "left"), ("runs", "right"),
                 ("collisions", "right"), ("worst clearance (m)", "right"),
                 ("median mean |d - rc| (m)", "right"), ("engaged", "right")],
                [(w, sensing, str(n), str(hits), metres(worst), metres(err), f"{eng}/{n}")
                 for w, sensing, n, hits, worst, err, eng in table_rows(runs)],
                TABLE_NOTES)
    return output.EXIT_COLLISION if any(r.collided for r in runs) else output.EXIT_OK


def _run(tasks: list[Any], args: argparse.Namespace, out: Path | None) -> list[Any]:
    """Run the experiment's tasks on the sweep engine, with a progress display on stderr."""
    from mdle.cli.sweep import progress_bar
    from mdle.experiments.following import run_many
    from mdle.sweep.executors import default_jobs

    jobs = args.jobs or default_jobs()
    try:
        return run_many(tasks, jobs=jobs, out=out, progress=progress_bar(f"{jobs} processes"))
    except KeyboardInterrupt:
        if out is not None:
            print(f"interrupted: finished runs are in {out}/results.csv; run the same command "
                  "again to resume", file=sys.stderr)
        raise


#: Options that only the generated study reads.
_GENERATED_ONLY = ("shapes", "starts", "robot", "rc", "kf", "csv", "tolerance", "suite",
                   "tangential")


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
