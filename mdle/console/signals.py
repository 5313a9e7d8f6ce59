"""SIGINT, SIGTERM and SIGHUP on the command line: a clean end whenever they come.

:func:`mdle.cli.main` installs a :class:`SignalGuard` before it imports anything heavy or
builds its parser, so there is no moment at which one of these signals kills mdle
outright or prints a raw ``KeyboardInterrupt`` traceback. What a signal does depends on
the guard's mode, which the commands set around what they do:

* **raise** (the default while a command works): :class:`Interrupted`, a
  ``KeyboardInterrupt``, is raised where the program is, as Python does for Ctrl-C;
* **defer** (while the command line is parsed, and around the short sections that must
  not be cut: creating the trace, ending the run, closing the robot): the signal is only
  recorded; the code after the section acts on it;
* **stop** (while ``mdle run`` ticks): the first signal asks the scheduler to stop at its
  next tick (robot stopped, trace ended); a second one raises :class:`Interrupted`
  unless the run is already ending.

Python cannot raise everywhere: an exception raised in a weakref callback or a
``__del__`` (the import system's module locks have one) is only reported as "Exception
ignored" and the program goes on. The guard replaces ``sys.unraisablehook`` so that such
a lost :class:`Interrupted` prints nothing and is kept as pending: the next checkpoint
(:meth:`SignalGuard.arm`, :meth:`SignalGuard.stopping`, the end of the command) acts on it.

A process that must not lose even a signal sent while the Python interpreter itself
starts (before any line of mdle runs) can start mdle with these signals blocked: the
guard unblocks them once its handlers are in place, and a signal that was held is acted
on then.
"""

from __future__ import annotations

import signal
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, Protocol

__all__ = ["SIGNALS", "Interrupted", "SignalGuard", "Stoppable", "ends_session",
           "interruption_of", "signal_name"]

#: The signals that end mdle (SIGHUP: the terminal went away).
SIGNALS: tuple[signal.Signals, ...] = tuple(
    s for s in (getattr(signal, n, None) for n in ("SIGINT", "SIGTERM", "SIGHUP"))
    if s is not None)


def signal_name(signum: int) -> str:
    """``SIGINT (Ctrl-C)``, ``SIGTERM``...: how messages and traces name a signal."""
    try:
        name = signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"
    return "SIGINT (Ctrl-C)" if signum == signal.SIGINT else name


def ends_session(exc: BaseException) -> bool:
    """Return True for an interruption that must end an interactive session too.

    Ctrl-C (SIGINT, or a plain ``KeyboardInterrupt``) only stops what runs; SIGTERM and
    SIGHUP end the program.
    """
    return getattr(exc, "signum", signal.SIGINT) != signal.SIGINT


def interruption_of(exc: BaseException) -> KeyboardInterrupt | None:
    """Return the KeyboardInterrupt behind ``exc`` (its cause or context chain), if any.

    Python wraps an exception raised while a class is being made (``__set_name__``, as
    dataclasses do while a module is imported) in a RuntimeError: a signal that lands
    there must still read as the interruption it is, not as an internal error.
    """
    seen: set[int] = set()
    e: BaseException | None = exc
    while e is not None and id(e) not in seen:
        if isinstance(e, KeyboardInterrupt):
            return e
        seen.add(id(e))
        e = e.__cause__ or e.__context__
    return None


class Interrupted(KeyboardInterrupt):
    """A signal ended what was running; ``signum`` says which (exit code 128 + signum)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal_name(signum))
        self.signum = signum
        self.reason = signal_name(signum)


class Stoppable(Protocol):
    """What the guard stops in ``stop`` mode (a :class:`~mdle.runtime.Scheduler`)."""

    @property
    def ending(self) -> bool:
        """True once the run has begun to end."""

    def request_stop(self, reason: str | None = None) -> None:
        """Stop at the next tick."""


class SignalGuard:
    """Handlers for :data:`SIGNALS` whose effect the command chooses (see the module doc).

    ``received`` is the first signal that came (None: none yet); :attr:`exit_code` is
    128 plus its number (130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP).
    """

    def __init__(self) -> None:
        self.received: int | None = None
        self._mode = "raise"
        self._pending = False  # a signal came while deferred and nothing acted on it yet
        self._target: Stoppable | None = None
        self._asked = False  # the target was asked to stop
        self._old: dict[int, Any] = {}
        self._old_hook: Any = None

    # ------------------------------------------------------------------ installation

    def install(self, *, deferred: bool = True) -> SignalGuard:
        """Install the handlers (main thread only), then unblock the signals.

        With ``deferred`` the guard starts in ``defer`` mode. Off the main thread nothing
        is installed (Python allows handlers only there) and the guard stays inert.
        """
        self._mode = "defer" if deferred else "raise"
        try:
            for sig in SIGNALS:
                self._old[sig] = signal.signal(sig, self._handle)
        except ValueError:  # not the main thread
            return self
        self._old_hook = sys.unraisablehook
        sys.unraisablehook = self._unraisable
        if hasattr(signal, "pthread_sigmask"):
            signal.pthread_sigmask(signal.SIG_UNBLOCK, SIGNALS)
        return self

    def restore(self) -> None:
        """Put back the handlers that were there before :meth:`install`."""
        for sig, old in self._old.items():
            signal.signal(sig, old if old is not None else signal.SIG_DFL)
        self._old.clear()
        if self._old_hook is not None:
            sys.unraisablehook = self._old_hook
            self._old_hook = None

    def _unraisable(self, unraisable: Any) -> None:
        """Keep an Interrupted that Python could not raise (see the module doc) as pending."""
        exc = unraisable.exc_value
        if exc is not None and interruption_of(exc) is not None:
            self._pending = True
            return
        (self._old_hook or sys.__unraisablehook__)(unraisable)

    # ------------------------------------------------------------------ modes

    def settle(self) -> None:
        """Enter ``defer`` mode for good: what runs now is the end, signals are only recorded."""
        self._mode = "defer"

    def arm(self) -> None:
        """Enter ``raise`` mode; a signal that came while deferred is raised now."""
        self._mode = "raise"
        self._raise_pending()

    def _raise_pending(self) -> None:
        if self._pending and self.received is not None:
            self._pending = False
            raise Interrupted(self.received)

    @contextmanager
    def deferring(self) -> Iterator[None]:
        """Record signals only, inside the ``with`` block (the code after it checks them)."""
        mode = self._mode
        self._mode = "defer"
        try:
            yield
        finally:
            self._mode = mode

    @contextmanager
    def stopping(self, target: Stoppable) -> Iterator[None]:
        """Inside the block, a signal asks ``target`` to stop; so does one that already came.

        That one may have been deferred, or raised and lost on the way.
        """
        mode, self._mode, self._target, self._asked = self._mode, "stop", target, False
        try:
            # Any signal that came before stops the run at once, not only a deferred one:
            # one raised as Interrupted ends the command before it gets here, unless
            # something on the way swallowed it (Python's "Exception ignored", a
            # library's `except BaseException`); a run must never start after a signal.
            if self.received is not None:
                self._pending = False
                self._asked = True
                target.request_stop(signal_name(self.received))
            yield
        finally:
            self._mode, self._target = mode, None

    @property
    def pending(self) -> bool:
        """True when a signal came while deferred and nothing has acted on it yet."""
        return self._pending

    @property
    def exit_code(self) -> int:
        """128 + the first signal's number (130 when none came: an interruption)."""
        return 128 + (self.received if self.received is not None else int(signal.SIGINT))

    # ------------------------------------------------------------------ the handler

    def _handle(self, signum: int, frame: Any) -> None:
        if self.received is None:
            self.received = signum
        mode = self._mode
        if mode == "defer":
            self._pending = True
            return
        if mode == "stop" and self._target is not None:
            target = self._target
            if not self._asked:
                self._asked = True
                target.request_stop(signal_name(signum))
                return
            if target.ending:
                return
            # a second signal while the run goes on (a tick that does not return):
            # raise once, then only record while the run ends
            self._mode = "defer"
            raise Interrupted(signum)
        raise Interrupted(signum)
