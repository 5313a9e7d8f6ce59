"""The REPL's robot session in-process on the fake ARCOS server: confirmation before the
first motion, stepping leaves the robot stopped, simulator-only commands refuse, the
session trace names the robot, the prompt asks before moving."""

from __future__ import annotations

import io
import json
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from prompt_toolkit.input import create_pipe_input
from prompt_toolkit.output import DummyOutput

from mdle.drivers import open_backend
from mdle.drivers.arcos import Cmd
from mdle.drivers.pioneer import PioneerBackend, PioneerOptions
from mdle.repl.commands import Repl
from mdle.repl.prompt import run_prompt
from mdle.repl.robot import RobotSession

if TYPE_CHECKING:
    from tests.drivers.conftest import FakeArcos

    FakeRobot = Callable[..., FakeArcos]

ATOM = "atom a = (go(0.2 m/s), never, 0.3 s)"


@pytest.fixture
def robot(fake_robot: FakeRobot, fast: PioneerOptions
          ) -> Iterator[tuple[FakeArcos, Callable[..., Repl]]]:
    """A fake robot and a factory of REPLs driving it (closed afterwards)."""
    fake = fake_robot()
    made: list[RobotSession] = []

    def make(*, armed: bool = False, confirm: Callable[[str], bool] | None = None) -> Repl:
        backend = open_backend("pioneer", fake.url, "sim", options=fast)
        assert isinstance(backend, PioneerBackend)
        session = RobotSession(backend, connect=fake.url, laser="sim", armed=armed,
                               confirm=confirm)
        made.append(session)
        return Repl(session, io.StringIO(), io.StringIO())

    yield fake, make
    for s in made:
        s.close()


def _out(repl: Repl) -> str:
    assert isinstance(repl.out, io.StringIO)
    return repl.out.getvalue()


def _err(repl: Repl) -> str:
    assert isinstance(repl.err, io.StringIO)
    return repl.err.getvalue()


def test_the_first_motion_is_confirmed_once(robot: tuple[FakeArcos, Callable[..., Repl]]
                                            ) -> None:
    fake, make = robot
    asked: list[str] = []
    answers = iter([False, True])

    def confirm(question: str) -> bool:
        asked.append(question)
        return next(answers)

    repl = make(confirm=confirm)
    assert repl.handle(ATOM)
    assert not repl.handle("a")  # declined: nothing moves
    assert "not confirmed: the robot did not move" in _err(repl)
    assert set(fake.args(Cmd.VEL)) <= {0}
    assert repl.handle("a") and repl.handle("a")  # yes once, then no more questions
    assert len(asked) == 2 and "will move" in asked[0] and fake.url[6:] in asked[0]
    assert 200 in fake.args(Cmd.VEL)
    assert not repl.handle("nonsense")  # a typo is reported without asking
    assert len(asked) == 2


def test_step_leaves_the_robot_stopped_between_steps(
        robot: tuple[FakeArcos, Callable[..., Repl]]) -> None:
    fake, make = robot
    repl = make(armed=True)
    assert repl.handle(ATOM.replace("0.3 s", "1 s")) and repl.handle("a")
    assert repl.handle(":step 3"), _err(repl)
    assert fake.wait_for(lambda: fake.args(Cmd.VEL)[-1] == 0 and fake.args(Cmd.RVEL)[-1] == 0)
    assert 200 in fake.args(Cmd.VEL)
    assert "#3" in _out(repl)
    assert repl.session.stepping


def test_simulator_only_commands_refuse_with_a_message(
        robot: tuple[FakeArcos, Callable[..., Repl]]) -> None:
    _, make = robot
    repl = make(armed=True)
    for line in (":where", ":world ellipse", ":world", ":set seed 3", ":set realtime on",
                 ":reset 1 2", ":load run.jsonl"):
        assert not repl.handle(line), line
    err = _err(repl)
    assert err.count("works in simulation only") == 7
    assert "internal error" not in err
    assert repl.handle(":reset") and "the robot stays at" in _out(repl)
    assert repl.handle(":pose") and "since connecting" in _out(repl)
    assert repl.handle(":scan") and "max range 32.767 m" in _out(repl)


def test_the_session_trace_names_the_robot(robot: tuple[FakeArcos, Callable[..., Repl]],
                                           tmp_path: Path) -> None:
    fake, make = robot
    repl = make(armed=True)
    assert repl.handle(ATOM) and repl.handle("a")
    path = tmp_path / "s.jsonl"
    assert repl.handle(f":trace {path}")
    header = json.loads(path.read_text().splitlines()[0])
    assert header["backend"] == "pioneer" and header["connect"] == fake.url
    assert header["laser"] == "sim" and header["program"]["runs"] == ["a"]
    assert repl.handle(f":plot {tmp_path / 's.png'}")
    assert (tmp_path / "s.png").stat().st_size > 1000


def test_the_prompt_asks_before_the_first_motion(
        robot: tuple[FakeArcos, Callable[..., Repl]]) -> None:
    fake, make = robot
    repl = make()
    with create_pipe_input() as inp:
        inp.send_text(ATOM + "\n" + "a\n" + "n\n" + "a\n" + "y\n" + "\x04")
        assert run_prompt(repl, input=inp, output=DummyOutput(), history=False) == 0
    assert "not confirmed" in _err(repl)
    assert "a (level 0) ended by timer" in _out(repl)
    assert _out(repl).count("ended by timer") == 1 and 200 in fake.args(Cmd.VEL)
    assert fake.url[6:] in _out(repl).splitlines()[0]  # the banner names the robot


def test_step_is_paced_like_a_run(robot: tuple[FakeArcos, Callable[..., Repl]]) -> None:
    """Each tick of a ``:step`` waits for its period, as in a run, even after the session
    looked at the robot between runs (``:pose``, a run's report): such a look used to
    start the tick grid, so the next ``:step 3`` ran ticks at 0.00, 0.01 and 0.11 s."""
    _, make = robot
    repl = make(armed=True)
    assert repl.handle("(go(0.2 m/s), never, 5 s)")
    assert repl.handle(":step 1") and repl.handle(":step 3")  # a run begun and paused
    assert repl.handle("(go(0.2 m/s), never, 0.1 s)")  # a run that ends, then its report
    assert repl.handle(":pose")
    time.sleep(0.3)  # the user reads the report
    for _ in range(2):
        before = len(repl.session.samples)
        assert repl.handle(":step 3"), _err(repl)
        ticks = [s.time for s in repl.session.samples[before:]]
        assert len(ticks) >= 2
        # the wait is a lower bound: a tick never comes before its period is over
        assert all(b - a >= 0.099 for a, b in zip(ticks[:-1], ticks[1:], strict=True)), ticks
