"""``mdle experiment random-starts --generated``: run a study, show its progress and tables.

The runs themselves are :mod:`mdle.experiments.generated`; this module only reads the
options, draws the progress bar (on a terminal), prints the summary tables and the failing
runs, and writes the CSV.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from mdle.console import output
from mdle.core.errors import WorldError

if TYPE_CHECKING:  # numpy and the simulator load only when a study runs (mdle check stays light)
    from mdle.experiments.generated import Row, StudyConfig

__all__ = ["add_arguments", "config_from", "run", "write_csv"]

_FAILURES_SHOWN = 40  # the rest are in the CSV


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the options of the generated study (all default to None: 'not given')."""
    g = p.add_argument_group("random-starts --generated (generated obstacles)")
    g.add_argument("--generated", action="store_true",
                   help="random-starts on generated obstacles instead of the paper's shapes")
    g.add_argument("--shapes", type=int, default=None, metavar="N",
                   help="number of generated shapes (default 30)")
    g.add_argument("--starts", type=int, default=None, metavar="N",
                   help="collision-course starts per shape (default 10)")
    g.add_argument("--blind-side", action="store_true",
                   help="also run as many blind-side starts per shape (reported apart)")
    g.add_argument("--suite", choices=("paper", "lab"), default=None,
                   help="paper: the 13 families of the paper's kind (default); lab: thin poles, "
                        "pole rows, spike stars, disc chains, thin plates, tables")
    g.add_argument("--tangential", type=int, default=None, metavar="N",
                   help="also run N tangential starts per shape, passing a tip or a pole "
                        "(reported apart)")
    g.add_argument("--robot", default=None, metavar="NAME",
                   help="robot profile (default: ideal, the paper's unicycle)")
    g.add_argument("--rc", type=float, default=None, metavar="M",
                   help="following distance, m (default 0.5)")
    g.add_argument("--kf", type=float, default=None, metavar="GAIN",
                   help="distance gain kf, 1/m^2 (default: the atom's)")
    g.add_argument("--jobs", type=int, default=None, metavar="N",
                   help="processes (default: every core); results do not depend on it")
    g.add_argument("--csv", type=Path, default=None, metavar="FILE",
                   help="write one row per run to FILE")
    g.add_argument("--save-failures", type=Path, default=None, metavar="DIR",
                   help="write each failing run's plan and world to DIR, ready for mdle run")
    g.add_argument("--tolerance", type=float, default=None, metavar="M",
                   help="largest second-half mean |d-rc| of an accurate run "
                        "(default 0.08 m at >= 50 Hz, else 0.10 m)")


def config_from(args: argparse.Namespace) -> "StudyConfig | str":
    """Build the study's configuration from the options, or return what is wrong with them."""
    from mdle.experiments.generated import StudyConfig
    from mdle.sim.profiles import robot_profile

    c = StudyConfig()
    cfg = StudyConfig(
        shapes=c.shapes if args.shapes is None else args.shapes,
        starts=c.starts if args.starts is None else args.starts,
        seed=args.seed, side=args.side, sensing=args.sensing,
        robot=c.robot if args.robot is None else args.robot,
        rate=c.rate if args.rate is None else args.rate,
        v=c.v if args.v is None else args.v,
        rc=c.rc if args.rc is None else args.rc,
        kf=args.kf, duration=args.duration, blind=args.blind_side, tolerance=args.tolerance,
        suite=getattr(args, "suite", None) or c.suite,
        tangential=getattr(args, "tangential", None) or c.tangential)
    from mdle.sweep.spec import MAX_AXIS

    checks = [
        (1 <= cfg.shapes <= MAX_AXIS,
         f"--shapes must be at least 1 and at most {MAX_AXIS:,}, got {cfg.shapes}"),
        (1 <= cfg.starts <= MAX_AXIS,
         f"--starts must be at least 1 and at most {MAX_AXIS:,}, got {cfg.starts}"),
        (cfg.seed >= 0, f"--seed must be >= 0, got {cfg.seed}"),
        (math.isfinite(cfg.rate) and cfg.rate > 0, f"--rate must be > 0 Hz, got {cfg.rate:g}"),
        (math.isfinite(cfg.v) and cfg.v > 0, f"--v must be > 0 m/s, got {cfg.v:g}"),
        (math.isfinite(cfg.rc) and cfg.rc > 0, f"--rc must be > 0 m, got {cfg.rc:g}"),
        (cfg.kf is None or (math.isfinite(cfg.kf) and cfg.kf > 0),
         f"--kf must be > 0, got {cfg.kf}"),
        (cfg.duration is None or (math.isfinite(cfg.duration) and cfg.duration > 0),
         f"--duration must be > 0 s, got {cfg.duration}"),
        (cfg.tolerance is None or cfg.tolerance > 0,
         f"--tolerance must be > 0 m, got {cfg.tolerance}"),
        (args.jobs is None or args.jobs >= 1, f"--jobs must be at least 1, got {args.jobs}"),
        (0 <= cfg.tangential <= MAX_AXIS,
         f"--tangential must be from 0 to {MAX_AXIS:,}, got {cfg.tangential}"),
    ]
    for ok, message in checks:
        if not ok:
            return message
    try:
        robot_profile(cfg.robot)
    except WorldError as e:
        return "; ".join(d.message for d in e.diagnostics)
    return cfg


def run(args: argparse.Namespace) -> int:
    """Run the generated study; print the tables; exit 3 if any run collided."""
    cfg = config_from(args)
    if isinstance(cfg, str):
        print(f"mdle experiment random-starts: {cfg}", file=sys.stderr)
        return output.EXIT_USAGE
    from mdle.experiments.generated import study_specs
    from mdle.sim.starts import StartsError

    if args.csv is not None:  # before the work: a folder we can write
        from mdle.cli.csv_output import check_csv_output, write_failed
        from mdle.core.userfile import UserFileError

        try:
            check_csv_output("--csv", args.csv)
        except UserFileError as err:
            return write_failed("mdle experiment random-starts", err)
    try:
        total = len(study_specs(cfg))
    except StartsError as err:  # more starts asked of a shape than it offers
        print(f"mdle experiment random-starts: {err}: ask for fewer (--starts, --tangential)",
              file=sys.stderr)
        return output.EXIT_USAGE
    out = args.out / "random-starts-generated" if getattr(args, "resume", False) else None
    try:
        rows = _run_with_progress(cfg, args.jobs, total, out)
    except KeyboardInterrupt:
        if out is not None:
            print(f"interrupted: finished runs are in {out}/results.csv; run the same command "
                  "again to resume", file=sys.stderr)
        raise
    if args.csv is not None:
        from mdle.cli.csv_output import write_failed
        from mdle.core.userfile import UserFileError

        try:
            write_csv(rows, args.csv)
        except UserFileError as err:
            _print_tables(cfg, rows, sys.stdout)
            return write_failed("mdle experiment random-starts", err)
    _print_tables(cfg, rows, sys.stdout)
    if args.csv is not None:
        print(f"wrote {args.csv} ({len(rows)} runs)")
    if args.save_failures is not None:
        try:
            saved = save_failures(rows, args.save_failures)
        except OSError as e:
            print(f"mdle experiment random-starts: cannot write to {args.save_failures}: "
                  f"{e.strerror}", file=sys.stderr)
            return output.EXIT_INPUT
        print(f"wrote {saved} failing runs to {args.save_failures} (replay: mdle run "
              f"{args.save_failures}/NAME.mdle --rate {cfg.rate:g} --sensing {cfg.sensing})")
    if any(r["error"] for r in rows):
        return output.EXIT_INPUT
    return output.EXIT_COLLISION if any(r["collided"] for r in rows) else output.EXIT_OK


def failure_name(r: Row) -> str:
    """Name a run's replay files: ``SHAPE-start-K`` (``-blind``, ``-tangential`` for those)."""
    from mdle.experiments.generated import row_kind

    kind = row_kind(r)
    return f"{r['shape']}-start-{r['start']}{'' if kind == 'collision' else '-' + kind}"


def save_failures(rows: Sequence[Row], folder: Path) -> int:
    """Write NAME.mdle and NAME.world.yaml for every failing run into ``folder``; count them."""
    from mdle.experiments.generated import RunSpec, replay_files, spec_fields

    folder.mkdir(parents=True, exist_ok=True)
    bad = [r for r in rows if r["outcome"] != "ok"]
    for r in bad:
        spec = RunSpec(**{k: r[k] for k in spec_fields()})
        plan, world = replay_files(spec)
        name = failure_name(r)
        (folder / f"{name}.mdle").write_text(plan, encoding="utf-8")
        (folder / f"{name}.world.yaml").write_text(world, encoding="utf-8")
    return len(bad)


def _run_with_progress(cfg: StudyConfig, jobs: int | None, total: int,
                       out: Path | None = None) -> list[Row]:
    from mdle.cli.progress import steps
    from mdle.experiments.generated import run_study

    with steps("runs", total) as step:
        return run_study(cfg, jobs=jobs, on_row=lambda _row: step(), out=out)


def _fmt(x: float, digits: int = 3) -> str:
    return "-" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.{digits}f}"


def _print_tables(cfg: StudyConfig, rows: Sequence[Row], stream: IO[str]) -> None:
    from rich.console import Console
    from rich.table import Table

    from mdle.experiments.generated import summarise

    tty = stream.isatty()
    # off a terminal: wide enough that no header or failure line wraps (logs, pipes, notes)
    console = Console(file=stream, highlight=False, width=None if tty else 200,
                      force_terminal=tty, no_color=not tty, soft_wrap=not tty)
    head = (f"{cfg.shapes} generated shapes (seed {cfg.seed}"
            f"{', lab suite' if cfg.suite == 'lab' else ''}), {cfg.starts} starts each"
            f"{f' and {cfg.tangential} tangential' if cfg.tangential else ''}; "
            f"{cfg.robot} at {cfg.v:g} m/s, rc {cfg.rc:g} m, {cfg.side} side, "
            f"{cfg.sensing} sensing, {cfg.rate:g} Hz, {cfg.run_duration:g} s runs")
    console.print(head)
    summary = summarise(rows, cfg.accuracy)
    titles = {"collision": "collision-course starts",
              "tangential": "tangential starts (passing a tip, a pole or a plate's end)",
              "blind": "blind-side starts (the obstacle passes on the non-followed side)"}
    for kind, title in titles.items():
        part = [s for s in summary if s["kind"] == kind]
        if not part:
            continue
        t = Table(title=title, title_justify="left")
        for name, justify in (("family", "left"), ("runs", "right"), ("collisions", "right"),
                              ("engaged", "right"), ("worst clearance (m)", "right"),
                              ("median mean |d-rc| (m)", "right"),
                              ("max mean |d-rc| (m)", "right"),
                              ("median time to engage (s)", "right"), ("drove away", "right"),
                              ("failures", "right")):
            t.add_column(name, justify=justify)  # type: ignore[arg-type]
        for s in part:
            pct = 100.0 * s["engaged"] / s["runs"]
            t.add_row(s["family"], str(s["runs"]), str(s["collisions"]),
                      f"{s['engaged']} ({pct:.1f} %)", _fmt(s["worst_clearance"]),
                      _fmt(s["median_err"]), _fmt(s["max_err"]),
                      _fmt(s["median_t_engage"], 1), str(s["away"]),
                      f"{s['failures']}" + (f" ({s['errors']} errors)" if s["errors"] else ""),
                      end_section=s["family"] == "all")
        console.print(t)
    console.print("engaged: |d - rc| <= 0.2 m with the obstacle on the followed side for 4 m "
                  "of path; mean |d-rc| over the second half of the time after engagement; "
                  f"accurate: mean <= {cfg.accuracy:g} m; drove away: ended more than 1 m "
                  "beyond rc from every boundary")
    bad = [r for r in rows if r["outcome"] != "ok"]
    if bad:
        console.print(f"failing runs ({len(bad)}): shape, seed, start, outcome")
        for r in bad[:_FAILURES_SHOWN]:
            console.print("  " + describe_failure(r))
        if len(bad) > _FAILURES_SHOWN:
            console.print(f"  ... and {len(bad) - _FAILURES_SHOWN} more (see --csv)")


def describe_failure(r: Row) -> str:
    """Say in one line which run failed and how (shape, seed, start, what it did)."""
    from mdle.experiments.generated import row_kind

    kind = {"blind": "blind-side", "tangential": f"tangential, {r['gap']:.2f} m off"}.get(
        row_kind(r), f"incidence {math.degrees(r['incidence']):+.0f} deg")
    what = r["outcome"]
    if what == "error":
        detail = r["error"]
    elif what == "collided":
        detail = f"min clearance {r['min_clearance']:.3f} m"
    elif what == "never engaged":
        detail = (f"ended {r['final_d']:.2f} m from the boundary, closest {r['min_d']:.2f} m, "
                  f"{r['blind_path']:.1f} m driven with it on the blind side")
    else:
        detail = f"mean |d-rc| {r['mean_err']:.3f} m, max {r['max_err']:.3f} m"
    return (f"{r['shape']} seed {r['shape_seed']} start {r['start']} ({kind}): {what}, "
            f"{detail}")


#: CSV columns converted from radians to degrees at this edge.
_DEGREES = ("theta0", "incidence")


def write_csv(rows: Sequence[Row], path: Path) -> None:
    """Write one line per run, whole or not at all; angles in degrees (``*_deg``), else SI.

    Raises
    ------
    UserFileError
        The file cannot be written (:func:`mdle.cli.csv_output.write_csv_output`).
    """
    from mdle.cli.csv_output import write_csv_output

    names = [f"{k}_deg" if k in _DEGREES else k for k in rows[0]] if rows else []
    write_csv_output(path, names, ([_cell(k, v) for k, v in r.items()] for r in rows))


def _cell(key: str, value: Any) -> Any:
    if isinstance(value, float):  # full precision: the CSV is data, not a table
        if math.isnan(value):
            return ""
        return repr(math.degrees(value)) if key in _DEGREES else repr(value)
    if value is None:
        return ""
    return value
