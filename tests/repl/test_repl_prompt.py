"""The prompt_toolkit front end, driven through a pipe input with a dummy output:
completion, multi-line input, history, Ctrl-C at the prompt and during a run, Ctrl-D."""

from __future__ import annotations

import io
import os
import signal
from pathlib import Path
from typing import IO, Any

import pytest
from prompt_toolkit.completion import CompleteEvent
from prompt_toolkit.document import Document
from prompt_toolkit.input import create_pipe_input
from prompt_toolkit.output import DummyOutput
from pygments.token import Keyword, Name, Number

from mdle.repl.commands import Repl
from mdle.repl.prompt import MdleCompleter, MdleLexer, history_path, run_prompt
from mdle.repl.session import Session
from mdle.runtime import BaseObserver


@pytest.fixture(autouse=True)
def data_home(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """Never touch the user's history: the data directory is a temporary one."""
    home = tmp_path / "data"
    monkeypatch.setenv("XDG_DATA_HOME", str(home))
    return home


@pytest.fixture
def repl() -> Repl:
    return Repl(Session("ellipse"), io.StringIO(), io.StringIO())


def _text(stream: IO[str]) -> str:
    """What was written to one of the test REPL's in-memory streams."""
    assert isinstance(stream, io.StringIO)
    return stream.getvalue()


def drive(repl: Repl, *chunks: str) -> int:
    """Type ``chunks`` at the prompt (then Ctrl-D) and run the REPL until it leaves."""
    with create_pipe_input() as inp:
        for c in chunks:
            inp.send_text(c)
        inp.send_text("\x04")
        return run_prompt(repl, input=inp, output=DummyOutput())


def completions(repl: Repl, text: str) -> list[str]:
    c = MdleCompleter(repl)
    return [x.text for x in c.get_completions(Document(text), CompleteEvent(True))]


# ---------------------------------------------------------------------- completion

def test_completer_offers_laws_sensors_names_and_keywords(repl: Repl) -> None:
    repl.handle("atom follow_wide = (follow_boundary(rc = 2 m), never, 5 s)")
    assert completions(repl, "fol") == ["follow_wide", "follow_boundary"]
    assert completions(repl, "(go(1 m/s), bou") == ["boundary_range", "boundary_curvature",
                                                    "boundary_tangent"]
    # a keyword at the start only, then names (the team sensor `bearing_to`)
    assert completions(repl, "be") == ["behavior", "bearing_to"]
    assert "behavior" not in completions(repl, "(go(1 m/s), be")
    assert completions(repl, "(go(1 m/s), stalled or nev") == ["never"]


def test_completer_offers_parameters_symbols_and_units(repl: Repl) -> None:
    params = completions(repl, "(follow_boundary(")
    names = [p.name for p in repl.session.workspace.registry.laws["follow_boundary"].params]
    assert params[:len(names)] == [f"{n} = " for n in names]
    assert names[:3] == ["side", "rc", "v"]
    assert "right" in params and "left" in params
    assert completions(repl, "(follow_boundary(rc = 1 m, ") == params
    assert completions(repl, "(follow_boundary(side = ") == ["right", "left"]
    assert completions(repl, "(go(v), boundary_range(side = l") == ["left"]
    assert completions(repl, "atom a(d = 1 m, speed) = (follow_boundary(rc = 1 m, s") == [
        "side = ", "scaled", "scan", "speed"]  # symbols the law takes (damping, model)
    # units of the parameter's dimension: v of go is a speed, rate of turn a turn rate
    assert completions(repl, "(go(0.3 m") == ["m/s"]
    assert completions(repl, "(turn(30 deg") == ["deg/s"]
    assert completions(repl, "(follow_boundary(side = left, 1 ") == ["m", "cm", "mm"]
    assert completions(repl, "(follow_boundary(v = 1 ") == ["m/s"]
    assert completions(repl, "(go(1 m/s), never, 2 m") == ["mm", "ms", "min", "m/s"]
    assert completions(repl, "(go(0") == []
    assert completions(repl, "atom x2 m") == ["min_range", "message"]  # `2` ends a name: no units


def test_completer_offers_commands_worlds_and_files(repl: Repl, tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    # A folder cluttered as a newcomer's is after the README's first command: a plot
    # beside the plans must not be offered as a world or a plan.
    monkeypatch.chdir(tmp_path)
    (tmp_path / "ellipse.png").write_bytes(b"")
    (tmp_path / "ellipse-run.jsonl").write_text("")
    (tmp_path / "plans").mkdir()
    (tmp_path / "plans" / "tune.mdle").write_text("")
    (tmp_path / "plans" / "tune.png").write_bytes(b"")
    (tmp_path / "worlds").mkdir()
    (tmp_path / "worlds" / "lab.yaml").write_text("")
    (tmp_path / "worlds" / "lab.txt").write_text("")
    assert completions(repl, ":s") == ["scan", "save", "step", "set"]
    assert completions(repl, ":wor") == ["world"]
    assert completions(repl, ":world ell") == ["ellipse"]
    assert completions(repl, ":world worlds/l") == ["ab.yaml"]
    assert completions(repl, ":set u") == ["until"]
    assert completions(repl, ":help qu") == ["quit"]
    assert completions(repl, ":load plans/tu") == ["ne.mdle"]
    # outputs may be any file name: `:plot` offers what is there
    assert sorted(completions(repl, ":plot plans/tu")) == ["ne.mdle", "ne.png"]


def test_tab_completes_at_the_prompt_and_enter_continues_unfinished_input(repl: Repl) -> None:
    rc = drive(repl,
               "atom hug(d = 1 m) = (follow_b\t(rc\td,\r",   # Enter: brackets still open
               "v = 1 m/s), never, 2 s)\r",
               "hu\t\r")
    assert rc == 0
    assert repl.session.workspace.format() == (
        "atom hug(d = 1 m) = (follow_boundary(rc = d, v = 1 m/s), never, 2 s)\n")
    out = _text(repl.out)
    assert "defined hug\n" in out
    assert "hug (level 0) ended by timer at 2.00 s" in out
    assert repl.failures == 0


def test_tab_with_several_candidates_inserts_their_common_part(repl: Repl) -> None:
    drive(repl, "(go(0.5 m/s), bou\t\tnever, 1 s)\r")
    # `bou` -> `boundary_` (common part of boundary_range/_curvature/_tangent); the second
    # Tab opens the menu without choosing, so the text stays as typed
    err = _text(repl.err)
    assert "boundary_never" in err


# ---------------------------------------------------------------------- keys

def test_ctrl_c_at_the_prompt_drops_the_line(repl: Repl) -> None:
    drive(repl, "atom junk = (go(1 m/s)\x03", "(go(1 m/s), never, 1 s)\r")
    assert repl.session.workspace.names() == []
    assert repl.failures == 0
    assert repl.session.backend.true_pose.x == pytest.approx(-8.0)


def test_ctrl_d_leaves_and_quit_too(repl: Repl) -> None:
    assert drive(repl) == 0
    r2 = Repl(Session("ellipse"), io.StringIO(), io.StringIO())
    assert drive(r2, ":quit\r", "(go(1 m/s), never, 1 s)\r") == 0
    assert r2.quit_requested and r2.session.samples == []  # nothing ran after :quit


def test_ctrl_c_during_a_run_stops_the_robot_and_gives_the_prompt_back(
        repl: Repl, monkeypatch: pytest.MonkeyPatch) -> None:
    session = repl.session
    session.until = None  # the element never ends by itself
    # Ctrl-C once the run is 2 s (simulated) in, sent from the run's own thread as the
    # backend reports that time: a watching thread raced the simulation, which covers a
    # minute of simulated time in half a second of wall time on a busy machine.
    backend = session.backend
    observe = backend.observe
    sent: list[float] = []

    def observe_then_interrupt() -> Any:
        obs = observe()
        if obs.time > 2.0 and not sent:
            sent.append(obs.time)
            os.kill(os.getpid(), signal.SIGINT)
        return obs

    monkeypatch.setattr(backend, "observe", observe_then_interrupt)
    drive(repl, "(turn(30 deg/s), never, inf)\r", ":pose\r")
    out = _text(repl.out)
    assert "turn (level 0) was stopped from outside at" in out
    assert "(Ctrl-C: robot stopped)" in out
    # the prompt came back: the next input ran
    assert "odometry x 0.00 m  y 0.00 m" in out
    assert session.backend._cmd.v == 0.0 and session.backend._cmd.omega == 0.0
    assert repl.failures == 1  # a stopped run counts as not done
    t = session.observe().time
    assert 2.0 < t < 60.0


def test_history_is_kept_in_the_data_directory(data_home: Path) -> None:
    assert history_path() == data_home / "mdle" / "repl_history"
    assert history_path({"XDG_DATA_HOME": ""}) == Path.home() / ".local/share/mdle/repl_history"
    assert history_path({"XDG_DATA_HOME": "relative/dir"}) == (
        Path.home() / ".local/share/mdle/repl_history")  # the XDG rule: absolute paths only
    r1 = Repl(Session("ellipse"), io.StringIO(), io.StringIO())
    drive(r1, "atom creep = (go(0.5 m/s), never, 1 s)\r", "creep\r")
    text = (data_home / "mdle" / "repl_history").read_text()
    assert "+atom creep = (go(0.5 m/s), never, 1 s)" in text and "+creep" in text
    # a new session recalls the definition with Up Up (history loads when a prompt
    # starts, so only the first prompt of a piped test sees it: typeahead is instant)
    r2 = Repl(Session("ellipse"), io.StringIO(), io.StringIO())
    drive(r2, "\x1b[A\x1b[A\r", "creep\r")
    assert r2.session.workspace.names() == ["creep"]
    assert r2.session.backend.true_pose.x == pytest.approx(-8.5)


# ---------------------------------------------------------------------- highlighting

def test_lexer_tokens() -> None:
    toks = [(t, v) for t, v in MdleLexer().get_tokens(
        "atom cruise(v = 0.3 m/s) = (go(v), range(0 deg) < 1 m or never, inf) # c\n")
        if v.strip()]
    kinds = {v: t for t, v in toks}
    assert kinds["atom"] in Keyword.Declaration
    assert kinds["cruise"] in Name.Function and kinds["go"] in Name.Function
    assert kinds["0.3"] in Number and kinds[" m/s"] in Keyword.Type
    assert kinds["never"] in Keyword.Constant and kinds["inf"] in Keyword.Constant
    assert kinds["# c"].__class__ is type(Keyword) and "Comment" in str(kinds["# c"])
    cmd = [(str(t), v) for t, v in MdleLexer().get_tokens(":world ellipse\n")]
    assert cmd[0] == ("Token.Name.Builtin", ":world")


def test_progress_line_shows_long_runs_and_is_erased() -> None:
    from mdle.repl.prompt import ProgressLine

    wall = [0.0]
    stream = io.StringIO()
    progress = ProgressLine(stream, interval=0.2, clock=lambda: wall[0])
    s = Session("ellipse")

    class Advance(BaseObserver):
        """Wall time goes 0.05 s per tick: a line every 4 ticks, from the 4th on."""

        def on_tick(self, sample: object) -> None:
            wall[0] += 0.05

    s.run("(go(1 m/s), never, 1 s)", [Advance(), progress])
    text = stream.getvalue()
    shown = text.split("\r\x1b[K")
    assert shown[0] == "" and shown[-1] == ""  # each line overwrites; erased at the end
    lines = [x for x in shown if x]
    assert lines[0] == "  running go: t 0.3 s  x 0.30 m  y 0.00 m  (Ctrl-C stops it)"
    assert len(lines) == 2  # at 0.3 s and 0.7 s of simulated time (11 ticks)
    quick = io.StringIO()
    s.run("(go(1 m/s), never, 0.1 s)", [ProgressLine(quick)])
    assert quick.getvalue() == ""  # a quick run shows nothing
