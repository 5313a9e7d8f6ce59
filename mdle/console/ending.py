"""The end of an ``mdle`` process: at once, once every output is written.

When a command has ended, all that is left is to free what it built, and Python frees a
checked plan of 200,000 lines or a world of 200,000 circles object by object: half a
second of CPU in which no signal handler runs, and after an interruption half a second
between ``interrupted by SIGINT`` and the process's end. A process about to exit need
not free anything: the command keeps what it built in a :class:`ProcessEnd`
(:func:`keep_to_the_end`), and the console script ends with :meth:`ProcessEnd.leave`
instead of Python's teardown.

:meth:`~ProcessEnd.leave` is registered with :mod:`atexit` before any other hook, so it
runs after all of them (they run last registered, first called): a robot's exit hook
has stopped it, a sweep's workers have been joined, logging has flushed its handlers,
and Python has already waited for the threads that are not daemons. The commands close
their own files (traces end with their ``end`` record on every way out, MCAP files are
renamed into place); what is left in the standard streams' buffers is flushed here.
"""

from __future__ import annotations

import os
import sys
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import argparse

__all__ = ["ProcessEnd", "keep_to_the_end"]


class ProcessEnd:
    """What the process holds until it ends, and the code it ends with.

    ``code`` None (the command has not returned a code: an exception escaped, as with
    ``--debug``) leaves the end to Python. A plain class, not a dataclass: this module is
    imported before the signal handlers are installed, and ``dataclasses`` would add
    its imports to that window.
    """

    def __init__(self) -> None:
        self.code: int | None = None
        self.kept: list[object] = []

    def keep(self, *things: object) -> None:
        """Hold ``things`` until the process ends: they are never freed one by one."""
        self.kept.extend(things)

    def leave(self) -> None:
        """Flush the standard streams, then end the process with :attr:`code`.

        Nothing is freed and Python's own teardown is skipped. A stream that cannot be
        flushed any more (a reader that went away) loses what it held, as it would have.
        """
        if self.code is None:
            return
        for stream in (sys.stdout, sys.stderr):
            try:
                if stream is not None:
                    stream.flush()
            except (OSError, ValueError):  # closed, or its reader is gone
                pass
        os._exit(self.code)


def keep_to_the_end(args: argparse.Namespace, *things: object) -> None:
    """Hand ``things`` to the command line's :class:`ProcessEnd`, when there is one.

    A command called from Python without one (a test, the REPL) frees them as usual.
    """
    end = getattr(args, "ending", None)
    if isinstance(end, ProcessEnd):
        end.keep(*things)
