"""The language says exactly what it means: one message per mistake, never-true comparisons,
xor as parity (issue 25)."""

from __future__ import annotations

import math

import pytest

from mdle.atoms.registry import Context
from mdle.core.backend import Observation, RobotLimits
from mdle.core.errors import CheckError, Diagnostic
from mdle.core.motion_limits import KnownRobot
from mdle.core.pose import Pose
from mdle.lang import load_text

PIONEER = KnownRobot("pioneer2dx", 2.2, 2.2, math.radians(500), "the default robot")


def errors(text: str) -> list[Diagnostic]:
    with pytest.raises(CheckError) as err:
        load_text(text, "t.mdle")
    return list(err.value.diagnostics)


def warnings(text: str) -> list[str]:
    return [w.message for w in load_text(text, "t.mdle", robot=PIONEER).warnings]


def test_a_positional_after_a_keyword_is_one_error_with_a_hint_that_checks() -> None:
    (e,) = errors("atom a = (arc(v = 0.2 m/s, 10 deg/s), never, 1 s)\nrun a\n")
    assert e.message == "a positional argument cannot follow a keyword argument"
    assert e.hint == "name it: `arc(v = 0.2 m/s, omega = 10 deg/s)`"
    # the hint, copied as it stands, checks clean
    load_text("atom a = (arc(v = 0.2 m/s, omega = 10 deg/s), never, 1 s)\nrun a\n")


def test_a_refused_definition_name_is_not_reported_again_at_its_uses() -> None:
    found = errors("atom go = (stop, never, 1 s)\ninterrupt x = t > 1 s\n"
                   "plan main = ((go, (stop, x, 2 s)), never, 2 s)\n")
    assert [e.message for e in found] == [
        "`go` is already a control law; a definition cannot take its name",
        "`x` is already a sensor function; a definition cannot take its name"]


def test_no_speed_warning_for_an_atom_used_only_scaled_down() -> None:
    assert warnings("atom fast = (go(3 m/s), never, 1 s)\n"
                    "plan main = (((0.5, 1, fast)), never, 2 s)\n") == []
    # used as it stands too: the warning is right
    (w,) = warnings("atom fast = (go(3 m/s), never, 1 s)\n"
                    "plan main = (((0.5, 1, fast), fast), never, 2 s)\n")
    assert w.startswith("`v` of `go` is 3 m/s, more than the robot can do")
    # scaled up past the limit: the scaled use is warned about, once
    (w,) = warnings("atom quick = (go(2 m/s), never, 1 s)\n"
                    "plan main = (((1.5, 1, quick)), never, 2 s)\n")
    assert "(scaled by 1.5)" in w
    # run as it stands (the entry), though used scaled elsewhere: warned
    assert warnings("atom fast = (go(3 m/s), never, 1 s)\n"
                    "plan other = (((0.5, 1, fast)), never, 2 s)\nrun fast\n")


@pytest.mark.parametrize("condition, holds", [
    ("theta > 200 deg", False), ("180 deg < theta", False), ("theta < -181 deg", False),
    ("theta > 179 deg", True), ("theta >= 180 deg", True), ("theta == 180 deg", True),
    ("range(0 deg) < 0 m", False), ("range(0 deg) <= 0 m", True),
    ("dist_to(1 m, 1 m) < -1 m", False), ("x > 200 m", True),
])
def test_a_comparison_that_can_never_hold_is_warned_about(condition: str, holds: bool) -> None:
    found = warnings(f"atom a = (turn(30 deg/s), {condition}, 1 s)\nrun a\n")
    never = [w for w in found if "can never hold" in w]
    assert bool(never) is not holds
    if never:
        assert never[0].startswith(f"`{condition}` can never hold: `")


def _ctx() -> Context:
    return Context(Observation(0.0, Pose()), 0.0, 0.1, RobotLimits(1.0, 1.0, 1.0))


@pytest.mark.parametrize("a, b, c, expect", [
    (True, False, False, True), (True, True, False, False), (True, True, True, True),
    (False, False, False, False),
])
def test_xor_chains_are_parity(a: bool, b: bool, c: bool, expect: bool) -> None:
    def word(v: bool) -> str:
        return "t >= 0 s" if v else "t < 0 s"

    program = load_text(f"atom a = (stop, {word(a)} xor {word(b)} xor {word(c)}, 1 s)\nrun a\n")
    interrupt = program.elements["a"].interrupt
    assert interrupt.test(_ctx()) is expect
