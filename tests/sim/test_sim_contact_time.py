"""A collision is reported at the time of first contact along the step, at any rate.

At ``--rate 0.05`` (20 s ticks) a run into the default room's box reported t = 1.0 s,
the start of the piece of motion that touched it, while the robot needs 16.3 s to reach
the box; at 10 Hz the time was up to a tick late.
"""

from __future__ import annotations

import pytest

from mdle import sim
from mdle.lang import load_text
from mdle.runtime import run_named

PLAN = "atom a = (go(0.3 m/s), never, 60 s)\nrun a\n"


def _contact(rate: float) -> sim.SimEvent:
    backend = sim.SimBackend(sim.load_world("default"), seed=0)
    result = run_named(load_text(PLAN), "a", backend, rate=rate)
    assert result.collided
    (event,) = [e for e in backend.events if e.kind == "collision"]
    return event


@pytest.mark.parametrize("rate", [50.0, 10.0, 1.0, 0.3, 0.05])
def test_the_contact_time_does_not_depend_on_the_rate(rate: float) -> None:
    reference = _contact(100.0)
    event = _contact(rate)
    assert event.time == pytest.approx(reference.time, abs=1e-9)
    assert (event.x, event.y) == pytest.approx((reference.x, reference.y), abs=1e-9)


def test_the_contact_time_is_when_the_motion_reaches_the_contact_pose() -> None:
    # The Pioneer 2-DX ramps to 0.3 m/s at 0.3 m/s^2 (1 s, 0.15 m), then drives on
    # straight: its centre is 0.3 * (t - 0.5) m from the start at time t.
    world = sim.load_world("default")
    backend = sim.SimBackend(world, seed=0)
    assert backend.profile.max_accel == 0.3 and world.start_pose.theta == 0.0
    event = _contact(0.05)
    start = world.start_pose
    assert event.y == pytest.approx(start.y, abs=1e-9)
    assert event.x - start.x == pytest.approx(0.3 * (event.time - 0.5), abs=1e-6)
    assert event.time == pytest.approx(16.333, abs=1e-3)
