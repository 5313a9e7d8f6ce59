"""``mdle check FILE...``: parse and check plans; report every error and warning.

Everything the command prints goes to standard output (diagnostics and the summary),
so ``mdle check plan.mdle | less`` shows it all; the exit code tells the result:
0 clean (warnings allowed unless ``--strict``), 1 errors, 2 usage errors.
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import Any

__all__ = ["add_parser", "run", "expand_paths"]


def add_parser(subparsers: Any) -> None:
    """Register ``mdle check``."""
    p = subparsers.add_parser(
        "check", help="check plans for errors (syntax, names, units, timers)",
        description="Parse and check MDLe plans: names, arguments, units, interrupts, "
                    "timers, imports. Prints every error and warning (to standard output) "
                    "with file:line:col and the source line. Exit code: 0 clean, 1 errors, "
                    "2 usage errors.")
    p.add_argument("files", nargs="+", metavar="FILE",
                   help="plan files; a folder means every .mdle file under it; a team file "
                        "(.yaml) is checked whole: its world, every robot's plan, and the "
                        "messages and robot names across them")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="print errors only (no warnings, no summary)")
    p.add_argument("--strict", action="store_true", help="treat warnings as errors (exit 1)")
    p.set_defaults(handler=run)


def expand_paths(paths: list[str]) -> list[str]:
    """Files as given; a folder becomes its .mdle files (recursively, sorted)."""
    out: list[str] = []
    for p in paths:
        if os.path.isdir(p):
            found = sorted(os.path.join(root, f) for root, _, files in os.walk(p)
                           for f in files if f.endswith(".mdle"))
            out.extend(found)
        else:
            out.append(p)
    return out


def _check_team(path: str, quiet: bool) -> int:
    """Check a team file and its plans (MdleError on errors); returns the warnings."""
    from mdle.cli.output import print_diagnostics
    from mdle.teamfile import load_team, read_team

    team = load_team(read_team(path))
    found = list(team.warnings)
    for program in team.programs.values():
        found += program.warnings
    if found and not quiet:
        print_diagnostics(found, team.sources, stream=sys.stdout)
    return len(found)


def run(args: argparse.Namespace) -> int:
    """Check each file; returns the exit code."""
    from mdle.cli.output import EXIT_INPUT, EXIT_OK, print_diagnostics
    from mdle.errors import MdleError
    from mdle.frames import FRAME_NOTE, reads_pose
    from mdle.loader import load_program

    files = expand_paths(args.files)
    errors = warnings = failed = 0
    pose = False
    for path in files:
        try:
            if path.endswith((".yaml", ".yml")):
                found = _check_team(path, args.quiet)
                warnings += found
                continue
            program = load_program(path)
        except MdleError as err:
            failed += 1
            errors += len(err.diagnostics)
            print_diagnostics(err.diagnostics, err.sources, stream=sys.stdout)
            continue
        pose = pose or reads_pose(program)
        warnings += len(program.warnings)
        if program.warnings and not args.quiet:
            print_diagnostics(program.warnings, program.sources, stream=sys.stdout)
    if not args.quiet:
        summary = (f"checked {len(files)} file{'s' * (len(files) != 1)}: "
                   f"{errors} error{'s' * (errors != 1)}, {warnings} warning"
                   f"{'s' * (warnings != 1)}")
        print(summary if files else "no .mdle files found", file=sys.stdout)
        if pose:
            print(f"note: {FRAME_NOTE}", file=sys.stdout)
    if failed or (args.strict and warnings) or not files:
        return EXIT_INPUT
    return EXIT_OK
