"""Observers ready to subclass or use: what watches a run without steering it.

The hooks themselves (:class:`~mdle.runtime.events.Observer`: ``on_start``, ``on_event``,
``on_tick``, ``on_end``) are declared with the events, in :mod:`mdle.runtime.events`,
which the scheduler imports; this module is for observers (the live view, tests,
notebooks), and the scheduler does not import it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from mdle.runtime.events import Event, Observer, RunResult, Sample

if TYPE_CHECKING:
    from mdle.runtime.scheduler import Scheduler

__all__ = ["Observer", "BaseObserver", "Recorder"]


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
