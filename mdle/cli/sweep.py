"""``mdle sweep``: parameter studies and Monte Carlo of a plan, on all cores or a cluster.

* ``mdle sweep SPEC.yaml [--out DIR] [--jobs N | --dask ADDRESS] [--keep-traces]``: run
  every combination the spec describes that is not yet in ``DIR/results.csv``.
* ``mdle sweep report RESULTS [--by AXIS] [--metric NAME] [--plots DIR]``: summary tables
  per value of each swept axis, and plots.

Exit codes: 0 the sweep finished (failed runs are rows of the table, not errors), 1 a bad
spec or results table, 2 usage, 130 interrupted (the table keeps every finished run;
rerun the same command to resume).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

from mdle.console import output
from mdle.core.errors import MdleError

__all__ = ["add_parser", "run", "progress_bar"]


def add_parser(subparsers: Any) -> None:
    """Register ``mdle sweep``."""
    p = subparsers.add_parser(
        "sweep", help="parameter studies and Monte Carlo over many simulated runs",
        description="Run a study (worlds x robots x sensing x rates x seeds x starts x plan "
                    "parameters) on every core or a Dask cluster, one row per run in "
                    "DIR/results.csv; `mdle sweep report RESULTS` summarises and plots it.",
        epilog="Rerunning an interrupted sweep resumes it: finished runs are skipped.")
    p.add_argument("spec", metavar="SPEC.yaml|report", help="the study spec, or `report`")
    p.add_argument("results", nargs="?", metavar="RESULTS",
                   help="report: the results folder (or its results.csv/.parquet)")
    p.add_argument("--out", "-o", type=Path, metavar="DIR",
                   help="results folder (default: SPEC-results in the current folder)")
    p.add_argument("--jobs", "-j", type=_jobs, metavar="N",
                   help="local worker processes (default: every core)")
    p.add_argument("--dask", metavar="ADDRESS",
                   help="run on a Dask cluster (scheduler address, e.g. tcp://host:8786)")
    p.add_argument("--keep-traces", action="store_true",
                   help="also keep each run's trace (DIR/traces/KEY.jsonl.gz)")
    p.add_argument("--dry-run", action="store_true",
                   help="check the spec and say how many runs it describes")
    p.add_argument("--by", action="append", metavar="AXIS",
                   help="report: summarise by this column (param name, rate, world...; "
                        "repeatable; default every column that varies)")
    p.add_argument("--metric", default=None, metavar="NAME",
                   help="report: the column to plot (default follow_mean_err when runs "
                        "follow a boundary, else min_clearance)")
    p.add_argument("--group", metavar="AXIS",
                   help="report: draw one median line per value of this column")
    p.add_argument("--plots", type=Path, metavar="DIR",
                   help="report: folder for the plots (default RESULTS/plots)")
    p.add_argument("--no-plots", action="store_true", help="report: tables only")
    p.set_defaults(handler=run)


def _jobs(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of processes, got {text!r}"
                                         ) from None
    if n < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {n}")
    return n


def run(args: argparse.Namespace) -> int:
    """Run a sweep or a report."""
    if args.spec == "report":
        if not args.results:
            print("mdle sweep report: give the results folder (or results.csv)",
                  file=sys.stderr)
            return output.EXIT_USAGE
        return _report(args)
    if args.results:
        print(f"mdle sweep: unexpected argument `{args.results}` (did you mean `mdle sweep "
              f"report {args.results}`?)", file=sys.stderr)
        return output.EXIT_USAGE
    if args.dask and args.jobs:
        print("mdle sweep: --jobs is for local processes; a Dask cluster has its own workers",
              file=sys.stderr)
        return output.EXIT_USAGE
    return _sweep(args)


def _sweep(args: argparse.Namespace) -> int:

    from mdle.sweep import read_study, run_sweep
    from mdle.sweep.executors import DaskExecutor, LocalExecutor, default_jobs

    spec_path = Path(args.spec)
    if not (args.dask or args.dry_run):
        LocalExecutor(args.jobs).start()   # the workers' server loads mdle as the study is read
    study = read_study(spec_path)
    if args.keep_traces:
        study = replace(study, keep_traces=True)
    out = args.out if args.out is not None else Path(f"{spec_path.stem}-results")
    if args.dry_run:
        print(f"{spec_path}: {study.size()} runs ({len(study.worlds)} worlds x "
              f"{len(study.robots)} robots x {len(study.sensing)} sensing x "
              f"{len(study.rates)} rates x {len(study.parameters)} parameter sets x "
              f"{len(study.seeds)} seeds x starts); results would go to {out}")
        return output.EXIT_OK
    executor: Any
    if args.dask:
        executor = DaskExecutor(args.dask)
        where = f"Dask cluster {args.dask} ({executor.threads()} worker threads)"
    else:
        executor = LocalExecutor(args.jobs)
        where = f"{executor.jobs} local processes" + (
            "" if args.jobs else f" (all {default_jobs()} cores)")
    from mdle.core.userfile import UserFileError, read_user_file, writable_folder

    try:  # read again for the results folder's copy: the file may have gone meanwhile
        spec_text = read_user_file(spec_path).decode("utf-8", "replace")
        writable_folder(out)  # before the runs, not after them
    except UserFileError as err:
        raise MdleError(f"--out: {err}" if err.path == str(out) else str(err)) from None
    progress = _RichProgress(where)
    # SIGINT, SIGTERM and SIGHUP reach the sweep as the command line's signal guard's
    # interruption: run_sweep stops its workers and keeps every finished row
    summary = run_sweep(study, out, executor=executor, progress=progress, spec_text=spec_text)
    tail = f"; Parquet: {summary.parquet}" if summary.parquet else ""
    print(f"{summary.done} runs done ({summary.failed} failed), {summary.skipped} already in "
          f"the table; table: {summary.table}{tail}", file=sys.stderr)
    if summary.interrupted:
        print(f"interrupted: every finished run is in {summary.table}; run the same command "
              "again to resume", file=sys.stderr)
        guard = getattr(args, "signals", None)  # 143 for SIGTERM, 129 for SIGHUP
        return guard.exit_code if guard is not None and guard.received is not None \
            else output.EXIT_INTERRUPTED
    print(f"summary: mdle sweep report {out}", file=sys.stderr)
    return output.EXIT_OK


class _RichProgress:
    """Progress on standard error: a rich bar on a terminal, else a line every 10 s."""

    def __init__(self, where: str) -> None:
        self.where = where
        self.failed = 0
        self.done = 0
        self.total = 0
        self._bar: Any = None
        self._task: Any = None
        self._console: Any = None
        self._t0 = self._last = 0.0
        self._skipped = 0

    def start(self, total: int, skipped: int) -> None:
        """Show the bar (the skipped runs count as done)."""
        import time

        from rich.console import Console
        from rich.progress import TextColumn

        from mdle.cli.progress import bar

        self.total, self.done, self._skipped = total, skipped, skipped
        self._t0 = self._last = time.monotonic()
        console = self._console = Console(stderr=True)
        console.print(f"{total} runs, {skipped} already in the table; running on "
                      f"{self.where}", highlight=False)
        if not console.is_terminal:
            return
        self._bar = bar(console, "sweep", TextColumn("[red]{task.fields[failed]} failed"))
        self._bar.start()
        self._task = self._bar.add_task("sweep", total=total, completed=skipped, failed=0)

    def advance(self, row: dict[str, Any]) -> None:
        """Count a finished run."""
        import time

        from mdle.sweep.engine import FAILED

        self.failed += row.get("status") in FAILED
        self.done += 1
        if self._bar is not None:
            self._bar.update(self._task, advance=1, failed=self.failed)
            return
        now = time.monotonic()
        if now - self._last >= 10.0 or self.done == self.total:
            self._last = now
            rate = (self.done - self._skipped) / max(now - self._t0, 1e-9)
            eta = (self.total - self.done) / rate if rate > 0 else float("inf")
            print(f"sweep: {self.done}/{self.total} runs, {self.failed} failed, "
                  f"{now - self._t0:.0f} s, ETA {eta:.0f} s", file=sys.stderr, flush=True)

    def interrupted(self) -> None:
        """Say at once that the runs stop (ending the workers and the table takes longer)."""
        self.stop()
        print("interrupted: stopping the workers; every finished run is kept", file=sys.stderr,
              flush=True)

    def stop(self) -> None:
        """Leave the final bar on screen."""
        if self._bar is not None:
            self._bar.stop()
            self._bar = None


def progress_bar(where: str) -> _RichProgress:
    """Return the sweep's progress display (stderr) for runs on ``where``."""
    return _RichProgress(where)


def _report(args: argparse.Namespace) -> int:
    from mdle.sweep.report import axes, format_summary, plot_axes
    from mdle.sweep.table import read_rows

    rows = read_rows(args.results)
    if not rows:
        print(f"{args.results}: the table has no runs yet", file=sys.stderr)
        return output.EXIT_OK
    names = None
    if args.by:
        names = []
        for b in args.by:
            col = b if b in rows[0] else f"param_{b}"
            if col not in rows[0]:
                raise MdleError(f"--by {b}: no such column (swept: "
                                f"{', '.join(a.removeprefix('param_') for a in axes(rows))})")
            names.append(col)
    print(format_summary(rows, names))
    if args.no_plots:
        return output.EXIT_OK
    metric = args.metric or ("follow_mean_err" if any(r.get("follow_mean_err") is not None
                                                      for r in rows) else "min_clearance")
    if metric not in rows[0]:
        raise MdleError(f"--metric {metric}: no such column; numeric columns: "
                        + ", ".join(c for c, v in rows[0].items()
                                    if isinstance(v, (int, float)) and not isinstance(v, bool)))
    base = Path(args.results)
    folder = args.plots or ((base if base.is_dir() else base.parent) / "plots")
    from mdle.core.userfile import UserFileError, writable_folder

    try:
        writable_folder(folder)
    except UserFileError as err:
        raise MdleError(f"--plots: {err}") from None
    group = None
    if args.group:
        group = args.group if args.group in rows[0] else f"param_{args.group}"
        if group not in rows[0]:
            raise MdleError(f"--group {args.group}: no such column")
    for path in plot_axes(rows, folder, metric, names, group):
        print(f"wrote {path}")
    return output.EXIT_OK
