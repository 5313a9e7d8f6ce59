"""``mdle repl``: compose atoms and try them on a simulated robot, interactively.

On a terminal: a prompt with history, completion and highlighting. With input piped in:
plain lines, no control codes, exit 0 or 1 if any input failed.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from mdle.cli.options import add_simulation_options, positive_seconds

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> None:
    """Register ``mdle repl``."""
    p = subparsers.add_parser(
        "repl", help="compose and try atoms interactively on a simulated robot",
        description="An interactive session with a simulated robot: type MDLe definitions "
                    "to add them and elements to run them from where the robot is; `:help` "
                    "lists the commands. With input piped in, reads it line by line and "
                    "exits with 0, or 1 if any input failed.",
        epilog="History is kept in $XDG_DATA_HOME/mdle/repl_history "
               "(~/.local/share/mdle/repl_history).")
    p.add_argument("file", nargs="?", metavar="FILE.mdle", help="definitions to load first")
    p.add_argument("--world", metavar="NAME|FILE",
                   help="simulated world: a reference world name or a YAML file "
                        "(default: the default world)")
    add_simulation_options(p)
    p.add_argument("--until", type=positive_seconds, metavar="SECONDS",
                   help="stop any run after this many simulated seconds (default 600; "
                        "`inf`: no limit)")
    p.add_argument("--realtime", action="store_true",
                   help="pace runs to the wall clock (default: as fast as the simulator goes)")
    p.add_argument("--plain", action="store_true",
                   help="read input plainly even on a terminal (no line editing)")
    p.add_argument("--echo", action="store_true",
                   help="with plain input, print each input after the prompt (a transcript)")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Start the session; returns the exit code."""
    import math

    from mdle.cli import output
    from mdle.repl.commands import Repl
    from mdle.repl.session import DEFAULT_UNTIL, Session

    until = DEFAULT_UNTIL if args.until is None else (None if math.isinf(args.until)
                                                      else args.until)
    session = Session(args.world, seed=args.seed, until=until, robot=args.robot,
                      sensing=args.sensing, realtime=args.realtime)
    repl = Repl(session, debug=getattr(args, "debug", False))
    interactive = sys.stdin.isatty() and sys.stdout.isatty() and not args.plain
    if args.file:
        repl.handle(f":load {_quote(args.file)}")
        if repl.failures and not interactive:
            return output.EXIT_INPUT
    if interactive:
        from mdle.repl.prompt import run_prompt

        return run_prompt(repl)
    from mdle.repl.plain import run_plain

    try:
        return run_plain(repl, sys.stdin, echo=args.echo)
    except KeyboardInterrupt:  # Ctrl-C while waiting for input (a run catches its own)
        print("interrupted", file=sys.stderr)
        return output.EXIT_INTERRUPTED


def _quote(path: str) -> str:
    import shlex

    return shlex.quote(path)
