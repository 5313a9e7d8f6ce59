"""``--robot PROFILE`` on a Pioneer: the law's lag prediction comes from the profile, and
without one from the ARCOS server loop (issue 24: the backend reported 0 latency, so the
shipped corridor plan ran its law without lag prediction on hardware)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import pytest

from mdle.cli import build_parser
from mdle.cli import repl as repl_cli
from mdle.cli import run as run_cli
from mdle.drivers import open_backend
from mdle.drivers.pioneer import SERVER_LOOP_LATENCY, PioneerBackend, PioneerOptions
from mdle.sim.profiles import robot_profile

if TYPE_CHECKING:
    from tests.drivers.conftest import FakeArcos

    FakeRobot = Callable[..., FakeArcos]


def test_without_a_profile_the_law_predicts_over_the_server_loop(
        fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    backend = open_backend("pioneer", fake_robot().url, options=fast)
    try:
        assert backend.limits.command_latency == SERVER_LOOP_LATENCY == 0.15
    finally:
        backend.close()


@pytest.mark.parametrize("command", ["run", "repl"])
def test_the_robot_profile_gives_the_law_its_latency(fake_robot: FakeRobot,
                                                     command: str) -> None:
    fake = fake_robot()
    argv = [command, "--backend", "pioneer", "--connect", fake.url, "--laser", "sim",
            "--robot", "pioneer-p3dx"]
    args = build_parser().parse_args([*argv, "plan.mdle"] if command == "run" else argv)
    if command == "run":
        args.rate = 10.0  # `mdle run` settles the rate (plan, team file or default) first
        backend, world = run_cli._open_backend(args, {})
        assert world is None
    else:
        session = repl_cli._robot_session(args, until=None)
        backend = session.hardware
    try:
        assert isinstance(backend, PioneerBackend)
        profile = robot_profile("pioneer-p3dx")
        # what the simulator's laws see with this profile: the server loop's mean delay
        assert math.isclose(backend.limits.command_latency,
                            profile.command_latency + 1.5 * profile.control_cycle)
        assert backend.limits.command_latency > 0.15
        assert backend.limits.command_latency == profile.limits.command_latency
        assert backend.limits.scan_latency == profile.limits.scan_latency > 0.0
        # the speed limits stay the robot's own (a P3-DX's working limits), not the profile's
        assert backend.limits.max_speed == 0.75
        assert backend.laser_mount == (0.017, 0.008, 0.0)
    finally:
        backend.close()
