"""``mdle experiment navigation``: a navigation plan over seeded random cluttered worlds.

``--runs N`` worlds (default 200) from seed ``--seed`` on, each run with the ideal unicycle
and the Pioneer 3-DX profile (``--robot NAME`` for one), ``--jobs N`` processes,
``--nav-plan FILE`` for another plan of ``plans/nav/`` shape (default ``plans/nav/bug2.mdle``
in the current folder), ``--csv FILE``
for one row per run. Prints success rate, path length against the straight line, time and
collisions per robot (:mod:`mdle.experiments.navigation`); exit 3 if any run collided.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys

from mdle.console import output

__all__ = ["run_navigation_study"]


def run_navigation_study(args: argparse.Namespace) -> int:
    """Run the study the options describe and print its table."""
    from mdle.cli.progress import steps
    from mdle.cli.tables import print_table
    from mdle.experiments.navigation import COLUMNS, PLAN, ROBOTS, run_study, summary_rows

    worlds = 200 if args.runs is None else args.runs
    robots = ROBOTS if args.robot is None else (args.robot,)
    plan = args.nav_plan if args.nav_plan is not None else PLAN
    if not plan.is_file():
        where = ("" if args.nav_plan is not None else
                 " (the default is read from the repository's top folder: run there, or "
                 "give --nav-plan)")
        print(f"mdle experiment navigation: --nav-plan {plan}: no such file{where}",
              file=sys.stderr)
        return output.EXIT_INPUT
    if args.csv is not None:  # before the work: never over the plan, a folder we can write
        from mdle.cli.csv_output import check_csv_output, write_failed
        from mdle.core.userfile import UserFileError

        try:
            check_csv_output("--csv", args.csv, [("the plan", str(plan))])
        except UserFileError as err:
            return write_failed("mdle experiment navigation", err)
    seeds = range(args.seed, args.seed + worlds)
    with steps("navigation", worlds * len(robots)) as step:
        runs = run_study(seeds, robots, plan, jobs=args.jobs or 1, step=lambda run: step())
    if args.csv is not None:
        from mdle.cli.csv_output import write_csv_output, write_failed
        from mdle.core.userfile import UserFileError

        fields = [fl.name for fl in dataclasses.fields(runs[0])] if runs else []
        try:
            write_csv_output(args.csv, fields,
                             ([getattr(r, name) for name in fields] for r in runs))
        except UserFileError as err:
            return write_failed("mdle experiment navigation", err)
    print_table(sys.stdout, f"navigation: {plan.name} over {worlds} seeded cluttered worlds "
                f"(seeds {seeds.start}-{seeds.stop - 1}), 10 Hz",
                COLUMNS, summary_rows(runs),
                ["reached: the plan ended by its goal interrupt (within 0.3 m of the goal) "
                 "without touching anything",
                 "path / straight line: distance travelled over the start-goal distance, "
                 "over the runs that reached the goal",
                 "least clearance: the smallest gap between the robot's body and an obstacle "
                 "over all runs"])
    failed = [f"{r.robot} seed {r.seed} ({r.ended})" for r in runs if not r.reached]
    if failed:
        print("not reached: " + ", ".join(failed))
    return output.EXIT_COLLISION if any(r.collided for r in runs) else output.EXIT_OK
