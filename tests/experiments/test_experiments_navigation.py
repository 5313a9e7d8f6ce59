"""The navigation library (plans/nav) reaches its goals; the navigation experiment's worlds."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from mdle import sim
from mdle.cli import main
from mdle.experiments.navigation import GAP, generate_world, run_navigation
from mdle.lang import load_program
from mdle.runtime import Cause, EventKind, Recorder, run_named
from mdle.sim.world_yaml import parse_world, read_world

NAV = Path(__file__).resolve().parents[2] / "plans" / "nav"
PLANS = sorted(NAV.glob("*.mdle"))


def _run(plan: Path, until: float) -> tuple[object, object]:
    program = load_program(plan)
    assert not program.warnings, program.warnings
    world = read_world(plan.with_suffix(".world.yaml"))
    backend = sim.SimBackend(world, seed=1)
    try:
        return program, run_named(program, None, backend, rate=10, until=until)
    finally:
        backend.close()


def test_the_library_has_its_plans_each_with_a_world() -> None:
    assert {p.stem for p in PLANS} == {"bug1", "bug2", "leave-clear", "patrol"}
    assert all(p.with_suffix(".world.yaml").is_file() for p in PLANS)


@pytest.mark.parametrize("name, goal", [("bug1", (10.0, 0.0)), ("bug2", (10.0, 0.0)),
                                        ("leave-clear", (9.0, 1.0))])
def test_each_goal_seeking_plan_reaches_its_goal_in_its_world(name: str,
                                                              goal: tuple[float, float]) -> None:
    _, result = _run(NAV / f"{name}.mdle", until=300.0)
    assert not result.collided  # type: ignore[attr-defined]
    goal_end = [t for t in result.terminations  # type: ignore[attr-defined]
                if t.level == 1 and t.cause is Cause.INTERRUPT]
    assert goal_end, result.termination  # type: ignore[attr-defined]
    end = result.events[-1].pose  # type: ignore[attr-defined]
    assert math.hypot(end.x - goal[0], end.y - goal[1]) < 0.35


def test_bug1_goes_round_each_obstacle_and_leaves_at_its_point_nearest_the_goal() -> None:
    program = load_program(NAV / "bug1.mdle")
    backend = sim.SimBackend(read_world(NAV / "bug1.world.yaml"), seed=1)
    recorder = Recorder()
    try:
        result = run_named(program, None, backend, rate=10, until=300.0, observers=[recorder])
    finally:
        backend.close()
    assert not result.collided
    starts = [e for e in result.events if e.path.startswith("main/bug1/hug")
              and e.kind is EventKind.START]
    ends = [t for t in result.terminations if t.path.startswith("main/bug1/hug")]
    assert len(starts) == len(ends) == 2  # one per obstacle of the world
    assert all(t.cause is Cause.INTERRUPT for t in ends)
    for start, end in zip(starts, ends, strict=True):
        path = [(s.x, s.y) for s in recorder.samples if start.time <= s.time <= end.time]
        goal = [math.hypot(10.0 - x, y) for x, y in path]
        hit = (start.pose.x, start.pose.y)
        away = [math.hypot(x - hit[0], y - hit[1]) for x, y in path]
        back = next(i for i, d in enumerate(away) if d < 0.6 and max(away[:i + 1]) > 1.5)
        # it came back to the hit point, then left within 0.1 m of the least distance
        # to the goal of the whole turn, and nowhere nearer the goal than that
        assert back < len(path) - 1
        assert goal[-1] < min(goal[:back + 1]) + 0.1
        assert min(goal[:back + 1]) < goal[0] - 1.0


def test_the_patrol_reaches_every_waypoint_in_turn() -> None:
    _, result = _run(NAV / "patrol.mdle", until=240.0)
    assert not result.collided  # type: ignore[attr-defined]
    legs = [t for t in result.terminations  # type: ignore[attr-defined]
            if re.fullmatch(r"main/leg(#\d)?", t.path) and t.cause is not Cause.STOPPED]
    # each leg ends by reaching its waypoint (its interrupt), never by its 5 min timer
    assert len(legs) >= 4 and all(t.cause is Cause.INTERRUPT for t in legs)


def test_worlds_are_seeded_cluttered_and_leave_the_way_open() -> None:
    for seed in range(40):
        text, (gx, gy) = generate_world(seed)
        assert text == generate_world(seed)[0]
        world = parse_world(text)
        assert 3 <= len(world.obstacles) <= 8
        assert 8.0 <= math.hypot(gx, gy) <= 11.5
        assert world.clearance((0.0, 0.0), 0.0) > 1.0
        assert world.clearance((gx, gy), 0.0) > 0.9
    assert GAP > 1.0  # room for a 0.5 m wide robot between any two


def test_a_run_reports_reached_path_and_time() -> None:
    run = run_navigation(3, "ideal", NAV / "bug2.mdle")
    assert run.reached and not run.collided and run.obstacles >= 3
    assert 0.9 < run.path / run.straight < 2.0 and 20.0 < run.time < 120.0


def test_the_experiment_from_the_command_line(capsys: pytest.CaptureFixture[str],
                                              tmp_path: Path) -> None:
    csv = tmp_path / "runs.csv"
    assert main(["experiment", "navigation", "--runs", "2", "--robot", "ideal",
                 "--nav-plan", str(NAV / "bug2.mdle"), "--csv", str(csv)]) == 0
    out = capsys.readouterr().out
    assert "navigation: bug2.mdle over 2 seeded cluttered worlds" in out
    assert re.search(r"ideal\s*│\s*2\s*│\s*100\.0\s*│\s*0", out)
    assert csv.read_text().splitlines()[0].startswith("seed,robot,obstacles,reached")
    assert main(["experiment", "navigation", "--nav-plan", str(tmp_path / "no.mdle")]) == 1
    assert "no.mdle: no such file" in capsys.readouterr().err
