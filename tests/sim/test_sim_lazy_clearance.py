"""The simulator measures the exact clearance only when someone needs it.

A step that touched nothing leaves a lower bound; an observation's truth is then a
LazyTruth that measures on first read, and the scheduler reads it only when the bound
could make a new least clearance. Every reader sees what an eager dict would hold.
"""

from __future__ import annotations

import math
import pickle

import pytest

from mdle.core.backend import Command, LazyTruth, clearance_floor
from mdle.core.pose import Pose
from mdle.lang import load_text
from mdle.runtime import Scheduler
from mdle.sim.backend import SimBackend
from mdle.sim.collision import Clearance, Collider
from mdle.sim.shapes import Rectangle, Wall
from mdle.sim.world import World


def _room() -> World:
    return World("room", obstacles=(
        Wall(((-4, -4), (4, -4), (4, 4), (-4, 4)), 0.2, True),
        Rectangle((1.5, 0.5), (0.6, 0.4), 0.3), Rectangle((-1.5, -1.0), (0.5, 0.8), 1.0)))


class _Counting(Collider):
    """A collider that counts its exact clearance queries."""

    queries = 0

    def clearance(self, x: float, y: float) -> Clearance:
        type(self).queries += 1
        return super().clearance(x, y)


def _drive(b: SimBackend, k: int) -> None:
    b.command(Command(0.3, 0.4 + 0.2 * math.sin(0.1 * k)))
    b.advance(0.1)


def test_truth_reads_as_the_exact_clearance_however_it_is_read() -> None:
    b = SimBackend(_room(), seed=2)
    exact = Collider(b.world.parts, b.profile.radius)
    lazy_seen = 0
    for k in range(60):
        _drive(b, k)
        truth = b.observe().truth
        want = exact.clearance(b.true_pose.x, b.true_pose.y)[0]
        if isinstance(truth, LazyTruth):
            lazy_seen += 1
            assert clearance_floor(truth) <= want
            assert "clearance" in truth and len(truth) == 5
            read = [truth["clearance"], truth.get("clearance"), dict(truth)["clearance"]]
            assert read == [want] * 3
            assert set(truth) == {"x", "y", "theta", "clearance", "collided"}
            copy = pickle.loads(pickle.dumps(truth))
            assert type(copy) is dict and copy == truth and copy["clearance"] == want
        else:
            assert truth["clearance"] == want
    assert lazy_seen > 50


def test_unread_clearances_are_not_measured(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(SimBackend, "_make_collider",
                        lambda self: _Counting(self.world.parts, self.profile.radius))
    b = SimBackend(_room(), seed=2)
    _Counting.queries = 0
    for k in range(100):
        b.observe()
        _drive(b, k)
    unread = _Counting.queries
    # the steps measure only when their bound no longer covers the next step
    assert unread < 30
    _Counting.queries = 0
    for k in range(100):
        b.observe().truth["clearance"]
        _drive(b, k)
    assert _Counting.queries == 100


def test_a_measured_clearance_starts_the_next_step_exactly() -> None:
    b = SimBackend(_room(), seed=2)
    _drive(b, 0)
    truth = b.observe().truth
    assert isinstance(truth, LazyTruth) and b._clear_bound
    value = truth["clearance"]
    assert not b._clear_bound and b._clear[0] == value
    # measured after the robot moved on: the value of where it was, the state untouched
    _drive(b, 1)
    late = b.observe().truth
    _drive(b, 2)
    kept = b._clear
    exact = Collider(b.world.parts, b.profile.radius)
    assert isinstance(late, LazyTruth)
    assert late["clearance"] == exact.clearance(late["x"], late["y"])[0]
    assert b._clear == kept
    # read after a reset elsewhere and a step to the same time: the state is not touched
    b.reset()
    _drive(b, 0)
    old = b.observe().truth
    b.reset(Pose(-3.0, 3.0, 0.0))
    _drive(b, 0)
    kept = b._clear
    assert isinstance(old, LazyTruth) and b._clear_bound
    assert old["clearance"] == exact.clearance(old["x"], old["y"])[0] != kept[0]
    assert b._clear == kept and b._clear_bound


def _least(observers: list, ticks: int = 150) -> tuple[float | None, int]:
    """Run a plan driving circles; return the run's least clearance and the queries made."""
    b = SimBackend(_room(), seed=5)
    _Counting.queries = 0
    prog = load_text("atom loop = (arc(v = 0.3 m/s, omega = 0.5 rad/s), never, inf)\n"
                     "plan main = ((loop), never, inf)\n")
    sch = Scheduler(prog.elements["main"], b, 10.0, observers, stall_timeout=None)
    for _ in range(ticks):
        sch.tick()
    return sch._min_clearance, _Counting.queries


class _ReadsTruth:
    """An observer that reads every tick's clearance, as a trace writer does."""

    def on_start(self, scheduler: object) -> None:
        """Start a run."""

    def on_event(self, event: object) -> None:
        """Take an event."""

    def on_tick(self, sample: object) -> None:
        """Take a sample (its clearance is read by the scheduler to build it)."""

    def on_end(self, result: object) -> None:
        """End a run."""


def test_the_runs_least_clearance_is_the_same_read_or_not(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(SimBackend, "_make_collider",
                        lambda self: _Counting(self.world.parts, self.profile.radius))
    least, queries = _least([])
    traced, traced_queries = _least([_ReadsTruth()])
    assert least is not None and least == traced
    assert traced_queries >= 149 and queries < traced_queries / 3, (queries, traced_queries)
