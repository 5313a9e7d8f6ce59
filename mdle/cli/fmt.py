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
    from mdle.console.output import EXIT_INPUT, EXIT_OK, print_diagnostics
    from mdle.core.errors import Diagnostic, MdleError
    from mdle.lang import format_source, read_source

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
                problem = _rewrite(path, out)
                if problem is not None:
                    print_diagnostics([Diagnostic(None, f"cannot write `{path}`: {problem}")])
                    status = EXIT_INPUT
                    continue
                print(f"reformatted {path}", file=sys.stderr)
        else:
            sys.stdout.write(out)
    return status if files else EXIT_INPUT


def _rewrite(path: str, text: str) -> str | None:
    """Replace the file's text whole (a new file renamed over it); return why not, or None.

    A file that cannot be written (read-only, on a read-only disk) is left as it is; so is
    one whose new text cannot be written in full (a full disk).
    """
    import os

    if not os.access(path, os.W_OK):
        return "the file is read-only (or not yours)"
    path = os.path.realpath(path)  # through a link: the file it names is rewritten
    head, name = os.path.split(path)
    tmp = os.path.join(head, f".{name}.{os.getpid()}.fmt")
    try:
        with open(tmp, "w", encoding="utf-8", newline="\n") as f:
            f.write(text)
        os.chmod(tmp, os.stat(path).st_mode & 0o7777)
        os.replace(tmp, path)
    except OSError as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        return exc.strerror or str(exc)
    return None
