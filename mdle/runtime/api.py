"""The runtime's Python API for supervisors, the REPL and tests.

MDLe has no branching: a supervisor runs an element, reads how it ended and picks what
runs next::

    program = load_program("plans/patrol.mdle")
    backend = SimBackend(load_world("corridor"))
    result = run_named(program, "explore", backend, until=60)
    if result.termination.cause is Cause.INTERRUPT:
        result = run_named(program, "go_home", backend)
    backend.close()

:func:`run` stops the robot at the end but never closes the backend, so the next run
continues from where the robot is, on the same clock.
"""

from __future__ import annotations

import difflib
from collections.abc import Sequence

from mdle.core.backend import Backend
from mdle.core.errors import Diagnostic, MdleRuntimeError
from mdle.lang import Element, Program
from mdle.runtime.events import Observer, RunResult
from mdle.runtime.scheduler import DEFAULT_STALL_TIMEOUT, Scheduler

__all__ = ["run", "run_named", "element_of"]


def run(element: Element, backend: Backend, *, rate: float = 10.0, until: float | None = None,
        observers: Sequence[Observer] = (), realtime: bool = False,
        stall_timeout: float | None = DEFAULT_STALL_TIMEOUT) -> RunResult:
    """Run ``element`` on ``backend`` to its end and return how it ended.

    Parameters
    ----------
    element : Element
        A checked element (``program.elements[name]``).
    backend : Backend
        The robot; stopped at the end whatever the cause, not closed.
    rate : float
        Control rate, Hz.
    until : float or None
        Stop after this many seconds of backend time (cause STOPPED).
    observers : sequence of Observer
        Trace writers, live views, recorders.
    realtime : bool
        Pace a simulated backend to the wall clock.
    stall_timeout : float or None
        Abort after the robot has been stalled (or refused to move) this long, s.

    Returns
    -------
    RunResult

    Raises
    ------
    MdleRuntimeError
        A control law or interrupt failed (the robot has been stopped first).
    BackendError
        The robot or its connection failed.
    KeyboardInterrupt
        Ctrl-C without a handler; the robot has been stopped and observers told.
    """
    scheduler = Scheduler(element, backend, rate, observers, until=until, realtime=realtime,
                          stall_timeout=stall_timeout)
    scheduler.start()
    while scheduler.tick():
        pass
    assert scheduler.result is not None
    return scheduler.result


def element_of(program: Program, name: str | None = None) -> Element:
    """Return the element called ``name`` in ``program`` (its entry when None).

    Raises
    ------
    MdleRuntimeError
        No such element (the message lists what can run), or no entry.
    """
    if name is None:
        name = program.entry
        if name is None:
            raise MdleRuntimeError(Diagnostic(
                None, "the program has no entry: add `run NAME` or a plan named `main`",
                hint=_listing(program)))
    try:
        return program.elements[name]
    except KeyError:
        close = difflib.get_close_matches(name, list(program.elements), n=1)
        hint = f"did you mean `{close[0]}`?" if close else _listing(program)
        raise MdleRuntimeError(Diagnostic(None, f"no runnable element named `{name}`",
                                          hint=hint)) from None


def run_named(program: Program, name: str | None, backend: Backend, **options: object
              ) -> RunResult:
    """Run the element ``name`` of ``program`` (its entry when None); see :func:`run`."""
    return run(element_of(program, name), backend, **options)  # type: ignore[arg-type]


def _listing(program: Program) -> str:
    names = sorted(program.elements)
    return ("runnable: " + ", ".join(names)) if names else "the program defines nothing runnable"
