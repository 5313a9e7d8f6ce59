"""Plans over ``--backend ros2`` against ``mdle sim serve --ros2`` in another process.

Every process of a test keeps its DDS traffic on 127.0.0.1 in a domain of the test's own
(``dds_env``); the ``cyclonedds`` package's own command line is the independent peer that
checks names, types and the final zero command.
"""

from __future__ import annotations

import re
import signal
import subprocess
import time
from pathlib import Path

import pytest

from tests.ros2.conftest import (
    Procs,
    cyclonedds_argv,
    element_sequence,
    mdle_argv,
    wait_for_text,
)

PLAN = """
interrupt near = min_range(-30 deg, 30 deg) < 1 m
atom cruise = (go(0.4 m/s), near, 20 s)
atom spin = (turn(60 deg/s), never, 2 s)
plan main = ((cruise, spin, cruise), stalled, 16 s)
run main
"""

TEAM_WORLD = """
name: split-room
seed: 3
robot: pioneer2dx
robots:
  - {name: east, start: [-3.2, 0.5, 0]}
  - {name: west, start: [3.5, -0.5, 3.14159]}
obstacles:
  - {type: wall, name: room, points: [[-6, -4], [6, -4], [6, 4], [-6, 4]], closed: true}
  - {type: wall, name: middle, points: [[0, -4], [0, 4]]}
"""

CRAWL = """
atom crawl = (go(0.2 m/s), never, 10 min)
plan main = (crawl, stalled, 10 min)
"""


def _serve(procs: Procs, tmp_path: Path, *args: str) -> subprocess.Popen[str]:
    out = tmp_path / "serve.out"
    server = procs.start(mdle_argv("sim", "serve", "--ros2", *args), out)
    wait_for_text(out, "serving world", 60, server)
    return server


def _end(proc: subprocess.Popen[str], signum: int = signal.SIGINT) -> int:
    proc.send_signal(signum)
    return proc.wait(timeout=30)


def test_a_plan_runs_over_ros2_with_the_simulators_element_sequence(
        procs: Procs, tmp_path: Path) -> None:
    plan = tmp_path / "p.mdle"
    plan.write_text(PLAN)
    alone = subprocess.run(mdle_argv("run", str(plan), "--world", "empty", "--quiet",
                                     "--trace", str(tmp_path / "sim.jsonl")),
                           env=procs.env, capture_output=True, text=True, timeout=120)
    assert alone.returncode == 0, alone.stderr
    server = _serve(procs, tmp_path, "--world", "empty", "--speed", "2")
    run = subprocess.run(mdle_argv("run", str(plan), "--backend", "ros2", "--use-sim-time",
                                   "--quiet", "--trace", str(tmp_path / "ros.jsonl")),
                         env=procs.env, capture_output=True, text=True, timeout=180)
    assert run.returncode == 0, run.stderr
    expected = element_sequence(tmp_path / "sim.jsonl")
    assert ("main/cruise", "end") in expected and ("main/spin", "end") in expected
    assert element_sequence(tmp_path / "ros.jsonl") == expected
    assert _end(server) == 130
    # the run's trace is a recording `mdle robots fit` fits a profile to
    fit = subprocess.run(mdle_argv("robots", "fit", str(tmp_path / "ros.jsonl"), "-o",
                                   str(tmp_path / "fitted.yaml")),
                         env=procs.env, capture_output=True, text=True, timeout=300)
    assert fit.returncode == 0, fit.stderr
    assert "RMS" in fit.stdout and (tmp_path / "fitted.yaml").is_file()


def test_the_repl_drives_a_ros2_robot_and_stops_it_on_quit(procs: Procs,
                                                          tmp_path: Path) -> None:
    server = _serve(procs, tmp_path, "--world", "empty")
    session = subprocess.run(
        mdle_argv("repl", "--backend", "ros2", "--use-sim-time", "--yes", "--plain"),
        input="atom fwd = (go(0.2 m/s), never, 2 s)\nfwd\n:quit\n", env=procs.env,
        capture_output=True, text=True, timeout=120)
    assert session.returncode == 0, session.stdout + session.stderr
    # the timer ends at the first tick at or after 2 s of the simulator's clock
    assert re.search(r"fwd \(level 0\) ended by timer at 2\.[01]\d s", session.stdout), \
        session.stdout
    x = float(re.search(r"pose\s+x ([-\d.]+) m", session.stdout).group(1))  # type: ignore[union-attr]
    assert 0.2 < x < 0.45   # 0.2 m/s for 2 s, less the ramp and the robot's lag
    assert "robot stopped; connection to ROS 2 robot" in session.stderr
    assert _end(server) == 130


def test_a_two_robot_team_runs_in_namespaces(procs: Procs, tmp_path: Path) -> None:
    plan = tmp_path / "p.mdle"
    plan.write_text(PLAN)
    world = tmp_path / "split.world.yaml"
    world.write_text(TEAM_WORLD)
    sim = subprocess.run(mdle_argv("run", "--world", str(world), "--robot-plan",
                                   f"east={plan}", "--robot-plan", f"west={plan}", "--quiet",
                                   "--trace", str(tmp_path / "sim.jsonl")),
                         env=procs.env, capture_output=True, text=True, timeout=180)
    assert sim.returncode == 0, sim.stderr
    server = _serve(procs, tmp_path, "--world", str(world), "--speed", "2")
    runs = {name: procs.start(mdle_argv("run", str(plan), "--backend", "ros2", "--ns", name,
                                        "--use-sim-time", "--quiet", "--trace",
                                        str(tmp_path / f"ros.{name}.jsonl")),
                              tmp_path / f"{name}.out")
            for name in ("east", "west")}
    for name, proc in runs.items():
        assert proc.wait(timeout=180) == 0, (tmp_path / f"{name}.out").read_text()
        expected = element_sequence(tmp_path / f"sim.{name}.jsonl")
        assert ("main/cruise", "end") in expected
        assert element_sequence(tmp_path / f"ros.{name}.jsonl") == expected, name
    assert _end(server) == 130


_TWIST = re.compile(r"Twist_\(\s*linear=Vector3_\(x=([-\d.e]+), y=[-\d.e]+, z=[-\d.e]+\),"
                    r"\s*angular=Vector3_\(x=[-\d.e]+, y=[-\d.e]+, z=([-\d.e]+)\)\s*\)")


def _twists_until_stopped(path: Path, timeout: float, listener: subprocess.Popen[str]
                          ) -> list[tuple[float, float]]:
    """The (v, omega) the tool printed, once the last is a zero command or ``timeout`` is up."""
    end = time.monotonic() + timeout
    while True:
        twists = [(float(v), float(w)) for v, w in _TWIST.findall(path.read_text())]
        if (twists and twists[-1] == (0.0, 0.0)) or time.monotonic() > end \
                or listener.poll() is not None:
            return twists
        time.sleep(0.1)


@pytest.mark.parametrize("how", ["SIGINT", "SIGTERM", "killed simulator"])
def test_an_independent_dds_tool_sees_ros2_names_and_the_final_zero_command(
        procs: Procs, tmp_path: Path, how: str) -> None:
    plan = tmp_path / "crawl.mdle"
    plan.write_text(CRAWL)
    env = {**procs.env, "COLUMNS": "250"}
    server = _serve(procs, tmp_path, "--world", "empty", "--ns", "robot1")
    run_out = tmp_path / "run.out"
    run = procs.start(mdle_argv("run", str(plan), "--backend", "ros2", "--ns", "robot1",
                                "--quiet"), run_out)
    # The tool learns the type from a writer it discovers (XTypes) during its scan, so it
    # starts once the run may publish, and again if its scan found no writer yet.
    domain = env["ROS_DOMAIN_ID"]
    sub_out = tmp_path / "sub.out"
    for _ in range(10):
        listener = procs.start(cyclonedds_argv("subscribe", "rt/robot1/cmd_vel", "-i", domain,
                                               "-r", "3s", "--suppress-progress-bar",
                                               "--color", "none"), sub_out)
        try:
            wait_for_text(sub_out, "x=0.2,", 30, listener)  # it decodes the run's commands
            break
        except pytest.fail.Exception:
            assert run.poll() is None, run_out.read_text()
            listener.kill()
            listener.wait(timeout=30)
    else:
        pytest.fail(f"the cyclonedds tool never received a command: {sub_out.read_text()}")
    if how == "SIGINT":
        ls = subprocess.run(cyclonedds_argv("ls", "-i", domain, "--runtime", "3s",
                                            "--suppress-progress-bar", "--color", "none"),
                            env=env, capture_output=True, text=True, timeout=60)
        for topic, dds in (("rt/robot1/cmd_vel", "geometry_msgs::msg::dds_::Twist_"),
                           ("rt/robot1/scan", "sensor_msgs::msg::dds_::LaserScan_"),
                           ("rt/robot1/odom", "nav_msgs::msg::dds_::Odometry_"),
                           ("rt/robot1/tf", "tf2_msgs::msg::dds_::TFMessage_"),
                           ("rt/robot1/tf_static", "tf2_msgs::msg::dds_::TFMessage_"),
                           ("rt/clock", "rosgraph_msgs::msg::dds_::Clock_")):
            assert re.search(rf"{re.escape(topic)}\b[\s\S]*?{re.escape(dds)}", ls.stdout), \
                (topic, ls.stdout[-3000:])
        code = _end(run, signal.SIGINT)
        assert code == 130, run_out.read_text()
    elif how == "SIGTERM":
        assert _end(run, signal.SIGTERM) == 143, run_out.read_text()
    else:
        server.kill()
        server.wait(timeout=30)
        assert run.wait(timeout=30) == 1, run_out.read_text()
        # whichever went stale first: the robot is lost either way
        assert re.search(r"no (odometry on /robot1/odom|scan on /robot1/scan) for",
                         run_out.read_text()), run_out.read_text()
    # (every message's angular part reads "x=0.0,": wait for the commands to end at zero)
    twists = _twists_until_stopped(sub_out, 10.0, listener)
    listener.terminate()
    listener.wait(timeout=30)
    assert any(v == pytest.approx(0.2) for v, _ in twists), twists[:3]
    assert twists[-1] == (0.0, 0.0), twists[-5:]
    if server.poll() is None:
        assert _end(server) == 130
