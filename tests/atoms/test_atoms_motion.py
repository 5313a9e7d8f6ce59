"""goto and heading in closed loop on an ideal unicycle; registry hygiene of the atoms modules."""

from __future__ import annotations

import math
import subprocess
import sys

import pytest

from mdle.atoms import default_registry
from mdle.atoms.registry import Context
from mdle.core.backend import Observation, RobotLimits
from mdle.core.pose import Pose

LIMITS = RobotLimits(1.0, 1.0, 2.0)


def _drive(law: str, args: dict[str, float], pose: tuple[float, float, float],
           steps: int = 1500, dt: float = 0.02) -> tuple[float, float, float]:
    fn = default_registry().laws[law].step
    x, y, th = pose
    for i in range(steps):
        cmd = fn(args, Context(Observation(i * dt, Pose(x, y, th)), i * dt, dt, LIMITS), None)
        v, w = min(cmd.v, LIMITS.max_speed), max(-2.0, min(2.0, cmd.omega))
        x += v * dt * math.cos(th + w * dt / 2)
        y += v * dt * math.sin(th + w * dt / 2)
        th = math.atan2(math.sin(th + w * dt), math.cos(th + w * dt))
    return x, y, th


@pytest.mark.parametrize("start", [(0.0, 0.0, 0.0), (0.0, 0.0, math.pi), (3.0, -2.0, 1.0)])
def test_goto_reaches_the_goal_and_stops(start: tuple[float, float, float]) -> None:
    x, y, _ = _drive("goto", {"x": 2.0, "y": 1.0, "v": 0.5, "tol": 0.05}, start)
    assert math.hypot(x - 2.0, y - 1.0) <= 0.06


def test_goto_never_drives_backwards_or_faster_than_asked() -> None:
    fn = default_registry().laws["goto"].step
    ctx = Context(Observation(0.0, Pose(0.0, 0.0, math.pi)), 0.0, 0.1, LIMITS)
    cmd = fn({"x": 5.0, "y": 0.0, "v": 0.4, "tol": 0.05}, ctx, None)
    assert cmd.v == pytest.approx(0.0, abs=1e-12) and abs(cmd.omega) == pytest.approx(2.0)
    ctx = Context(Observation(0.0, Pose(0.0, 0.0, 0.0)), 0.0, 0.1, LIMITS)
    cmd = fn({"x": 5.0, "y": 0.0, "v": 0.4, "tol": 0.05}, ctx, None)
    assert cmd.v == pytest.approx(0.4) and cmd.omega == pytest.approx(0.0)


@pytest.mark.parametrize("target", [0.0, 1.0, -2.5, math.pi])
def test_heading_turns_on_the_spot_the_short_way(target: float) -> None:
    x, y, th = _drive("heading", {"theta": target, "rate": 1.0}, (0.0, 0.0, 0.5), steps=500)
    assert (x, y) == (0.0, 0.0)
    assert abs(math.atan2(math.sin(th - target), math.cos(th - target))) < 1e-3


def test_registry_lists_the_atoms_laws_and_sensors() -> None:
    reg = default_registry()
    assert {"follow_boundary", "goto", "heading"} <= set(reg.laws)
    assert {"boundary_range", "boundary_curvature", "boundary_tangent"} <= set(reg.sensors)
    side = reg.laws["follow_boundary"].param("side")
    assert side is not None and side.choices == ("right", "left") and side.default == "right"


def test_declaring_modules_do_not_import_numpy() -> None:
    code = ("import sys, atoms; atoms.default_registry(); "
            "print('numpy' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
