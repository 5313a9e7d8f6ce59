"""What the command line prints: diagnostics, exit codes, the internal-error guard.

Colour and rich markup only when standard output or error is a terminal; plain text
otherwise, so logs and pipes carry no control codes.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable, Iterable, Mapping
from typing import IO, TYPE_CHECKING

from mdle.console.ending import keep_to_the_end
from mdle.core.errors import Diagnostic, MdleError, Severity, render_diagnostic

if TYPE_CHECKING:
    from mdle.console.signals import SignalGuard

__all__ = [
    "EXIT_OK",
    "EXIT_INPUT",
    "EXIT_USAGE",
    "EXIT_COLLISION",
    "EXIT_INTERNAL",
    "EXIT_INTERRUPTED",
    "EXIT_IO",
    "EXIT_PIPE",
    "print_diagnostics",
    "guarded",
    "interrupted",
    "output_closed",
]

EXIT_OK = 0
EXIT_INPUT = 1
EXIT_USAGE = 2
EXIT_COLLISION = 3
EXIT_INTERNAL = 70
#: An output file (the trace, a plot) could not be written: disk full, I/O error
#: (sysexits' EX_IOERR).
EXIT_IO = 74
#: Ctrl-C (SIGINT); SIGTERM gives 143 and SIGHUP 129: 128 + the signal's number.
EXIT_INTERRUPTED = 130
#: Standard output was closed (``mdle run ... | head``): 128 + SIGPIPE, what a shell
#: reports for a program a closed pipe ends.
EXIT_PIPE = 141

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
    """Run a subcommand; turn MdleErrors into diagnostics and anything else into one line.

    A signal guard in ``args.signals`` is armed first (a signal that came while the
    command line was read ends the command here), unless the handler manages the guard
    itself (``args.own_signals``).
    """
    guard: SignalGuard | None = getattr(args, "signals", None)
    try:
        if guard is not None and not getattr(args, "own_signals", False):
            guard.arm()
        return handler(args)
    except MdleError as err:
        keep_to_the_end(args, err)
        print_diagnostics(err.diagnostics, getattr(err, "sources", None))
        return EXIT_INPUT
    except KeyboardInterrupt as exc:
        keep_to_the_end(args, exc)  # its frames hold what the command built: not freed
        return interrupted(exc, guard)
    except BrokenPipeError:
        output_closed()
        return EXIT_PIPE
    except OSError as exc:
        from mdle.core.userfile import file_fault, file_fault_words

        if not file_fault(exc):
            return _internal(exc, args)
        print(f"mdle: {file_fault_words(exc)}", file=sys.stderr)
        return EXIT_IO
    except Exception as exc:  # an mdle bug: never a raw traceback unless asked
        from mdle.console.signals import interruption_of

        signal_exc = interruption_of(exc)
        if signal_exc is not None:  # a signal inside class creation, wrapped by Python
            keep_to_the_end(args, exc)
            return interrupted(signal_exc, guard)
        return _internal(exc, args)


def _internal(exc: Exception, args: argparse.Namespace) -> int:
    if getattr(args, "debug", False):
        raise exc
    print(f"mdle: internal error: {type(exc).__name__}: {exc} (run with --debug for the "
          "traceback)", file=sys.stderr)
    return EXIT_INTERNAL




def interrupted(exc: BaseException, guard: SignalGuard | None) -> int:
    """Say that a signal ended the command; return 128 + its number."""
    from mdle.console.signals import signal_name

    signum = getattr(exc, "signum", None)
    if signum is None and guard is not None:
        signum = guard.received
    code = 128 + signum if signum is not None else EXIT_INTERRUPTED
    try:
        print(f"mdle: interrupted by {signal_name(code - 128)}", file=sys.stderr)
    except OSError:  # no one to tell
        pass
    return code


def output_closed() -> None:
    """Point standard output at /dev/null after EPIPE, so nothing more fails on it.

    Whatever is still printed (and the flush at exit) then goes nowhere instead of raising
    again, as ``head``-friendly programs behave.
    """
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):  # no real file descriptor behind stdout
        pass
    try:
        sys.stdout.flush()  # what was left in the buffer goes nowhere now
    except (OSError, ValueError):
        pass
