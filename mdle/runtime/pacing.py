"""Pacing a simulated run to the wall clock (``--realtime``).

This is the only module of :mod:`mdle.runtime` that reads the wall clock: the scheduler's
logic runs on the backend's observation time, and a simulated backend advances as fast
as the CPU allows unless a :class:`Pacer` holds each tick back to its wall-clock
deadline. Hardware backends pace themselves in ``advance``.
"""

from __future__ import annotations

import time
from collections.abc import Callable

__all__ = ["Pacer"]


class Pacer:
    """Hold a simulated run to wall-clock speed.

    ``wait(elapsed)`` sleeps until ``elapsed`` seconds of wall time have passed since the
    first call, and returns how late that deadline already was (seconds, >= 0).
    ``clock`` and ``sleep`` are injectable for tests.
    """

    def __init__(self, clock: Callable[[], float] = time.monotonic,
                 sleep: Callable[[float], None] = time.sleep) -> None:
        self._clock = clock
        self._sleep = sleep
        self._origin: float | None = None

    def wait(self, elapsed: float) -> float:
        """Sleep until ``elapsed`` s after the first call; return the lateness (s)."""
        now = self._clock()
        if self._origin is None:
            self._origin = now
        ahead = self._origin + elapsed - now
        if ahead > 0.0:
            self._sleep(ahead)
            return 0.0
        return -ahead
