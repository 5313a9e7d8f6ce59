"""Observers: what watches a run (trace writer, live view, tests) without steering it.

An observer has four hooks, called by the scheduler in this order: ``on_start`` once
before the first tick, ``on_event`` for every element start and end, ``on_tick`` once per
tick with its :class:`~mdle.runtime.events.Sample`, ``on_end`` once with the
:class:`~mdle.runtime.events.RunResult` (also after an error or Ctrl-C). Hooks must be
quick: they run on the control loop.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from mdle.runtime.events import Event, RunResult, Sample

if TYPE_CHECKING:
    from mdle.runtime.scheduler import Scheduler

__all__ = ["Observer", "BaseObserver", "Recorder"]


@runtime_checkable
class Observer(Protocol):
    """Anything with the four observer hooks."""

    def on_start(self, scheduler: "Scheduler") -> None:
        """Handle the start of the run, just before its first tick."""

    def on_event(self, event: Event) -> None:
        """Handle an element starting or ending."""

    def on_tick(self, sample: Sample) -> None:
        """Handle a completed tick (its command has been sent)."""

    def on_end(self, result: RunResult) -> None:
        """Handle the end of the run (whatever the cause), after the robot was stopped."""


class BaseObserver:
    """An observer whose hooks do nothing: subclass it and override what you need."""

    def on_start(self, scheduler: "Scheduler") -> None:
        """Do nothing."""

    def on_event(self, event: Event) -> None:
        """Do nothing."""

    def on_tick(self, sample: Sample) -> None:
        """Do nothing."""

    def on_end(self, result: RunResult) -> None:
        """Do nothing."""


class Recorder(BaseObserver):
    """Keeps everything in memory: events, samples and the result (tests, notebooks)."""

    def __init__(self) -> None:
        self.events: list[Event] = []
        self.samples: list[Sample] = []
        self.result: RunResult | None = None
        self.started: Any = None

    def on_start(self, scheduler: "Scheduler") -> None:
        """Remember the scheduler."""
        self.started = scheduler

    def on_event(self, event: Event) -> None:
        """Append the event."""
        self.events.append(event)

    def on_tick(self, sample: Sample) -> None:
        """Append the sample."""
        self.samples.append(sample)

    def on_end(self, result: RunResult) -> None:
        """Keep the result."""
        self.result = result
