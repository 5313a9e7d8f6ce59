"""Time is counted in whole ticks: no drift, timers exact to the tick at any length."""

from __future__ import annotations

from mdle import sim
from mdle.core.backend import TickClock
from mdle.lang import load_text
from mdle.runtime import Cause, run_named
from mdle.runtime.scripted import ScriptedBackend


def test_the_clock_is_tick_count_times_dt() -> None:
    clock = TickClock()
    for _ in range(36_000):
        clock.advance(0.1)
    assert clock.now == 3600.0            # a float sum would give 3600.0999999978
    clock.advance(0.05)                   # a new dt counts on from the time reached
    assert clock.now == 3600.05 and clock.ticks == 1


def test_an_hour_long_timer_ends_at_exactly_3600_s_at_10_hz() -> None:
    program = load_text("atom wait = (stop, never, 60 min)\nrun wait\n")
    backend = sim.SimBackend(sim.load_world("default"), seed=1)
    result = run_named(program, None, backend, rate=10)
    assert result.termination.cause is Cause.TIMER
    assert result.termination.time == 3600.0
    assert result.ticks == 36_001       # ticks 0..36000: the timer fires at tick 36000


def test_a_long_timer_at_100_hz_fires_at_its_own_tick() -> None:
    # at 100 Hz the summed clock was a tick late from 1260 s on
    program = load_text("atom wait = (stop, never, 1300 s)\nrun wait\n")
    backend = ScriptedBackend()
    result = run_named(program, None, backend, rate=100)
    assert result.termination.time == 1300.0 and result.ticks == 130_001
