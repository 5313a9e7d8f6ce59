"""What the command line prints: diagnostics, exit codes, the internal-error guard.

Colour and rich markup only when standard output or error is a terminal; plain text
otherwise, so logs and pipes carry no control codes.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterable, Mapping
from typing import IO

from mdle.errors import Diagnostic, MdleError, Severity, render_diagnostic

__all__ = [
    "EXIT_OK",
    "EXIT_INPUT",
    "EXIT_USAGE",
    "EXIT_COLLISION",
    "EXIT_INTERNAL",
    "EXIT_INTERRUPTED",
    "print_diagnostics",
    "guarded",
]

EXIT_OK = 0
EXIT_INPUT = 1
EXIT_USAGE = 2
EXIT_COLLISION = 3
EXIT_INTERNAL = 70
EXIT_INTERRUPTED = 130

_STYLE = {Severity.ERROR: "bold red", Severity.WARNING: "bold yellow", Severity.NOTE: "cyan"}


def print_diagnostics(diagnostics: Iterable[Diagnostic], sources: Mapping[str, str] | None = None,
                      stream: IO[str] | None = None) -> None:
    """Print diagnostics with their source lines; coloured only on a terminal."""
    stream = stream or sys.stderr
    tty = stream.isatty()
    console = None
    if tty:
        from rich.console import Console

        console = Console(file=stream, highlight=False)
    for d in diagnostics:
        text = render_diagnostic(d, dict(sources or {}))
        if console is None:
            print(text, file=stream)
            continue
        from rich.text import Text

        head, _, rest = text.partition("\n")
        line = Text(head)
        label = f"{d.severity.value}:"
        at = head.find(label)
        if at >= 0:
            line.stylize(_STYLE[d.severity], at, at + len(label))
        console.print(line)
        if rest:
            console.print(Text(rest))
    stream.flush()


def guarded(handler: Callable[[argparse.Namespace], int], args: argparse.Namespace) -> int:
    """Run a subcommand; turn MdleErrors into diagnostics and anything else into one line."""
    try:
        return handler(args)
    except MdleError as err:
        print_diagnostics(err.diagnostics, getattr(err, "sources", None))
        return EXIT_INPUT
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        return EXIT_OK
    except Exception as exc:  # an mdle bug: never a raw traceback unless asked
        if getattr(args, "debug", False):
            raise
        print(f"mdle: internal error: {type(exc).__name__}: {exc} (run with --debug for the "
              "traceback)", file=sys.stderr)
        return EXIT_INTERNAL
