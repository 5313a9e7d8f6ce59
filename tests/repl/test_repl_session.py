"""The REPL's session: the robot is kept between runs, errors leave it intact, stepping,
reset, worlds, seeds, the session trace and plot.

Poses are checked against closed forms: the ellipse world's robot is the ideal unicycle
(no acceleration limits, no odometry noise) starting at (-9, 0.3) heading east, so
``go(v)`` for T seconds moves exactly v T and ``turn(w)`` for T turns exactly w T.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from mdle.core.errors import CheckError, MdleError, WorldError
from mdle.core.pose import Pose
from mdle.record.load import read_trace
from mdle.repl.session import ReplError, Session
from mdle.runtime import Cause

START = (-9.0, 0.3, 0.0)


@pytest.fixture
def session() -> Session:
    return Session("ellipse")


def pose_of(s: Session) -> tuple[float, float, float]:
    p = s.backend.true_pose
    return p.x, p.y, p.theta


def test_runs_continue_from_where_the_robot_stopped(session: Session) -> None:
    session.define("atom creep(v = 0.5 m/s) = (go(v), never, 2 s)\n"
                   "atom quarter = (turn(90 deg/s), never, 1 s)")
    first = session.run("creep")
    assert first.decisive.cause is Cause.TIMER
    assert first.decisive.time - first.t0 == pytest.approx(2.0)
    assert pose_of(session) == pytest.approx((-8.0, 0.3, 0.0), abs=1e-9)
    session.run("quarter")
    assert pose_of(session) == pytest.approx((-8.0, 0.3, math.pi / 2), abs=1e-9)
    third = session.run("creep(1 m/s)")  # now heading north
    assert pose_of(session) == pytest.approx((-8.0, 2.3, math.pi / 2), abs=1e-9)
    assert third.result.distance == pytest.approx(2.0)
    assert third.t0 == pytest.approx(3.0)  # the clock went on: 2 s + 1 s before it
    assert len(session.samples) == 21 + 11 + 21
    path = session.path_xy()
    assert path[0] == pytest.approx(START[:2])
    assert path[-1] == pytest.approx((-8.0, 2.3))


def test_an_interrupt_ends_the_run_and_the_report_says_which_level(session: Session) -> None:
    session.define("atom approach = (go(1 m/s), range(0 deg) < 1.5 m, 30 s)\n"
                   "behavior careful = ((approach, (turn(1 rad/s), never, 10 s)),"
                   " theta > 1 rad, inf)")
    report = session.run("careful")
    d = report.decisive
    # the behavior's own interrupt fired while the turn was running: level 0 ends it
    assert (d.path, d.level, d.cause) == ("careful", 0, Cause.INTERRUPT)
    assert report.result.terminations[0].path == "careful/approach"
    assert report.result.terminations[0].cause is Cause.INTERRUPT
    # the ellipse's left end is at x = -4; approach stops 1.5 m before (within a tick)
    assert report.result.terminations[0].time - report.t0 == pytest.approx(3.6, abs=0.11)
    # theta passes 1 rad in the 11th tick of the turn
    assert d.time - report.result.terminations[0].time == pytest.approx(1.1)
    assert report.result.terminations[1].cause is Cause.ENDED_BY_PARENT
    assert report.ok


def test_nested_completion_reports_the_innermost_decisive_end(session: Session) -> None:
    report = session.run("(((go(1 m/s), never, 1 s), (turn(1 rad/s), never, 0.5 s)), never, inf)")
    d = report.decisive
    assert d.cause is Cause.TIMER and d.level == 1 and d.path.endswith("turn")
    assert report.result.termination.cause is Cause.COMPLETED
    assert pose_of(session) == pytest.approx((-8.0, 0.3, 0.5), abs=1e-9)


def test_errors_leave_the_session_as_it_was(session: Session) -> None:
    session.define("atom creep = (go(0.5 m/s), never, 2 s)")
    session.run("creep")
    before = pose_of(session), session.workspace.format(), len(session.samples)
    with pytest.raises(CheckError):
        session.define("atom creep = (go(3 s), never, 1 s)")  # a time where a speed goes
    with pytest.raises(CheckError):
        session.run("crep")
    with pytest.raises(MdleError):
        session.run("(go(1 m/s), never")  # unfinished
    with pytest.raises(WorldError):
        session.set_world("no-such-world")
    with pytest.raises(WorldError):
        session.reset(Pose(0.0, 0.0, 0.0))  # inside the ellipse
    assert (pose_of(session), session.workspace.format(), len(session.samples)) == before
    assert session.world.name == "ellipse"


def test_a_collision_is_reported_and_the_robot_stays_put(session: Session) -> None:
    report = session.run("(go(1 m/s), never, 10 s)")  # straight into the ellipse
    assert not report.ok
    assert report.collision is not None and report.collision.label == "ellipse"
    assert report.result.collided
    # the ideal robot is a point: contact at the ellipse's boundary, x = -4 * sqrt(1 - (0.3/2)^2)
    assert report.collision.x == pytest.approx(-4 * math.sqrt(1 - 0.15 ** 2), abs=1e-3)
    # the session carries on: back off and run again
    back = session.run("(go(-0.5 m/s), never, 2 s)")
    assert back.collision is None
    assert session.backend.true_pose.x == pytest.approx(report.collision.x - 1.0, abs=1e-6)


def test_reset_to_a_pose_and_to_the_start(session: Session) -> None:
    session.run("(go(1 m/s), never, 1 s)")
    here = session.reset(Pose(-8.0, -3.0, math.radians(90)))
    assert (here.x, here.y, here.theta) == pytest.approx((-8.0, -3.0, math.pi / 2))
    assert session.samples == [] and session.observe().time == 0.0
    session.run("(go(1 m/s), never, 1 s)")
    assert pose_of(session) == pytest.approx((-8.0, -2.0, math.pi / 2), abs=1e-9)
    session.reset()
    assert pose_of(session) == pytest.approx(START)


def test_step_advances_tick_by_tick_and_finishes(session: Session) -> None:
    with pytest.raises(ReplError, match="run an element first"):
        session.step(1)
    session.run("(go(1 m/s), never, 0.5 s)")  # x: -9 -> -8.5
    out = session.step(3)
    assert out.started and out.report is None and session.stepping
    assert [r.tick for r in out.rows] == [1, 2, 3]
    assert [r.sample.cmd_v for r in out.rows] == [1.0, 1.0, 1.0]
    assert out.rows[0].sample.x == pytest.approx(0.5)       # odometry
    assert out.rows[0].sample.true_x == pytest.approx(-8.5)
    assert out.rows[0].front == pytest.approx(8.5 - 4 * math.sqrt(1 - 0.15 ** 2) + 0.0, abs=0.2)
    assert pose_of(session)[0] == pytest.approx(-8.2)
    out = session.step(10)  # continues the same run: 2 more ticks of motion, then the end
    assert not out.started and out.report is not None and not session.stepping
    assert out.report.decisive.cause is Cause.TIMER
    assert out.report.result.distance == pytest.approx(0.5)
    assert len(out.rows) == 3  # ticks 4, 5 move; tick 6 sees the timer and ends
    assert out.rows[-1].sample.cmd_v == 0.0
    assert pose_of(session)[0] == pytest.approx(-8.0)
    with pytest.raises(ReplError):
        session.step(0)


def test_running_an_element_ends_a_paused_step(session: Session) -> None:
    session.define("atom creep = (go(1 m/s), never, 5 s)")
    session.run("creep")
    session.step(2)
    assert session.stepping
    session.run("(turn(1 rad/s), never, 1 s)")
    assert not session.stepping
    causes = [r.result.termination.cause for r in session._runs if r.result]
    assert causes == [Cause.TIMER, Cause.STOPPED, Cause.TIMER]


def test_the_run_limit_stops_an_endless_element() -> None:
    s = Session("ellipse", until=3.0)
    report = s.run("(turn(1 rad/s), never, inf)")
    assert report.limit == 3.0 and report.result.cause is Cause.STOPPED
    assert report.result.duration == pytest.approx(3.0)
    assert report.ok  # the limit is not a failure


def test_set_seed_keeps_the_robot_and_changes_the_noise() -> None:
    s = Session("default")  # the Pioneer with a noisy LMS-200
    s.run("(turn(0.5 rad/s), never, 1 s)")
    here = s.backend.true_pose
    scan_a = s.observe().scan
    assert scan_a is not None
    s.set_seed(7)
    assert s.seed == 7
    assert (s.backend.true_pose.x, s.backend.true_pose.y) == pytest.approx((here.x, here.y))
    assert s.samples == []
    scan_b = s.observe().scan
    assert scan_b is not None
    assert not (scan_b.ranges == scan_a.ranges).all()


def test_set_world_moves_to_its_start() -> None:
    s = Session("ellipse")
    s.run("(go(1 m/s), never, 1 s)")
    s.set_world("corridor")
    assert s.world.name == "corridor"
    sp = s.world.start_pose
    assert pose_of(s) == pytest.approx((sp.x, sp.y, sp.theta))
    assert s.samples == []


def test_trace_and_plot_of_the_session(session: Session, tmp_path: Path) -> None:
    with pytest.raises(ReplError, match="nothing to write"):
        session.write_trace(tmp_path / "empty.jsonl")
    session.define("atom hug = (follow_boundary(rc = 1 m, v = 1 m/s), never, 4 s)")
    session.run("(go(1 m/s), range(0 deg) < 1.5 m, 20 s)")
    session.run("hug")
    n = session.write_trace(tmp_path / "s.jsonl")
    trace = read_trace(tmp_path / "s.jsonl")
    assert n == len(trace.samples) == len(session.samples)
    assert trace.header["world"]["name"] == "ellipse" and trace.header["repl"] is True
    assert trace.end is not None and trace.end["ticks"] == n
    # each run's last sample is taken after its element ended (path '')
    assert {p.split("/")[0] for p in trace.paths()} == {"go", "hug", ""}
    assert "side_range" in trace.diag_names()
    assert [r["type"] for r in trace.extra] == ["start", "start"]
    out = session.plot(tmp_path / "s.png")
    assert Path(out).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_save_and_load(session: Session, tmp_path: Path) -> None:
    with pytest.raises(ReplError, match="nothing to save"):
        session.save(tmp_path / "none.mdle")
    session.define("atom   creep(v=0.5 m/s)=(go(v),never,2 s)")
    added, replaced, _ = session.define("atom creep(v = 0.25 m/s) = (go(v), never, 2 s)\n"
                                        "atom spin = (turn(1 rad/s), never, 1 s)")
    assert added == ("spin",) and replaced == ("creep",)
    text = session.save(tmp_path / "defs.mdle")
    assert text == ("atom creep(v = 0.25 m/s) = (go(v), never, 2 s)\n"
                    "atom spin = (turn(1 rad/s), never, 1 s)\n"
                    "run spin\n")
    other = Session("ellipse")
    names, _ = other.load(tmp_path / "defs.mdle")
    assert names == ("creep", "spin")
    other.run("creep")
    assert pose_of(other)[0] == pytest.approx(-8.5)
    with pytest.raises(ReplError, match="cannot write"):
        session.save(tmp_path / "no" / "such" / "dir.mdle")


def test_save_writes_a_run_line_mdle_run_can_use(session: Session, tmp_path: Path) -> None:
    """Issue 12.18: the saved file runs. The entry given with `run`; else the definition
    last run; else the plan defined last; else the runnable element defined last."""
    session.define("atom creep(v = 0.25 m/s) = (go(v), never, 2 s)\n"
                   "atom need(v) = (go(v), never, 1 s)")
    assert session.save_entry() == "creep"  # the only one that runs as it stands
    session.define("plan tour = ((creep, creep), never, inf)\n"
                   "atom spin = (turn(1 rad/s), never, 1 s)")
    assert session.save_entry() == "tour"  # a plan before a later atom
    session.run("creep(0.5 m/s)")
    assert session.save_entry() == "creep"  # the definition last run
    session.run("(go(0.1 m/s), never, 0.1 s)")  # not a name: the plan again
    assert session.save_entry() == "tour"
    session.define("run spin")
    assert session.save_entry() == "spin"
    assert session.save(tmp_path / "s.mdle").endswith("atom spin = (turn(1 rad/s), never, 1 s)\n"
                                                      "run spin\n")
    other = Session("ellipse")
    other.define("atom need(v) = (go(v), never, 1 s)")
    assert other.save_entry() is None
    assert "run" not in other.save(tmp_path / "n.mdle")


def test_report_closest_approach_and_settled_boundary_distance(session: Session) -> None:
    approach = session.run("(go(1 m/s), range(0 deg) < 1.5 m, 20 s)")
    # heading straight at the ellipse: closest at the last tick, where it stopped
    assert approach.closest is not None
    t, x, y = approach.closest
    assert (t, x, y) == pytest.approx((3.6, -5.4, 0.3), abs=1e-6)
    assert approach.result.min_clearance == pytest.approx(
        session.world.clearance((x, y), 0.0), abs=1e-6)
    assert approach.side is None  # go reports no boundary distance
    session.reset(Pose(0.0, 3.0, math.pi))  # 1 m above the ellipse's top, heading west
    hug = session.run("(follow_boundary(side = left, rc = 1 m, v = 0.5 m/s), never, 12 s)")
    side = hug.side
    # 120 ticks with control (the 121st sample is after the end: no diagnostics)
    assert side is not None and side.n == 120 and side.window == 10.0
    samples = [s.diag["side_range"] for s in session.samples if s.diag.get("side_hit")]
    assert side.low == min(samples) and side.high == max(samples)
    assert side.mean == pytest.approx(sum(samples[-101:]) / 101)
    assert side.mean == pytest.approx(1.0, abs=0.05) and side.std < 0.05


def test_step_uses_the_definitions_as_they_are_now(session: Session) -> None:
    session.define("atom creep = (go(0.5 m/s), never, 2 s)")
    session.run("creep")
    session.define("atom creep = (go(0.25 m/s), never, 2 s)")
    out = session.step(2)
    assert [r.sample.cmd_v for r in out.rows] == [0.25, 0.25]
    session.define("atom creep = (go(1 m/s), never, 2 s)")
    out = session.step(1)  # the paused run goes on as it started
    assert out.rows[0].sample.cmd_v == 0.25
