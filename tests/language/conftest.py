"""Fixtures of the language tests: a small registry, a context factory, plan files."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from mdle.atoms.registry import BOOL, Args, Context, Param, Registry, control_law, sensor
from mdle.core.backend import Command, Observation, RobotLimits
from mdle.core.pose import Pose
from mdle.core.units import ANGLE, LENGTH, SPEED, TIME, TURN_RATE
from mdle.lang.check_state import CheckerState

REPO = Path(__file__).resolve().parents[2]
PLANS = sorted((REPO / "plans").rglob("*.mdle"))


@control_law(Param("v", SPEED, doc="speed"))
def drive(args: Args, ctx: Context, state: object) -> Command:
    """Drive straight."""
    return Command(float(args["v"]), 0.0)


@control_law(Param("side", choices=("right", "left"), default="right"),
             Param("v", SPEED, 0.3), Param("rc", LENGTH, 0.5))
def hug(args: Args, ctx: Context, state: object) -> Command:
    """Follow a wall on one side."""
    return Command(float(args["v"]), 0.0)


@control_law(Param("rate", TURN_RATE))
def spin(args: Args, ctx: Context, state: object) -> Command:
    """Turn on the spot."""
    return Command(0.0, float(args["rate"]))


@sensor(Param("angle", ANGLE), result=LENGTH)
def beam(args: Args, ctx: Context) -> float:
    """Range along a bearing: here 10 m minus x, so tests can steer it."""
    return 10.0 - ctx.obs.pose.x


@sensor(result=LENGTH)
def px(args: Args, ctx: Context) -> float:
    """Odometry x."""
    return ctx.obs.pose.x


@sensor(result=TIME)
def clock(args: Args, ctx: Context) -> float:
    """Local time."""
    return ctx.t


@sensor(result=BOOL)
def bumped(args: Args, ctx: Context) -> bool:
    """Stall flag."""
    return ctx.obs.stalled


@sensor(Param("side", choices=("right", "left")), result=LENGTH)
def gap(args: Args, ctx: Context) -> float:
    """1 m on the right, 2 m on the left."""
    return 1.0 if args["side"] == "right" else 2.0


def small_registry() -> Registry:
    """A registry of test laws and sensor functions (not the shipped ones)."""
    import types

    return Registry.from_modules(types.SimpleNamespace(
        drive=drive, hug=hug, spin=spin, beam=beam, px=px, clock=clock, bumped=bumped, gap=gap))


def _make_ctx(x: float = 0.0, t: float = 0.0, stalled: bool = False) -> Context:
    obs = Observation(time=t, pose=Pose(x, 0.0, 0.0), stalled=stalled)
    return Context(obs, t, 0.1, RobotLimits(1.0, 1.0, 3.0))


@pytest.fixture
def reg() -> Registry:
    """The small test registry: drive(v), hug(side, v, rc), spin(rate); beam(angle), px,
    clock, bumped, gap(side)."""
    return small_registry()


@pytest.fixture
def make_ctx() -> Callable[..., Context]:
    """``make_ctx(x=0, t=0, stalled=False)``: a Context for evaluating compiled interrupts."""
    return _make_ctx


@pytest.fixture
def plans_dir() -> Path:
    """The repository's plans/ folder."""
    return REPO / "plans"


def count_instances(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Count the instances of definitions the checker makes (each passes the budget once)."""
    made = [0]
    expand = CheckerState._expand

    def counted(self: CheckerState, d: Any, call: Any) -> None:
        made[0] += 1
        expand(self, d, call)

    monkeypatch.setattr(CheckerState, "_expand", counted)
    return made
