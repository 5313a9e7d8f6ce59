"""Hints a user can copy as they stand (issue 12.17).

They reuse the user's own text (a chained comparison, a call missing an argument) and
suggest only names that may stand where the unknown one is.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from mdle.atoms import default_registry
from mdle.core.errors import Diagnostic, MdleError
from mdle.lang import load_text
from mdle.lang.hints import chained_hint

MDLE = str(Path(sys.executable).parent / "mdle")
REPO = Path(__file__).resolve().parents[2]


def diagnostics(text: str) -> list[Diagnostic]:
    with pytest.raises(MdleError) as err:
        load_text(text, "t.mdle", default_registry())
    return list(err.value.diagnostics)


def hint_of(text: str) -> str | None:
    (d,) = diagnostics(text)
    return d.hint


@pytest.mark.parametrize(("text", "hint"), [
    ("atom b = (go(0.3 m/s), 0 m < x < 1 m, 1 s)\n", "write `0 m < x and x < 1 m`"),
    ("interrupt near = 0.2 m <= range(0 deg) < 2 m\n",
     "write `0.2 m <= range(0 deg) and range(0 deg) < 2 m`"),
    ("atom q = (go(1 m/s), stalled or (1 s < t < 2 s), 3 s)\n", "write `1 s < t and t < 2 s`"),
])
def test_a_chained_comparison_is_rewritten_with_the_users_numbers(text: str, hint: str) -> None:
    assert hint_of(text) == hint


def test_chained_hint_gives_up_rather_than_guess() -> None:
    assert chained_hint("x < 1 m", 3) is None  # no first comparison
    assert chained_hint("0 m < x < 1 m", 1) is None  # not at an operator


def test_a_missing_argument_keeps_the_arguments_given() -> None:
    assert hint_of("atom a = (arc(0.3 m/s), never, 1 s)\n") == \
        "write it as `arc(0.3 m/s, omega = ...)`"
    assert hint_of("atom a = (arc(v = 0.3 m/s), never, 1 s)\n") == \
        "write it as `arc(v = 0.3 m/s, omega = ...)`"


def test_a_control_law_is_suggested_only_where_one_can_stand() -> None:
    # an element of a string cannot be a control law: `go` is not offered
    d = diagnostics("atom a = (go(0.3 m/s), never, 1 s)\nbehavior c = ((g, a), never, inf)\n")
    assert d[0].message.startswith("unknown name `g`") and d[0].hint is None
    # at the head of an atom it can
    assert hint_of("atom d = (g(0.3 m/s), never, 1 s)\n") == "did you mean `go`?"
    # an atom is still found among the elements
    d = diagnostics("atom go_on = (go(0.3 m/s), never, 1 s)\nbehavior c = ((go_o), never, inf)\n")
    assert d[0].hint == "did you mean `go_on`?"


def test_conditions_and_values_are_offered_only_what_fits_there() -> None:
    # a condition: interrupts and sensor functions, not atoms
    d = diagnostics("atom cruise = (go(0.3 m/s), never, 1 s)\n"
                    "atom a = (go(0.3 m/s), cruse, 1 s)\n")
    assert d[0].hint is None
    d = diagnostics("interrupt near = range(0 deg) < 1 m\natom a = (go(0.3 m/s), nea, 1 s)\n")
    assert d[0].hint == "did you mean `near`?"
    # a fixed value: the definition's parameters, not sensor functions
    d = diagnostics("atom f(speed = 1 m/s) = (go(sped), never, 1 s)\n")
    assert d[0].hint == "did you mean `speed`?"
    d = diagnostics("atom f = (go(stalle), never, 1 s)\n")
    assert d[0].hint is None


@pytest.mark.parametrize(("command", "hint"), [
    ("run", "hint: to run a plan in this world: `mdle run PLAN.mdle --world w.world.yaml`"),
])  # (`mdle check` reads a .yaml as a team file)
def test_a_world_file_given_as_a_plan_says_how_to_give_it(tmp_path: Path, command: str,
                                                          hint: str) -> None:
    (tmp_path / "w.world.yaml").write_text("name: w\nstart: {x: 0, y: 0, theta: 0}\n")
    r = subprocess.run([MDLE, command, "w.world.yaml"], capture_output=True, text=True,
                       timeout=60, cwd=tmp_path)
    out = r.stdout + r.stderr
    assert r.returncode == 1
    assert "error: `w.world.yaml` is a YAML file (a world file?), not an MDLe plan" in out
    assert hint in out and "Traceback" not in out
