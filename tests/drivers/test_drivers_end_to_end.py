"""A small MDLe program run on the Pioneer backend against the fake ARCOS server."""

from __future__ import annotations

import json
import math
import subprocess
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pytest

from mdle.core.errors import BackendError
from mdle.drivers import open_backend
from mdle.drivers.arcos import Cmd
from mdle.drivers.pioneer import PioneerOptions
from mdle.lang import load_text
from mdle.runtime import Cause, element_of, run

if TYPE_CHECKING:
    from tests.drivers.conftest import FakeArcos

    FakeRobot = Callable[..., FakeArcos]

PLAN = """\
atom fwd = (go(0.4 m/s), range(0 deg) < 0.8 m, 3 s)
atom spin = (turn(30 deg/s), never, 0.3 s)
plan main = ((fwd, spin), never, 5 s)
run main
"""


def _wall_ahead(fake: FakeArcos) -> Callable[[int], np.ndarray]:
    """Scans of a wall 1 m ahead of where the robot started (it drives towards it)."""

    def scan(_: int) -> np.ndarray:
        bearings = -math.pi / 2 + np.arange(181) * math.pi / 181
        ahead = 1000.0 - fake.pose_mm[0]
        with np.errstate(divide="ignore"):
            r = np.where(np.cos(bearings) > 0.05, ahead / np.cos(bearings), 32000)
        return np.minimum(r, 32000).astype(int)

    return scan


def test_plan_runs_on_the_pioneer_and_stops_it(fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    fake = fake_robot()
    fake.scan_mm = _wall_ahead(fake)
    program = load_text(PLAN)
    backend = open_backend("pioneer", fake.url, "sim", options=fast)
    try:
        result = run(element_of(program), backend, rate=10.0)
        # fwd ended by its interrupt (the wall within 0.8 m), spin by its timer
        causes = {t.path.split("/")[-1]: t.cause for t in result.terminations}
        assert causes["fwd"] is Cause.INTERRUPT and causes["spin"] is Cause.TIMER
        assert result.fault is None
        assert 0.15 < result.distance < 0.4
        assert result.max_lateness < 0.05
        vel, rvel = fake.args(Cmd.VEL), fake.args(Cmd.RVEL)
        assert 400 in vel and 30 in rvel  # go(0.4 m/s), then turn(30 deg/s)
        # the robot is stopped at the end, before the connection closes
        assert fake.wait_for(lambda: fake.args(Cmd.VEL)[-1] == 0 and fake.args(Cmd.RVEL)[-1] == 0)
        assert fake.v_mm == 0 and fake.w_deg == 0
        assert not fake.commands(Cmd.CLOSE)
        assert fake.watchdog_trips == 0
    finally:
        backend.close()
    assert fake.wait_for(lambda: fake.commands(Cmd.CLOSE) != [])


def test_dropped_robot_ends_the_run_with_the_robot_stopped(fake_robot: FakeRobot,
                                                           fast: PioneerOptions) -> None:
    fake = fake_robot(behaviour="drop", drop_after=0.4)
    fake.scan_mm = _wall_ahead(fake)
    program = load_text(PLAN.replace("0.8 m, 3 s", "0.1 m, 3 s"))
    backend = open_backend("pioneer", fake.url, "sim", options=fast)
    try:
        t0 = time.monotonic()
        with pytest.raises(BackendError, match="lost the robot"):
            run(element_of(program), backend, rate=10.0)
        assert time.monotonic() - t0 < 1.0
    finally:
        backend.close()


def _run_on_fake(fake_robot: FakeRobot, tmp_path: Path, *options: str) -> FakeArcos:
    """``mdle run`` the wall plan on a fake robot with its laser; return the robot."""
    from mdle.cli import main

    fake = fake_robot()
    fake.scan_mm = _wall_ahead(fake)
    plan = tmp_path / "wall.mdle"
    plan.write_text(PLAN)
    code = main(["run", str(plan), "--backend", "pioneer", "--connect", fake.url,
                 "--laser", "sim", "--quiet", *options])
    assert code == 0
    return fake


def test_mdle_run_cli_on_the_fake_robot(fake_robot: FakeRobot, tmp_path: Path) -> None:
    trace = tmp_path / "run.jsonl"
    fake = _run_on_fake(fake_robot, tmp_path, "--trace", str(trace))
    lines = [json.loads(line) for line in trace.read_text().splitlines()]
    assert lines[0]["backend"] == "pioneer" and lines[0]["laser"] == "sim"
    samples = [x for x in lines if x["type"] == "sample"]
    assert len(samples) >= 5
    # wall-clock ticks: lateness and the scan's age are recorded per tick
    assert all(0 <= s["lateness"] < 0.08 for s in samples)
    assert all(0 <= s["scan_age"] < 0.5 for s in samples)
    assert fake.wait_for(lambda: fake.commands(Cmd.CLOSE) != [])
    assert fake.v_mm == 0 and fake.w_deg == 0
    assert 400 in fake.args(Cmd.VEL)


@pytest.mark.parametrize("robot", [None, "pioneer-p3dx"])
def test_a_recording_on_the_robot_takes_the_ladar_from_the_robot_profile(
        fake_robot: FakeRobot, tmp_path: Path, robot: str | None) -> None:
    """--robot names the profile whose ladar mount (base_link -> laser) and scan period
    (LaserScan.scan_time) a recording made on hardware uses; without it both are unknown."""
    pytest.importorskip("rosbags")
    from tests.ros.conftest import mcap_doctor, read_rosbags

    record = tmp_path / "r.mcap"
    _run_on_fake(fake_robot, tmp_path, "--record", str(record),
                 *(["--robot", robot] if robot else []))
    mcap_doctor(record)
    msgs: dict[str, list[Any]] = {}
    for m in read_rosbags(record):  # mdle's own types registered from the file
        msgs.setdefault(m.topic, []).append(m.msg)
    assert "/ground_truth" not in msgs and "/map" not in msgs  # no simulation topics
    (static,) = msgs["/tf_static"]
    mount = static.transforms[0].transform.translation
    scans = msgs["/scan"]
    assert scans
    if robot is None:
        assert (mount.x, mount.y) == (0.0, 0.0)
        assert all(s.scan_time == 0.0 and s.time_increment == 0.0 for s in scans)
    else:  # the profile's mount, 17 mm ahead and 8 mm left, and its 10 Hz scans
        assert (mount.x, mount.y) == (0.017, 0.008)
        assert all(s.scan_time == np.float32(0.1) and s.time_increment == 0.0 for s in scans)


def test_mdle_run_cli_reports_a_lost_robot(fake_robot: FakeRobot, tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    from mdle.cli import main

    fake = fake_robot(behaviour="drop", drop_after=0.5)
    plan = tmp_path / "long.mdle"
    plan.write_text("atom fwd = (go(0.2 m/s), never, 10 s)\nrun fwd\n")
    t0 = time.monotonic()
    code = main(["run", str(plan), "--backend", "pioneer", "--connect", fake.url, "--quiet"])
    assert code == 1 and time.monotonic() - t0 < 3.0
    err = capsys.readouterr().err
    assert "lost the robot" in err and err.count(fake.url) == 1  # named once
    assert "Traceback" not in err


def test_mdle_run_cli_robot_not_answering(fake_robot: FakeRobot, tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    from mdle.cli import main

    fake = fake_robot(behaviour="silent")
    plan = tmp_path / "p.mdle"
    plan.write_text("atom fwd = (go(0.2 m/s), never, 1 s)\nrun fwd\n")
    code = main(["run", str(plan), "--backend", "pioneer", "--connect", fake.url, "--quiet"])
    assert code == 1
    assert "no answer from a Pioneer" in capsys.readouterr().err


def _spawn_run(fake: FakeArcos, tmp_path: Path) -> subprocess.Popen[str]:
    import sys

    plan = tmp_path / "long.mdle"
    plan.write_text("atom fwd = (go(0.2 m/s), never, 30 s)\nrun fwd\n")
    return subprocess.Popen(
        [sys.executable, "-m", "mdle", "run", str(plan), "--backend", "pioneer",
         "--connect", fake.url, "--laser", "sim", "--quiet", "--trace",
         str(tmp_path / "run.jsonl")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


@pytest.mark.parametrize("signame", ["SIGTERM", "SIGINT"])
def test_mdle_run_process_stopped_by_a_signal_stops_the_robot(fake_robot: FakeRobot,
                                                              tmp_path: Path,
                                                              signame: str) -> None:
    import signal

    fake = fake_robot()
    proc = _spawn_run(fake, tmp_path)
    try:
        assert fake.wait_for(lambda: fake.v_mm == 200, timeout=15.0), proc.stderr
        proc.send_signal(getattr(signal, signame))
        _, err = proc.communicate(timeout=10.0)
    finally:
        proc.kill()
    assert proc.returncode == 128 + getattr(signal, signame), err
    assert fake.wait_for(lambda: fake.commands(Cmd.CLOSE) != [])
    assert fake.v_mm == 0 and fake.w_deg == 0 and fake.args(Cmd.VEL)[-1] == 0
    # one owner of the signal (mdle's guard, not the driver's own SIGTERM handler): the
    # run stopped at a tick and its trace ends with a record naming the signal
    records = [json.loads(line) for line in (tmp_path / "run.jsonl").read_text().splitlines()]
    end = records[-1]
    assert end["type"] == "end" and signame in end["reason"], end
    stops = fake.commands(Cmd.STOP)
    assert stops and stops[-1].t < fake.commands(Cmd.CLOSE)[-1].t


@pytest.mark.parametrize("serial", [False, True], ids=["tcp", "serial"])
def test_killed_process_leaves_the_robot_to_stop_itself(fake_robot: FakeRobot, tmp_path: Path,
                                                       serial: bool) -> None:
    # TCP: the simulator sees the connection close and ends the session; serial: the
    # line just goes quiet and the firmware watchdog (0.5 s here, 2 s on a robot) trips
    fake = fake_robot(watchdog=0.5, serial=serial)
    if serial:
        fake.url += "?baud=9600"
    proc = _spawn_run(fake, tmp_path)
    try:
        assert fake.wait_for(lambda: fake.v_mm == 200, timeout=15.0)
        proc.kill()  # SIGKILL: no handler, no finally block runs
        proc.communicate(timeout=10.0)
    finally:
        proc.kill()
    assert fake.wait_for(lambda: fake.v_mm == 0, timeout=2.0)
    assert not fake.commands(Cmd.CLOSE)
    assert (fake.watchdog_trips >= 1) if serial else (fake.watchdog_trips == 0)


@pytest.mark.parametrize("waiting_for", ["scan", "sip"])
def test_sigterm_while_connecting_still_stops_and_closes(fake_robot: FakeRobot,
                                                         tmp_path: Path,
                                                         waiting_for: str) -> None:
    # After ENABLE the backend waits for the first SIP (2 s) and scan (3 s); a SIGTERM
    # then used to kill the process outright: exit -15, no STOP, no CLOSE.
    import signal

    fake = fake_robot(send_laser=waiting_for != "scan", send_sips=waiting_for != "sip")
    proc = _spawn_run(fake, tmp_path)
    try:
        assert fake.wait_for(lambda: fake.commands(Cmd.ENABLE) != [], timeout=15.0)
        time.sleep(0.1)  # well inside the wait for the first data
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=10.0)
    finally:
        proc.kill()
    assert proc.returncode == 143, err
    assert fake.wait_for(lambda: fake.commands(Cmd.CLOSE) != [], timeout=2.0)
    stop = fake.commands(Cmd.STOP)
    assert stop and stop[-1].t > fake.commands(Cmd.ENABLE)[0].t
    assert stop[-1].t < fake.commands(Cmd.CLOSE)[-1].t
    assert "interrupted while connecting: robot stopped" in err
    assert "Traceback" not in err


def test_ctrl_c_while_a_robot_never_answers_ends_at_once(fake_robot: FakeRobot,
                                                        tmp_path: Path) -> None:
    # Interrupted in the handshake, mdle said goodbye (STOP, CLOSE) to a robot that had
    # never answered and waited goodbye_timeout for it to hang up. No session was open
    # and the motors were never enabled: it now drops the line at once.
    import signal

    fake = fake_robot(behaviour="silent")
    proc = _spawn_run(fake, tmp_path)
    try:
        assert fake.wait_for(lambda: fake.commands(Cmd.SYNC0, "sync") != [], timeout=15.0)
        time.sleep(0.1)
        sent = time.monotonic()
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=10.0)
        latency = time.monotonic() - sent
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert "interrupted while connecting" in err and "Traceback" not in err
    assert latency < 2.0  # generous: benchmarks/interrupts.py measures the answer
    assert {r.cmd for r in fake.received} == {Cmd.SYNC0}  # no STOP or CLOSE to no one
    from mdle.record.load import read_trace

    trace = read_trace(tmp_path / "run.jsonl")  # whole: header to end record
    assert trace.end is not None and not trace.truncated
