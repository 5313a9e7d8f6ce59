"""`mdle run` and `mdle plot` end to end.

The installed command in a subprocess, the embedded simulator, traces that parse, plots
that are written, exit codes, Ctrl-C.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import signal
import subprocess
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from mdle.record.load import read_trace

FOLLOW = """\
interrupt blocked(d = 0.5 m) = range(0 deg) < d
atom cruise = (go(0.5 m/s), blocked(1.5 m), 30 s)
atom follow = (follow_boundary(side = right, rc = 1 m, v = 0.5 m/s), never, 6 s)
plan main = ((cruise, follow), stalled, 2 min)
"""

RAM = "plan main = ((go(0.5 m/s), never, 60 s), never, inf)\n"

SPIN = """\
atom spin = (turn(20 deg/s), never, inf)
plan main = ((spin), never, inf)
run main
"""

RunMdle = Callable[..., subprocess.CompletedProcess[str]]  # the run_mdle fixture
WritePlan = Callable[..., Path]  # the plan fixture: (text, name="plan.mdle") -> path


@pytest.fixture
def run_mdle(mdle_command: list[str]) -> RunMdle:
    """Run the installed ``mdle`` with ``args``, output captured, plots on the Agg backend."""

    def call(*args: str, cwd: Path | None = None, timeout: float = 120
             ) -> subprocess.CompletedProcess[str]:
        env = dict(os.environ, MPLBACKEND="Agg")
        return subprocess.run([*mdle_command, *args], capture_output=True, text=True, cwd=cwd,
                              timeout=timeout, env=env)

    return call


@pytest.fixture
def plan(tmp_path: Path) -> WritePlan:
    """Write ``text`` to a plan file in ``tmp_path`` and return its path."""
    def write(text: str, name: str = "plan.mdle") -> Path:
        p = tmp_path / name
        p.write_text(text)
        return p

    return write


def test_run_writes_trace_and_plot_and_summary(
        plan: WritePlan, tmp_path: Path, run_mdle: RunMdle) -> None:
    trace, png = tmp_path / "t.jsonl", tmp_path / "p.png"
    res = run_mdle("run", str(plan(FOLLOW)), "--world", "ellipse", "--trace", str(trace),
               "--plot", str(png))
    assert res.returncode == 0, res.stderr
    assert "\x1b" not in res.stdout  # off a terminal: plain lines, no control codes
    assert "start main/cruise" in res.stdout and "end   main/cruise  interrupt" in res.stdout
    assert "elements run:" in res.stdout and "distance travelled:" in res.stdout
    t = read_trace(trace)
    assert t.header["world"]["name"] == "ellipse" and t.header["seed"] == 0
    assert t.header["program"]["element"] == "main"
    assert t.end is not None
    assert t.end["cause"] == "completed" and not t.end["collided"]
    assert [(e["path"], e["cause"]) for e in t.events if e["kind"] == "end"] == [
        ("main/cruise", "interrupt"), ("main/follow", "timer"), ("main", "completed")]
    assert {"side_range", "side_curvature"} <= set(t.diag_names())
    assert all("clearance" in s and "true_x" in s for s in t.samples)
    assert png.read_bytes().startswith(b"\x89PNG")


def test_world_beside_the_plan_is_used(plan: WritePlan, tmp_path: Path, run_mdle: RunMdle) -> None:
    from mdle import sim

    world_file = Path(sim.__file__).parent / "worlds" / "ellipse.yaml"
    shutil.copy(world_file, tmp_path / "plan.world.yaml")
    trace = tmp_path / "t.jsonl"
    res = run_mdle("run", str(plan(FOLLOW)), "--quiet", "--until", "2", "--trace", str(trace))
    assert res.returncode == 0, res.stderr
    assert res.stdout == ""
    head = read_trace(trace).header
    assert head["world"]["spec"] == str(tmp_path / "plan.world.yaml")
    end = read_trace(trace).end
    assert end is not None and end["cause"] == "stopped"


def test_default_world_when_none_is_given(
        plan: WritePlan, tmp_path: Path, run_mdle: RunMdle) -> None:
    trace = tmp_path / "t.jsonl"
    res = run_mdle("run", str(plan(SPIN)), "-q", "--until", "1", "--trace", str(trace))
    assert res.returncode == 0, res.stderr
    t = read_trace(trace)
    assert t.header["world"]["spec"] == "default" and len(t.samples) == 11


def test_plan_errors_exit_1_with_check_style_messages(plan: WritePlan, run_mdle: RunMdle) -> None:
    p = plan("plan main = ((cruise), never, inf)\n")
    res = run_mdle("run", str(p))
    assert res.returncode == 1
    assert f"{p}:1:" in res.stderr and "error:" in res.stderr and "cruise" in res.stderr


def test_unknown_element_and_world_exit_1(plan: WritePlan, run_mdle: RunMdle) -> None:
    p = plan(FOLLOW)
    res = run_mdle("run", str(p), "--plan", "cruse")
    assert res.returncode == 1 and "did you mean `cruise`" in res.stderr
    res = run_mdle("run", str(p), "--world", "elipse")
    assert res.returncode == 1 and "ellipse" in res.stderr and "Traceback" not in res.stderr


def test_bad_plot_or_trace_file_is_refused_before_running(
        plan: WritePlan, tmp_path: Path, run_mdle: RunMdle) -> None:
    res = run_mdle("run", str(plan(FOLLOW)), "--plot", str(tmp_path / "p.jpg"))
    assert res.returncode == 1 and ".png, .svg or .pdf" in res.stderr
    assert res.stdout == ""  # nothing ran
    res = run_mdle("run", str(plan(FOLLOW)), "--trace", str(tmp_path / "no" / "t.jsonl"))
    assert res.returncode == 1 and "--trace" in res.stderr and "no folder" in res.stderr
    assert res.stdout == ""
    # a plot that could not be written at the end of the run is refused before it
    res = run_mdle("run", str(plan(FOLLOW)), "--plot", str(tmp_path / "none" / "p.png"))
    assert res.returncode == 1 and "--plot" in res.stderr and "no folder" in res.stderr
    assert res.stdout == ""
    res = run_mdle("run", str(plan(FOLLOW)), "--plot", str(tmp_path))
    assert res.returncode == 1 and "must end in" in res.stderr
    (tmp_path / "d.png").mkdir()
    res = run_mdle("run", str(plan(FOLLOW)), "--plot", str(tmp_path / "d.png"))
    assert res.returncode == 1 and "is a folder" in res.stderr and res.stdout == ""


def test_pioneer_backend_needs_a_connection(plan: WritePlan, run_mdle: RunMdle) -> None:
    res = run_mdle("run", str(plan(FOLLOW)), "--backend", "pioneer")
    assert res.returncode == 1 and "--connect" in res.stderr


def test_collision_exits_3(plan: WritePlan, tmp_path: Path, run_mdle: RunMdle) -> None:
    trace = tmp_path / "t.jsonl"
    res = run_mdle("run", str(plan(RAM)), "--world", "ellipse", "--trace", str(trace), "-q")
    assert res.returncode == 3
    assert "collided" in res.stderr
    end = read_trace(trace).end
    assert end is not None and end["collided"] is True


def test_a_collision_is_named_in_stderr_the_trace_the_summary_and_the_plot(
        plan: WritePlan, tmp_path: Path, run_mdle: RunMdle) -> None:
    trace, png = tmp_path / "t.jsonl", tmp_path / "p.png"
    res = run_mdle("run", str(plan(RAM)), "--world", "default", "--trace", str(trace),
                   "--plot", str(png))
    assert res.returncode == 3
    # what was hit, where and when, and in which element (the box of the default room)
    assert res.stderr.startswith("mdle run: the robot collided: hit `box` (rectangle) at "
                                 "x 0.75 m, y -3.00 m, t = 10.3 s, while `main/go` ran"), res.stderr
    assert "collided: YES: hit `box` (rectangle)" in res.stdout
    t = read_trace(trace)
    (hit,) = t.collisions()
    assert (hit["obstacle"], hit["kind"], hit["index"], hit["path"]) == (
        "box", "rectangle", 1, "main/go")
    # the contact itself, not the tick's start: a ramp of 0.5 / 0.3 s to 0.5 m/s, then
    # the rest of the 4.75 m at 0.5 m/s, which is 9.5 s plus half the ramp
    assert hit["x"] == pytest.approx(0.75, abs=0.01)
    assert hit["t"] == pytest.approx(9.5 + 0.5 / 0.3 / 2, abs=2e-4)
    assert t.end is not None and t.end["collision"]["obstacle"] == "box"
    assert png.read_bytes().startswith(b"\x89PNG")


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_signal_stops_the_robot_and_leaves_a_valid_trace(
        plan: WritePlan, tmp_path: Path, sig: signal.Signals, code: int,
        mdle_command: list[str]) -> None:
    trace = tmp_path / "t.jsonl"
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.Popen([*mdle_command, "run", str(plan(SPIN)), "--world", "empty",
                             "--realtime", "--trace", str(trace)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:  # wait until the run is under way
            if trace.exists() and trace.read_text().count('"type":"sample"') >= 3:
                break
            time.sleep(0.05)
        else:
            pytest.fail("the run never started")
        proc.send_signal(sig)
        out, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == code, err
    assert "robot stopped" in err
    lines = trace.read_text().splitlines()
    records = [json.loads(line) for line in lines]  # complete, strict JSON lines
    assert records[-1]["type"] == "end" and records[-1]["cause"] == "stopped"
    assert records[-1]["reason"] == ("SIGINT (Ctrl-C)" if sig == signal.SIGINT else "SIGTERM")
    # the stop command that was sent is the last sample, after the elements ended
    assert records[-2]["type"] == "sample" and records[-2]["cmd_omega"] == 0.0
    assert records[-2]["cmd_v"] == 0.0 and records[-2]["path"] == ""
    last_event = next(r for r in reversed(records) if r["type"] == "event")
    assert last_event["cause"] == "stopped" and last_event["t"] == records[-2]["t"]
    assert "elements run:" in out


def test_plot_command_writes_svg_and_reports_errors(
        plan: WritePlan, tmp_path: Path, run_mdle: RunMdle) -> None:
    trace = tmp_path / "t.jsonl"
    assert run_mdle("run", str(plan(FOLLOW)), "--world", "ellipse", "-q", "--until", "5",
                "--trace", str(trace)).returncode == 0
    svg = tmp_path / "p.svg"
    res = run_mdle("plot", str(trace), "-o", str(svg))
    assert res.returncode == 0, res.stderr
    assert svg.read_text().lstrip().startswith("<?xml")
    res = run_mdle("plot", str(trace), "-o", str(tmp_path / "p.gif"))
    assert res.returncode == 1 and ".png, .svg or .pdf" in res.stderr
    res = run_mdle("plot", str(tmp_path / "missing.jsonl"), "-o", str(svg))
    assert res.returncode == 1 and "cannot read trace" in res.stderr


REPO = Path(__file__).resolve().parents[2]
PLANS = sorted((REPO / "plans").rglob("*.mdle"))


@pytest.mark.parametrize("plan_file", PLANS, ids=lambda p: str(p.relative_to(REPO)))
def test_every_plan_in_plans_runs_in_the_simulator(
        plan_file: Path, tmp_path: Path, run_mdle: RunMdle) -> None:
    from mdle.lang import load_program

    program = load_program(plan_file)
    extra = [] if program.entry else ["--plan", sorted(program.elements)[0]]
    trace, png = tmp_path / "t.jsonl", tmp_path / "p.png"
    res = run_mdle("run", str(plan_file), *extra, "--until", "30", "--trace", str(trace),
               "--plot", str(png), cwd=REPO)
    # Every example runs in its own world (the one beside it, or the default) without
    # touching anything: a collision here is a bad example or a regression.
    assert res.returncode == 0, res.stderr
    t = read_trace(trace)
    assert t.end is not None and t.end["ticks"] == len(t.samples) > 0
    assert not any(s.get("collided") for s in t.samples)
    assert png.read_bytes().startswith(b"\x89PNG")


def test_plans_folder_is_not_empty() -> None:
    # the parametrised test above runs one case per plan: it must have something to run
    assert PLANS, "no plans in plans/"


def test_simulation_options_reach_the_backend(
        plan: WritePlan, tmp_path: Path, run_mdle: RunMdle) -> None:
    trace = tmp_path / "t.jsonl"
    res = run_mdle("run", str(plan(FOLLOW)), "--world", "ellipse", "--seed", "5", "--robot",
               "ideal", "--sensing", "exact", "--rate", "20", "--until", "1", "-q",
               "--trace", str(trace))
    assert res.returncode == 0, res.stderr
    t = read_trace(trace)
    assert (t.header["seed"], t.header["robot"], t.header["sensing"]) == (5, "ideal", "exact")
    assert t.column("t").tolist() == pytest.approx([k * 0.05 for k in range(21)])
    res = run_mdle("run", str(plan(FOLLOW)), "--robot", "segway", "-q", "--until", "1")
    assert res.returncode == 1 and "segway" in res.stderr and "Traceback" not in res.stderr


def test_realtime_runs_at_wall_clock_speed(plan: WritePlan, run_mdle: RunMdle) -> None:
    # a lower bound only: paced runs must not go faster than the wall clock
    start = time.monotonic()
    res = run_mdle("run", str(plan(SPIN)), "--world", "empty", "--realtime", "--until", "1.5", "-q")
    assert res.returncode == 0, res.stderr
    assert time.monotonic() - start >= 1.4


def test_live_view_on_a_terminal(plan: WritePlan, mdle_command: list[str]) -> None:
    import pty

    master, slave = pty.openpty()
    env = dict(os.environ, MPLBACKEND="Agg", COLUMNS="100", TERM="xterm")
    proc = subprocess.Popen([*mdle_command, "run", str(plan(SPIN)), "--world", "empty", "--until",
                             "2", "--realtime"], stdout=slave, stderr=slave, env=env)
    os.close(slave)
    chunks = []
    try:
        while True:
            try:
                data = os.read(master, 65536)
            except OSError:  # the child closed the terminal
                break
            if not data:
                break
            chunks.append(data)
        assert proc.wait(timeout=60) == 0
    finally:
        os.close(master)
        if proc.poll() is None:
            proc.kill()
    text = b"".join(chunks).decode("utf-8", "replace")
    assert "\x1b[" in text  # drawn with control codes
    assert "mdle run" in text and "timer left" in text  # the live panel was drawn
    assert "spin" in text and "elements run" in text and "real-time factor" in text


def test_second_ctrl_c_between_ticks_still_ends_the_run(
        plan: WritePlan, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # Two SIGINTs while no tick is running: the first asks for a stop, the second raises
    # KeyboardInterrupt outside the scheduler, which must still end the run cleanly.
    from mdle.cli import main
    from mdle.runtime import Scheduler

    original = Scheduler.tick
    calls = {"n": 0}

    def tick(self: Scheduler) -> bool:
        calls["n"] += 1
        if calls["n"] == 3:
            os.kill(os.getpid(), signal.SIGINT)
            os.kill(os.getpid(), signal.SIGINT)
        return original(self)

    monkeypatch.setattr(Scheduler, "tick", tick)
    trace = tmp_path / "t.jsonl"
    code = main(["run", str(plan(FOLLOW)), "--world", "ellipse", "--quiet",
                 "--trace", str(trace)])
    assert code == 130
    t = read_trace(trace)
    assert t.end is not None and t.end["cause"] == "stopped"
    # two ticks, then the stop command sent when the run was ended between ticks
    assert len(t.samples) == 3 and t.samples[-1]["cmd_v"] == 0.0


def test_set_overrides_a_parameter_and_start_places_the_robot(
        plan: WritePlan, tmp_path: Path, run_mdle: RunMdle) -> None:
    text = "atom cruise(v = 0.3 m/s) = (go(v), never, 2 s)\nplan main = ((cruise), never, inf)\n"
    trace = tmp_path / "t.jsonl"
    res = run_mdle("run", str(plan(text)), "--world", "empty", "-q", "--trace", str(trace),
                   "--set", "cruise.v=0.5m/s", "--start", "1, -2 m, 90")
    assert res.returncode == 0, res.stderr
    t = read_trace(trace)
    assert max(t.column("cmd_v")) == pytest.approx(0.5)
    assert (t.samples[0]["true_x"], t.samples[0]["true_y"]) == (1.0, -2.0)
    assert t.samples[0]["true_theta"] == pytest.approx(math.pi / 2)
    assert t.header["overrides"] == ["cruise.v=0.5m/s"]
    assert t.header["start"]["theta"] == pytest.approx(math.pi / 2)


def test_bad_set_and_start_are_located_messages_not_tracebacks(
        plan: WritePlan, run_mdle: RunMdle) -> None:
    path = str(plan("atom cruise(v = 0.3 m/s) = (go(v), never, 2 s)\n"
                    "plan main = ((cruise), never, inf)\n"))
    res = run_mdle("run", path, "--world", "empty", "--set", "cruise.v=0.5 m")
    assert res.returncode == 1
    assert res.stderr.startswith("--set:1:10: error: `v` of `cruise` is a speed such as "
                                 "`0.3 m/s`, found a length (`0.5 m`)\n    cruise.v=0.5 m\n")
    res = run_mdle("run", path, "--world", "empty", "--start", "1,2")
    assert res.returncode == 2 and "expected X,Y,THETA" in res.stderr
    res = run_mdle("run", path, "--world", "empty", "--start", "1 s,2,0")
    assert res.returncode == 2 and "X of --start is a length" in res.stderr
    res = run_mdle("run", path, "--world", "default", "--start", "1.5,-3,0")  # in the box
    assert res.returncode == 1 and "overlaps" in res.stderr and "Traceback" not in res.stderr
