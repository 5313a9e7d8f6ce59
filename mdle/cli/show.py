"""``mdle show FILE``: the program's tree and its structure figures.

Prints the element tree (atoms with their control laws and arguments, behaviors and
plans, each with its interrupt and timer) and the figures: number of atoms, distinct
control laws, nesting depth and worst-case duration.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> None:
    """Register ``mdle show``."""
    p = subparsers.add_parser(
        "show", help="show a plan's tree and structure figures",
        description="Show the element tree of a checked plan (its entry, or --plan NAME) "
                    "and its figures: atoms, distinct control laws, nesting depth, "
                    "worst-case duration.")
    p.add_argument("file", metavar="FILE", help="plan file")
    p.add_argument("--plan", metavar="NAME",
                   help="the atom, behavior or plan to show (default: the entry; every "
                        "runnable definition if there is none)")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Show the program; returns the exit code."""
    from mdle.console.output import EXIT_INPUT, EXIT_OK, print_diagnostics
    from mdle.lang import load_program, show_program

    program = load_program(args.file)  # an MdleError is reported by the CLI guard
    if program.warnings:
        print_diagnostics(program.warnings, program.sources)
    if args.plan is not None and args.plan not in program.elements:
        import difflib

        close = difflib.get_close_matches(args.plan, list(program.elements), n=1)
        hint = f" (did you mean `{close[0]}`?)" if close else ""
        runnable = ", ".join(sorted(program.elements)) or "none"
        print(f"mdle show: no runnable element `{args.plan}` in {args.file}{hint}; "
              f"runnable: {runnable}", file=sys.stderr)
        return EXIT_INPUT
    sys.stdout.write(show_program(program, args.plan))
    return EXIT_OK
