"""The ``mdle`` command line: one module per subcommand.

Each module in :data:`COMMANDS` defines ``add_parser(subparsers)`` (registering its
subcommand with ``set_defaults(handler=run)``) and ``run(args) -> int``. Those modules
import their heavy dependencies inside ``run``, so ``mdle --help`` and ``mdle check``
start fast.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from mdle import __version__
from mdle.cli import output

__all__ = ["main", "build_parser", "COMMANDS"]

#: Subcommand modules under ``mdle.cli``, in the order ``--help`` lists them.
COMMANDS: tuple[str, ...] = ("check", "fmt", "show", "run", "plot", "export", "worlds",
                             "robots", "repl", "experiment", "sweep")


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser with every subcommand."""
    parser = argparse.ArgumentParser(
        prog="mdle",
        description="Write, check, simulate and run MDLe motion plans for mobile robots.",
        epilog="Run `mdle COMMAND --help` for a command's options.",
    )
    parser.add_argument("--version", action="version", version=f"mdle {__version__}")
    parser.add_argument("--debug", action="store_true",
                        help="show Python tracebacks for internal errors")
    sub = parser.add_subparsers(title="commands", metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"mdle.cli.{name}").add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``mdle`` console script; returns the exit code.

    Exit codes: 0 success, 1 errors in the input (plan, world), 2 usage errors,
    3 the robot collided or stalled fatally, 130 interrupted (Ctrl-C), 70 an internal
    error (a bug in mdle: reported in one line, traceback with ``--debug``).
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    handler = getattr(args, "handler", None)
    if handler is None:
        parser.print_help(sys.stderr)
        return output.EXIT_USAGE
    return output.guarded(handler, args)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
