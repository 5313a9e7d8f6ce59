"""A REPL session's runs: each run's recorder, and the runs since a reset as one trace.

A run loaded from a recording is kept as a :class:`_Run` too, with a :class:`_Recorded`
standing in for the scheduler the trace writer reads.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

from mdle.runtime import Recorder, RunResult, Scheduler

__all__: list[str] = []


class _Run(Recorder):
    """Records one run of the session: the scheduler, its events and samples."""

    def __init__(self, label: str, text: str) -> None:
        super().__init__()
        self.label = label
        self.text = text

    @property
    def scheduler(self) -> Scheduler | None:
        """The run's scheduler, once it has started."""
        return self.started

    @property
    def t0(self) -> float:
        """Simulated time of the run's first sample (or event), seconds."""
        if self.samples:
            return self.samples[0].time
        return self.events[0].time if self.events else 0.0



class _Element:
    def __init__(self, label: str) -> None:
        self.label = label


class _Recorded:
    """What a trace writer reads of a scheduler, for a run loaded from a recording."""

    def __init__(self, label: str, rate: float, backend: Any) -> None:
        self.element = _Element(label)
        self.rate = rate
        self.until = None
        self.backend = backend


def _write_runs(writer: Any, runs: Sequence[_Run]) -> int:
    """Write started runs to a trace writer: a ``start`` per run, one summing ``end``.

    Returns the number of samples written; the caller closes the writer.
    """
    for r in runs:
        assert r.scheduler is not None
        writer.on_start(r.scheduler)
        for e in r.events:
            writer.on_event(e)
        for s in r.samples:
            writer.on_tick(s)
    summary = _summary([r.result for r in runs if r.result is not None])
    if summary is not None:
        writer.on_end(summary)
    return sum(len(r.samples) for r in runs)


def _summary(results: Sequence[RunResult]) -> RunResult | None:
    """One result for several runs: the last run's termination, everything else summed."""
    if not results:
        return None
    last = results[-1]
    clear = [r.min_clearance for r in results if r.min_clearance is not None]
    return replace(
        last,
        terminations=tuple(t for r in results for t in r.terminations),
        events=tuple(e for r in results for e in r.events),
        ticks=sum(r.ticks for r in results),
        duration=sum(r.duration for r in results),
        distance=sum(r.distance for r in results),
        min_clearance=min(clear) if clear else None,
        collided=any(r.collided for r in results),
        fault=next((r.fault for r in reversed(results) if r.fault), None),
        max_lateness=max(r.max_lateness for r in results),
    )
