"""Constant speeds and turn rates are compared with the robot the plan runs on (issue 12.15).

A command beyond the robot's limits is clamped by the robot, so the plan does not move as
written: `go(3 m/s)` on a 2.2 m/s Pioneer. The checker warns, at the argument, naming the
limit and the robot.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest

from mdle.atoms import default_registry
from mdle.core.errors import Diagnostic
from mdle.core.motion_limits import KnownRobot
from mdle.lang import load_text

PIONEER = KnownRobot("pioneer2dx", 2.2, 2.2, math.radians(500), "the default robot")


def place(d: Diagnostic) -> tuple[int, int, int]:
    assert d.span is not None
    return d.span.line, d.span.column, d.span.end_column


def warnings(text: str, robot: KnownRobot | None = PIONEER) -> list[Diagnostic]:
    return list(load_text(text, "t.mdle", default_registry(), robot=robot).warnings)


def test_speed_beyond_the_top_speed_is_a_located_warning_naming_robot_and_limit() -> None:
    (w,) = warnings("atom dash = (go(3 m/s), never, 5 s)\nrun dash\n")
    assert place(w) == (1, 17, 22)
    assert w.message == ("`v` of `go` is 3 m/s, more than the robot can do: the top speed of "
                         "`pioneer2dx` (the default robot) is 2.2 m/s")


def test_turn_rate_and_reverse_speed_are_compared_too() -> None:
    ws = warnings("atom a = (arc(1 m/s, -600 deg/s), never, 1 s)\n"
                  "atom b = (go(-2.5 m/s), never, 1 s)\natom c = (turn(400 deg/s), never, 1 s)\n")
    assert [w.message.split(": ", 1)[1] for w in ws] == [
        "the largest turn rate of `pioneer2dx` (the default robot) is 500 deg/s",
        "the top reverse speed of `pioneer2dx` (the default robot) is 2.2 m/s"]
    assert ws[0].message.startswith("`omega` of `arc` is -600 deg/s")


@pytest.mark.parametrize("text", [
    "atom a = (go(2.2 m/s), never, 1 s)",
    "atom a = (follow_boundary(v = 1 m/s, umax = 50 rad/s), never, 1 s)",  # umax is a ceiling
    "atom a = (heading(90 deg, rate = 50 rad/s), never, 1 s)",
    "behavior b = (((0.5, 1, (go(3 m/s), never, 1 s))), never, inf)",      # scaled to 1.5 m/s
])
def test_values_the_robot_can_do_or_caps_the_law_keeps_are_quiet(text: str) -> None:
    assert warnings(text + "\n") == []


def test_no_robot_no_comparison() -> None:
    assert warnings("atom dash = (go(30 m/s), never, 5 s)\n", robot=None) == []


def test_a_scaled_atom_is_compared_once_scaled() -> None:
    (w,) = warnings("behavior b = (((2, 1, (go(2 m/s), never, 1 s))), never, inf)\n")
    assert w.message.startswith("`v` of `go` is 4 m/s (scaled by 2), more than")
    assert place(w)[:2] == (1, 16)  # the scaled atom


def test_a_parameter_fixed_by_a_use_points_at_the_body_and_the_use() -> None:
    (w,) = warnings("atom f(v = 1 m/s) = (go(v), never, 1 s)\n"
                    "behavior b = ((f(1 m/s), f(2.5 m/s)), never, inf)\n")
    assert w.message.startswith("`v` of `go` is 2.5 m/s")
    assert place(w)[:2] == (1, 25)
    (note,) = w.notes
    assert note.message == "in this use of `f`" and place(note)[:2] == (2, 26)


def test_the_robot_is_named_by_how_it_was_chosen() -> None:
    ideal = KnownRobot("ideal", 1.0, 1.0, 3.0, "--robot")
    (w,) = warnings("atom a = (go(1.5 m/s), never, 1 s)\n", robot=ideal)
    assert w.message.endswith("the top speed of `ideal` (--robot) is 1 m/s")


def test_check_reads_each_world_once_across_plans(tmp_path: Path,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    import mdle.sim.catalog as catalog
    from mdle.cli.options import known_robot

    reads: list[str] = []
    real = catalog.world_robot

    def counting(spec: Any) -> Any:
        reads.append(str(spec))
        return real(spec)

    monkeypatch.setattr(catalog, "world_robot", counting)
    (tmp_path / "b.world.yaml").write_text("robot: ideal\n")
    memo: dict[tuple[str, ...], KnownRobot] = {}
    found = [known_robot(tmp_path / name, memo=memo) for name in ("a.mdle", "c.mdle", "b.mdle",
                                                                   "b.mdle")]
    assert [r.name for r in found] == ["pioneer2dx", "pioneer2dx", "ideal", "ideal"]
    assert reads == ["default", str(tmp_path / "b.world.yaml")]
    assert known_robot(tmp_path / "b.mdle", robot="pioneer2dx").how == "--robot"
