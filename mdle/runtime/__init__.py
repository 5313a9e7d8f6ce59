"""Executing checked MDLe programs on a backend: the scheduler, its records and its API.

Public names: :func:`run`, :func:`run_named`, :func:`element_of`, :class:`Scheduler`,
:class:`ActiveElement`, the records :class:`Cause`, :class:`EventKind`, :class:`Event`,
:class:`Termination`, :class:`Sample`, :class:`RunResult`, and the observer hooks
:class:`Observer`, :class:`BaseObserver`, :class:`Recorder`.
"""

from __future__ import annotations

from mdle.runtime.api import element_of, run, run_named
from mdle.runtime.events import (
    Cause,
    Collision,
    Event,
    EventKind,
    RunResult,
    Sample,
    Termination,
    ended_how,
)
from mdle.runtime.observer import BaseObserver, Observer, Recorder
from mdle.runtime.scheduler import ActiveElement, Scheduler

__all__ = [
    "run",
    "run_named",
    "element_of",
    "Scheduler",
    "ActiveElement",
    "Cause",
    "Collision",
    "EventKind",
    "Event",
    "Termination",
    "Sample",
    "RunResult",
    "ended_how",
    "Observer",
    "BaseObserver",
    "Recorder",
]
