"""``mdle fmt FILE...``: print (or rewrite) plans in canonical form.

The formatter only parses (a plan with unknown names can still be formatted); comments
are kept. Without options it prints the canonical text to standard output; ``--write``
rewrites files that change; ``--check`` lists the files that are not in canonical form
and exits 1 if there are any.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> None:
    """Register ``mdle fmt``."""
    p = subparsers.add_parser(
        "fmt", help="print plans in canonical form (or rewrite them with --write)",
        description="Format MDLe plans canonically: one statement per line, long tuples "
                    "opened one part per line, comments kept.")
    p.add_argument("files", nargs="+", metavar="FILE",
                   help="plan files; a folder means every .mdle file under it")
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("-w", "--write", action="store_true",
                      help="rewrite each file in place (only files that change)")
    mode.add_argument("--check", action="store_true",
                      help="print the files that would change; exit 1 if any")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Format each file; returns the exit code."""
    from mdle.cli.check import expand_paths
    from mdle.cli.output import EXIT_INPUT, EXIT_OK, print_diagnostics
    from mdle.errors import MdleError
    from mdle.format import format_source
    from mdle.loader import read_source

    status = EXIT_OK
    files = expand_paths(args.files)
    for path in files:
        try:
            text = read_source(path)
            out = format_source(text, path)
        except MdleError as err:
            print_diagnostics(err.diagnostics, err.sources)
            status = EXIT_INPUT
            continue
        if args.check:
            if out != text:
                print(f"would reformat {path}")
                status = EXIT_INPUT
        elif args.write:
            if out != text:
                with open(path, "w", encoding="utf-8", newline="\n") as f:
                    f.write(out)
                print(f"reformatted {path}", file=sys.stderr)
        else:
            sys.stdout.write(out)
    return status if files else EXIT_INPUT
