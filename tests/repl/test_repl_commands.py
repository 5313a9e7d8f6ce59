"""The REPL interpreter: what each input prints, and that no mistake leaves the REPL."""

from __future__ import annotations

import io
import math
import re
from pathlib import Path

import numpy as np
import pytest

from mdle.core.pose import Pose
from mdle.repl.commands import COMMANDS, Repl, classify
from mdle.repl.session import Session


class Run:
    """A Repl on the ellipse world with captured output."""

    def __init__(self, world: str = "ellipse") -> None:
        self.out, self.err = io.StringIO(), io.StringIO()
        self.repl = Repl(Session(world), self.out, self.err)

    def __call__(self, text: str) -> tuple[bool, str, str]:
        o, e = self.out.tell(), self.err.tell()
        ok = self.repl.handle(text)
        return ok, self.out.getvalue()[o:], self.err.getvalue()[e:]


@pytest.fixture
def r() -> Run:
    return Run()


def test_classify() -> None:
    assert classify("  ") == "empty" and classify("# note") == "empty"
    assert classify(":pose") == "command"
    assert classify("atom a = (go(1 m/s), never, 1 s)") == "definition"
    assert classify("import \"x.mdle\"") == "definition"
    assert classify("run main") == "definition"
    assert classify("atomic") == "element"  # a name that starts like a keyword
    assert classify("(go(1 m/s), never, 1 s)") == "element"


def test_define_run_and_report(r: Run) -> None:
    ok, out, err = r("atom creep(v = 0.5 m/s) = (go(v), never, 2 s)")
    assert ok and out == "defined creep\n" and err == ""
    ok, out, _ = r("atom creep(v = 0.25 m/s) = (go(v), never, 2 s)")
    assert out == "redefined creep\n"
    ok, out, _ = r("atom creep(v=0.25 m/s)=(go(v),never,2 s)")  # the same, retyped
    assert ok and out == "no change\n"
    ok, out, err = r("creep")
    assert ok and err == ""
    lines = out.splitlines()
    assert lines[0] == "creep (level 0) ended by timer at 2.00 s"
    assert lines[1] == "  pose      x 0.50 m  y 0.00 m  heading 0.0 deg"  # odometry
    assert lines[2].startswith("  travelled 0.50 m in 2.00 s (21 ticks), min clearance ")


def test_mistakes_print_a_message_and_keep_the_session(r: Run) -> None:
    r("atom creep = (go(0.5 m/s), never, 2 s)")
    r("creep")
    before = r.repl.session.backend.true_pose, r.repl.session.workspace.format()
    bad = [
        ("atom creep = (go(3 s), never, 1 s)", "is a speed such as"),
        ("crep", "did you mean `creep`"),
        ("atom x = (go(1 m/s) never, 1 s)", "error"),
        ("(go(1 m/s), never, 1 s) )", "error"),
        (":nope", "unknown command `:nope`"),
        (":world atlantis", "unknown world `atlantis`"),
        (":reset 0 0", "overlaps"),
        (":reset a b", "x must be a number"),
        (":reset 0 1e7", "y: a coordinate must be from -1,000,000 to 1,000,000 m, got 1e7"),
        (":reset -9 0.3 1e308", "theta: a heading must be from -360 to 360 deg, got 1e308"),
        (":reset -9 0.3 inf", "theta must be a finite number, got `inf`"),
        (":step x", "whole number"),
        (":load /no/such/file.mdle", "no/such/file.mdle"),
        (":set speed 3", "no setting `speed`"),
        (":pose extra", "takes no arguments"),
        (":plot", "takes one argument"),
        (":save 'unbalanced", "cannot read the command"),
    ]
    for text, message in bad:
        ok, _, err = r(text)
        assert not ok, text
        assert message in err, (text, err)
        assert "Traceback" not in err
    assert r.repl.failures == len(bad)
    assert (r.repl.session.backend.true_pose, r.repl.session.workspace.format()) == before


def test_a_collision_fails_the_input_and_the_next_one_works(r: Run) -> None:
    ok, out, _ = r("(go(1 m/s), never, 20 s)")
    assert not ok
    assert "COLLIDED with `ellipse`" in out
    # stalled against it: the runtime aborts after 5 s
    assert "aborted: the robot stalled for 5.0 s" in out
    assert "was aborted by an error at 10.10 s" in out  # stalled from the tick at 5.1 s
    ok, out, _ = r(":reset")
    assert ok and "x -9.00 m  y 0.30 m" in out
    ok, _, _ = r("(go(1 m/s), never, 1 s)")
    assert ok


def test_help_lists_every_command(r: Run) -> None:
    ok, out, _ = r(":help")
    assert ok
    for name in COMMANDS:
        assert re.search(rf"^  :{name}\b", out, re.MULTILINE), name
    ok, out, _ = r(":help step")
    assert out.startswith(":step [N]\n")
    assert {"help", "pose", "scan", "where", "plot", "trace", "reset", "world", "defs", "save",
            "load", "step", "set", "quit"} <= set(COMMANDS)


def test_pose_and_scan(r: Run) -> None:
    r("(go(1 m/s), range(0 deg) < 1.5 m, 20 s)")
    ok, out, _ = r(":pose")
    assert ok
    assert "odometry x 3.60 m  y 0.00 m  heading 0.0 deg" in out
    assert "true     x -5.40 m  y 0.30 m  heading 0.0 deg" in out
    assert "world `ellipse`, seed 0" in out
    ok, out, _ = r(":scan")
    assert ok
    lines = out.splitlines()
    assert lines[0].startswith("scan at t = 3.60 s: 181 beams from -90 to 90 deg")
    found = re.search(r"ahead ([0-9.]+) m", out)
    assert found, out
    ahead = float(found.group(1))
    assert ahead == pytest.approx(5.40 - 3.95, abs=0.1)
    assert lines[-2].startswith("  right:") and lines[-1].startswith("  left :")
    assert "front ray 1.4" in lines[-2]  # the ellipse ahead, seen by both sides' front ray


def test_scan_shows_the_boundary_the_sensor_functions_read() -> None:
    r = Run()
    # put the robot 1 m above the ellipse's top (y = 2), heading west: boundary on its left
    r(":reset 0 3 180")
    ok, out, _ = r(":scan")
    assert ok
    m = re.search(r"left : boundary_range ([0-9.]+) m, boundary_tangent (-?[0-9.]+) deg, "
                  r"boundary_curvature ([-+][0-9.]+) 1/m", out)
    assert m, out
    assert float(m.group(1)) == pytest.approx(1.0, abs=0.05)
    assert abs(float(m.group(2))) < 5.0
    # the top of the ellipse (a = 4, b = 2) has curvature b / a^2 = 0.125; convex on the
    # left is positive
    assert float(m.group(3)) == pytest.approx(0.125, abs=0.08)
    assert "right: no boundary on the side ray" in out


def test_where_draws_the_world_the_path_and_the_robot(r: Run) -> None:
    r("(go(1 m/s), never, 2 s)")
    r("(turn(90 deg/s), never, 1 s)")
    ok, out, _ = r(":where 60")
    assert ok
    rows = out.splitlines()
    grid = [row[1:-1] for row in rows[1:-2]]
    assert all(len(g) == 60 for g in grid)
    assert sum(g.count("#") for g in grid) > 50  # the ellipse
    robot = [(i, g.index("^")) for i, g in enumerate(grid) if "^" in g]
    start = [(i, g.index("o")) for i, g in enumerate(grid) if "o" in g]
    assert len(robot) == 1 and len(start) == 1
    # 2 m east of the start, on the same row: the columns are (18 m / 60) = 0.3 m wide
    assert robot[0][0] == start[0][0]
    assert robot[0][1] - start[0][1] == pytest.approx(2.0 / 0.3, abs=1)
    assert grid[start[0][0]][start[0][1] + 1:robot[0][1]] == "." * (robot[0][1] - start[0][1] - 1)
    assert "^ robot (x -7.00 m  y 0.30 m  heading 90.0 deg)" in rows[-1]


def test_defs_save_load(r: Run, tmp_path: Path) -> None:
    ok, out, _ = r(":defs")
    assert out == "nothing defined yet\n"
    r("atom creep(v = 0.5 m/s) =\n    (go(v),\n     never, 2 s)")
    r("interrupt near(d = 1 m) = range(0 deg) < d")
    r("behavior both = ((creep, (turn(1 rad/s), near, 1 s)), never, inf)")
    ok, out, _ = r("run both")
    assert ok and "entry is now `both`" in out
    ok, out, _ = r(":defs")
    expected = ("atom creep(v = 0.5 m/s) = (go(v), never, 2 s)\n"
                "interrupt near(d = 1 m) = range(0 deg) < d\n"
                "behavior both = ((creep, (turn(1 rad/s), near, 1 s)), never, inf)\n"
                "run both\n")
    assert out == expected
    target = tmp_path / "saved.mdle"
    ok, out, _ = r(f":save {target}")
    assert ok and out == (f"saved 3 definitions to {target} (4 lines, ending `run both`: "
                          f"`mdle run {target}` runs it), and world `ellipse` to "
                          f"{tmp_path / 'saved.world.yaml'}\n")
    assert target.read_text() == expected
    other = Run()
    ok, out, _ = other(f":load {target}")
    assert ok and out == f"loaded {target}: both, creep, near\n"
    ok, out, _ = other("both")
    assert ok and out.startswith("both/turn (level 1) ended by timer at 3.00 s; "
                                 "both ran to its end")


def test_step_prints_each_tick(r: Run) -> None:
    ok, _, err = r(":step")
    assert not ok and "run an element first" in err
    r("atom hug = (follow_boundary(side = left, rc = 1 m, v = 1 m/s), never, 0.3 s)")
    r(":reset 0 3 180")
    r("hug")
    r(":reset 0 3 180")
    ok, out, _ = r(":step 2")
    lines = out.splitlines()
    assert ok and lines[0] == "stepping `hug` from the robot's current state"
    assert lines[1].startswith("  #1    t   0.00 s  hug  cmd v +1.000 m/s  omega ")
    found = re.search(r"side_range ([0-9.]+) m  side_tangent [-0-9.e]+ deg  side_curvature "
                      r"[-0-9.e]+ 1/m", lines[2])
    assert found, lines[2]
    side = float(found.group(1))
    assert side == pytest.approx(1.0, abs=0.05) and "side_hit yes" in lines[2]
    # every diagnostic with its unit (or as a flag, a mode, `none`): issue 12.18
    for item in lines[2].split("  "):
        if item.strip():
            name, value, *unit = item.split()
            assert unit or value in ("yes", "no", "follow", "corner", "search", "none"), item
    assert re.search(r"mode follow  lost [0-9.]+ s  u_law [-0-9.e]+ rad/s  safety (yes|no)  "
                     r"predicted_clearance ([0-9.]+ m|none)$", lines[2]), lines[2]
    assert lines[3].startswith("  #2    t   0.10 s  hug")
    ok, out, _ = r(":step 5")
    lines = out.splitlines()
    assert lines[0].startswith("  #3    t   0.20 s  hug")
    assert any(line.startswith("hug (level 0) ended by timer at 0.30 s") for line in lines)


def test_set_until_and_seed(r: Run) -> None:
    ok, out, _ = r(":set until 2")
    assert ok and out == "a run stops after 2 s\n"
    ok, out, _ = r("(turn(1 rad/s), never, inf)")
    assert ok and "(the run limit of 2 s; change it with `:set until SECONDS`)" in out
    ok, out, _ = r(":set until inf")
    assert r.repl.session.until is None
    ok, out, _ = r(":set seed 5")
    assert ok and r.repl.session.seed == 5
    ok, _, err = r(":set until -1")
    assert not ok and "positive" in err


def test_trace_plot_world_quit(r: Run, tmp_path: Path) -> None:
    ok, _, err = r(f":trace {tmp_path / 't.jsonl'}")
    assert not ok and "nothing to write" in err
    r("(go(1 m/s), never, 1 s)")
    ok, out, _ = r(f":trace {tmp_path / 't.jsonl'}")
    assert ok and out == f"trace written to {tmp_path / 't.jsonl'} (11 samples)\n"
    ok, out, _ = r(f":plot {tmp_path / 'p.svg'}")
    assert ok and (tmp_path / "p.svg").read_text().lstrip().startswith("<?xml")
    ok, _, err = r(f":plot {tmp_path / 'p.gif'}")
    assert not ok and ".png, .svg or .pdf" in err
    ok, out, _ = r(":world")
    assert "reference worlds:" in out and "corridor" in out
    ok, out, _ = r(":world corridor")
    assert ok and out.startswith("world `corridor`")
    ok, out, _ = r(":quit")
    assert ok and r.repl.quit_requested


def test_an_internal_error_is_one_line_and_the_session_survives(r: Run, monkeypatch:
                                                                   pytest.MonkeyPatch) -> None:
    def broken(self: Session, text: str, observers: object = ()) -> None:
        raise ZeroDivisionError("boom")

    monkeypatch.setattr(Session, "run", broken)
    ok, _, err = r("(go(1 m/s), never, 1 s)")
    assert not ok and "internal error: ZeroDivisionError: boom" in err
    monkeypatch.undo()
    ok, _, _ = r("(go(1 m/s), never, 1 s)")
    assert ok and r.repl.session.backend.true_pose.x == pytest.approx(-8.0)
    assert math.isfinite(r.repl.session.observe().time)


def test_where_path_has_no_gaps_and_stays_on_the_map() -> None:
    from mdle.repl.views import render_map

    s = Session("ellipse")
    # a long jump between two samples must still be drawn cell by cell
    path = np.array([[-10.0, -4.0], [6.0, 4.0]])
    rows = render_map(s.world, path, Pose(20.0, 4.0, 0.0), width=40)
    grid = [row[1:-1] for row in rows[1:-2]]
    marks = [(i, j) for i, g in enumerate(grid) for j, ch in enumerate(g) if ch in ".o"]
    cols = sorted({j for _, j in marks})
    assert cols == list(range(cols[0], cols[-1] + 1))  # every column in between is drawn
    assert any(">" in g for g in grid)  # the robot far off the world's extent is on the map
    assert "x -11.0..20.5 m" in rows[-1]


def test_exact_sensing_scan_and_a_world_file(tmp_path: Path) -> None:
    out, err = io.StringIO(), io.StringIO()
    repl = Repl(Session("ellipse", sensing="exact"), out, err)
    assert repl.handle(":reset 0 3 180") and repl.handle(":scan")
    text = out.getvalue()
    assert "(exact)" in text
    m = re.search(r"left : boundary_range ([0-9.]+) m, boundary_tangent (-?[0-9.]+) deg, "
                  r"boundary_curvature ([-+][0-9.]+) 1/m", text)
    assert m, text
    # the oracle: exactly 1 m to the ellipse's top, tangent along the heading, b / a^2
    assert float(m.group(1)) == pytest.approx(1.0, abs=0.005)
    assert float(m.group(2)) == pytest.approx(0.0, abs=0.05)
    assert float(m.group(3)) == pytest.approx(0.125, abs=0.001)
    world = tmp_path / "box.yaml"
    world.write_text("name: box\nseed: 3\nstart: {x: 0, y: 0, theta: 90}\nrobot: ideal\n"
                     "obstacles:\n  - {type: circle, name: post, center: [0, 3], radius: 0.5}\n")
    assert repl.handle(f":world {world}")
    assert repl.session.world.name == "box" and repl.session.seed == 3
    assert repl.handle("(go(1 m/s), range(0 deg) < 1 m, 10 s)")
    assert repl.session.backend.true_pose.y == pytest.approx(1.5, abs=0.11)


def test_a_failing_control_law_is_reported_and_the_session_goes_on() -> None:
    import types

    from mdle.atoms import default_registry
    from mdle.atoms.registry import Registry, control_law
    from mdle.core.backend import Command

    @control_law()
    def explode(args: object, ctx: object, state: object) -> Command:
        """Drive, then fail."""
        if ctx.t > 0.25:  # type: ignore[attr-defined]
            raise ValueError("sensor went away")
        return Command(1.0, 0.0)

    reg = default_registry().merged(Registry.from_modules(types.SimpleNamespace(e=explode)))
    out, err = io.StringIO(), io.StringIO()
    repl = Repl(Session("ellipse", registry=reg), out, err)
    assert not repl.handle("(explode, never, 5 s)")
    assert "control law `explode` of `explode` failed at t = 0.300 s" in err.getvalue()
    assert "was aborted by an error at 0.30 s" in out.getvalue()
    assert repl.session.backend._cmd.v == 0.0  # stopped
    assert repl.handle("(go(1 m/s), never, 1 s)")
    assert repl.session.backend.true_pose.x == pytest.approx(-9.0 + 0.3 + 1.0)


def test_classify_skips_comments() -> None:
    assert classify("# just a note\n   # and another") == "empty"
    assert classify("# tuned on Monday\natom a = (go(1 m/s), never, 1 s)") == "definition"
    assert classify("import \"dir#1/x.mdle\"  # a # inside a string is not a comment") == (
        "definition")
    assert classify("  # first\n  :pose") == "command"


def test_set_realtime_paces_runs_to_the_wall_clock(r: Run) -> None:
    import time

    ok, out, _ = r(":set realtime on")
    assert out == "runs go at the pace of the wall clock\n"
    assert ok and r.repl.session.realtime
    start = time.monotonic()
    assert r("(go(1 m/s), never, 0.5 s)")[0]
    assert time.monotonic() - start >= 0.45
    ok, _, _ = r(":set realtime off")
    assert ok and not r.repl.session.realtime
    ok, _, err = r(":set realtime maybe")
    assert not ok and "`on` or `off`" in err


def test_colour_only_when_asked(r: Run) -> None:
    r("(go(1 m/s), never, 1 s)")
    ok, plain, _ = r(":where")
    assert "\x1b" not in plain
    r.repl.color = True
    ok, coloured, _ = r(":where")
    assert ok and "\x1b[" in coloured
    strip = re.sub(r"\x1b\[[0-9;]*m", "", coloured)
    assert strip == plain  # the same text, with colours
    ok, report, _ = r("(go(1 m/s), never, 1 s)")
    assert report.startswith("\x1b[1;32mgo (level 0) ended by timer")  # bold green: fine


def test_a_negative_seed_is_a_message(r: Run) -> None:
    ok, out, err = r(":set seed -1")
    assert not ok and "a seed is a whole number from 0 to 4294967295" in err
    assert "internal error" not in err
    ok, out, err = r(":set seed 4294967296")
    assert not ok and "internal error" not in err


@pytest.mark.parametrize("args", ["inf 0", "0 nan", "0 0 inf", "-inf -inf"])
def test_reset_to_a_place_that_is_not_finite_is_a_message(r: Run, args: str) -> None:
    ok, out, err = r(f":reset {args}")
    assert not ok and ("must be a finite number" in err or "must be a number" in err)
    ok, out, err = r("(go(0.3 m/s), never, 1 s)")  # the robot was left where it was
    assert ok and "internal error" not in err, err


def test_load_of_a_world_file_says_to_use_world(r: Run, tmp_path: Path) -> None:
    world = tmp_path / "w.world.yaml"
    world.write_text("name: w\nstart: {x: 0, y: 0, theta: 0}\n")
    ok, _, err = r(f":load {world}")
    assert not ok and f"`{world}` is a YAML file (a world file?), not an MDLe plan" in err
    assert f"hint: to make it the session's world: `:world {world}`" in err


def test_save_says_when_nothing_can_run(r: Run, tmp_path: Path) -> None:
    r("atom need(v) = (go(v), never, 1 s)")
    ok, out, _ = r(f":save {tmp_path / 'n.mdle'}")
    assert ok and out.endswith("(1 line; no `run` line: nothing here runs without arguments), "
                               f"and world `ellipse` to {tmp_path / 'n.world.yaml'}\n")


def test_speeds_are_compared_with_the_sessions_robot() -> None:
    r = Run("default")  # its robot: pioneer2dx, 2.2 m/s
    ok, _, err = r("atom dash = (go(3 m/s), never, 1 s)")
    assert ok and ("warning: `v` of `go` is 3 m/s, more than the robot can do: the top speed of "
                   "`pioneer2dx` (the robot of world `default`) is 2.2 m/s") in err
    ok, _, err = r("(go(2.5 m/s), never, 0.1 s)")
    assert ok and "<repl>:1:5: warning: `v` of `go` is 2.5 m/s" in err
    ok, _, err = r("(go(2 m/s), never, 0.1 s)")
    assert ok and err == ""
