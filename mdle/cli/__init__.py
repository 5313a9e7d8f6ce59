"""The ``mdle`` command line: one module per subcommand.

Each module in :data:`COMMANDS` defines ``add_parser(subparsers)`` (registering its
subcommand with ``set_defaults(handler=run)``) and ``run(args) -> int``. Those modules
import their heavy dependencies inside ``run``, so ``mdle --help`` and ``mdle check``
start fast. :func:`main` installs the signal handlers (:mod:`mdle.console.signals`) before
anything else, so a signal at any moment ends mdle with 128 + its number and a message.
"""

from __future__ import annotations

import atexit
import importlib

# Only what the signal handlers need is imported before they are installed.
import os
import signal
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING

from mdle import __version__
from mdle.console.ending import ProcessEnd
from mdle.console.signals import SIGNALS, SignalGuard

if TYPE_CHECKING:
    import argparse

__all__ = ["main", "build_parser", "COMMANDS"]

#: Subcommand modules under ``mdle.cli``, in the order ``--help`` lists them.
COMMANDS: tuple[str, ...] = ("check", "fmt", "show", "run", "plot", "export", "recover",
                             "worlds", "robots", "repl", "experiment", "sweep", "sim")


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser with every subcommand."""
    import argparse


    parser = argparse.ArgumentParser(
        prog="mdle",
        description="Write, check, simulate and run MDLe motion plans for mobile robots.",
        epilog="Run `mdle COMMAND --help` for a command's options.",
    )
    class Version(argparse.Action):
        """Print the version and whether the per-tick loops are compiled, then exit."""

        def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                     values: object, option_string: str | None = None) -> None:
            from importlib.util import find_spec

            # The C extensions are optional builds: without a C compiler their numpy
            # references run, with the same numbers and a higher cost.
            def how(module: str) -> str:
                return ("compiled loops" if find_spec(module) is not None
                        else "numpy loops; its C extension was not built (no C compiler)")

            print(f"mdle {__version__} (simulator: {how('mdle.sim._kernels')}; "
                  f"whole-scan model: {how('mdle.atoms._searches')}; "
                  f"scan points: {how('mdle.atoms._points')})")
            parser.exit()

    parser.add_argument("--version", action=Version, nargs=0,
                        help="show the version and whether the simulator's, the whole-scan "
                             "model's and the scan points' loops are compiled, then exit")
    parser.add_argument("--debug", action="store_true",
                        help="show Python tracebacks for internal errors")
    sub = parser.add_subparsers(title="commands", metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"mdle.cli.{name}").add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``mdle`` console script; returns the exit code.

    Exit codes (docs/runtime.md has the table): 0 success, 1 errors in the input (plan,
    world, trace) or a robot fault, 2 usage errors, 3 the robot collided or stalled
    fatally, 70 an internal error (a bug in mdle: one line, the traceback with
    ``--debug``), 74 an output file could not be written (disk full), 129/130/143
    ended by SIGHUP/SIGINT (Ctrl-C)/SIGTERM, 141 standard output was closed (``| head``).

    ``argv`` None (the console script) reads ``sys.argv`` and leaves the handlers in
    place, recording only, until the interpreter exits; with ``argv`` given (a caller in
    Python) the previous handlers are restored on return.
    """
    guard = SignalGuard().install(deferred=True)
    ending = ProcessEnd()
    if argv is None:  # the process ends with the command: it frees nothing at exit
        atexit.register(ending.leave)  # the first hook registered is the last to run
    _closed_streams_to_null()
    try:
        code = _main(argv, guard, ending)
        # The command has ended: a signal from here on is recorded, never raised. One
        # raised while the handlers were swapped to ignored escaped with a traceback (exit 1)
        guard.settle()
        ending.code = code
        return code
    except KeyboardInterrupt as exc:  # a signal while the command line was read
        from mdle.console import output

        ending.keep(exc)
        ending.code = output.interrupted(exc, guard)
        return ending.code
    finally:
        if argv is not None:
            guard.restore()
        else:
            _hold_signals_to_the_end()


def _hold_signals_to_the_end() -> None:
    """Ignore SIGINT, SIGTERM and SIGHUP from the command's end to the process's exit.

    The command has said everything; Python then puts the default handlers back while it
    shuts down (60 to 260 ms), and a signal in that window killed mdle with no message
    and a code that was not the command's. Python leaves an ignored signal ignored (it
    resets only the handlers it installed), and ignoring is process-wide, whichever
    thread a signal lands on.
    """
    for sig in SIGNALS:
        try:
            signal.signal(sig, signal.SIG_IGN)
        except (ValueError, OSError):  # not the main thread
            return


def _closed_streams_to_null() -> None:
    """Give a standard stream that was closed at start (``mdle repl >&-``) /dev/null.

    Python sets such a stream to None, and every print then failed as an internal error;
    worse, the first file mdle opened took the free descriptor, so a child process would
    have written its output into a trace. The descriptor gets /dev/null instead, and the
    output goes nowhere, as it would have on a closed stream.
    """
    for fd, name, mode in ((0, "stdin", "r"), (1, "stdout", "w"), (2, "stderr", "w")):
        if getattr(sys, name) is not None:
            continue
        try:
            os.fstat(fd)
        except OSError:  # closed: /dev/null takes its number (the lowest free one)
            null = os.open(os.devnull, os.O_RDWR)
            if null != fd:
                os.dup2(null, fd)
                os.close(null)
        setattr(sys, name, open(fd, mode, closefd=False))


def _main(argv: Sequence[str] | None, guard: SignalGuard, ending: ProcessEnd) -> int:
    from mdle.console import output

    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:  # --help, --version, usage errors
        if guard.received is not None:
            return guard.exit_code
        code = exit_.code
        return code if isinstance(code, int) else (0 if code is None else output.EXIT_USAGE)
    handler = getattr(args, "handler", None)
    if handler is None:
        parser.print_help(sys.stderr)
        return output.EXIT_USAGE
    args.signals = guard
    args.ending = ending
    code = output.guarded(handler, args)
    if guard.pending:  # a signal the command deferred and never acted on
        return guard.exit_code
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
