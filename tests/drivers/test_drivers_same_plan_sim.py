"""Issue 11: one odometry frame everywhere: a plan using x, y and theta runs the same in
the simulator (started anywhere in its world) and on the Pioneer (the fake ARCOS server)."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from mdle.core.pose import Pose
from mdle.drivers import open_backend
from mdle.drivers.pioneer import PioneerOptions
from mdle.lang import load_text
from mdle.runtime import element_of, run
from mdle.runtime.events import RunResult
from mdle.sim import SimBackend, load_world

if TYPE_CHECKING:
    from tests.drivers.conftest import FakeArcos

    FakeRobot = Callable[..., FakeArcos]

PLAN = """\
atom out = (go(0.3 m/s), x > 0.3 m, 4 s)
atom left = (turn(60 deg/s), theta > 60 deg, 3 s)
atom up = (go(0.3 m/s), y > 0.15 m or dist_to(0 m, 0 m) > 0.6 m, 4 s)
plan main = ((out, left, up), never, 12 s)
run main
"""


def _sequence(result: RunResult) -> list[tuple[str, str]]:
    return [(t.path, t.cause.value) for t in result.terminations]


def test_same_plan_same_elements_in_simulation_and_on_the_pioneer(
        fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    program = load_text(PLAN)
    # In the simulator the robot starts far from the world's origin, turned: the plan's
    # x, y and theta are odometry from there, so the world's coordinates do not matter.
    sim = SimBackend(load_world("empty"), robot="ideal")
    sim.reset(Pose(-4.0, 3.0, 2.5))   # world x < 0.3 m and theta > 60 deg from the start
    simulated = run(element_of(program), sim, rate=10.0)
    assert sim.true_pose.x < -4.0  # it drove towards the world's -x
    fake = fake_robot()
    backend = open_backend("pioneer", fake.url, "sim", options=fast)
    try:
        real = run(element_of(program), backend, rate=10.0)
    finally:
        backend.close()
    expected = [("main/out", "interrupt"), ("main/left", "interrupt"), ("main/up", "interrupt"),
                ("main", "completed")]
    assert _sequence(simulated) == expected, _sequence(simulated)
    assert _sequence(real) == expected, _sequence(real)
