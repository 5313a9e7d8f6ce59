"""PioneerBackend against the fake ARCOS server over TCP and over a pseudo-terminal."""

from __future__ import annotations

import math
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np
import pytest

from mdle.core.backend import Backend, ClockMode, Command, RobotLimits
from mdle.core.errors import BackendError
from mdle.drivers import open_backend
from mdle.drivers.arcos import Cmd
from mdle.drivers.pioneer import PioneerBackend, PioneerOptions

if TYPE_CHECKING:
    from tests.drivers.conftest import FakeArcos

    FakeRobot = Callable[..., FakeArcos]


def _open(connect: str, laser: str | None = None, *, options: PioneerOptions | None = None,
          limits: RobotLimits | None = None) -> PioneerBackend:
    """``open_backend("pioneer", ...)``, checked to be the Pioneer backend."""
    backend = open_backend("pioneer", connect, laser, options=options, limits=limits)
    assert isinstance(backend, PioneerBackend)
    return backend


def _tick(backend: PioneerBackend, cmd: Command, dt: float = 0.05) -> float:
    backend.observe()
    backend.command(cmd)
    return backend.advance(dt)


def test_handshake_sips_and_simulator_laser(fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    fake = fake_robot()
    backend = _open(fake.url, "sim", options=fast)
    try:
        assert isinstance(backend, Backend) and backend.clock is ClockMode.WALL
        assert backend.info.subtype == "p3dx-sh"
        # the handshake in order, then OPEN, motors on, laser on
        sent = [(r.cmd, r.arg) for r in fake.received]
        assert sent[:3] == [(0, None), (1, None), (2, None)]
        assert (Cmd.ENABLE, 1) in sent and (Cmd.SIM_LRF_ENABLE, 1) in sent
        assert fake.commands(Cmd.SIM_LRF_ENABLE)[0].extra == b"\x00"
        before = backend.stats["sips"]
        time.sleep(0.5)
        got = backend.stats["sips"] - before
        assert 3 <= got <= 7  # a SIP every 100 ms
        obs = backend.observe()
        assert obs.motors_enabled and obs.battery == pytest.approx(12.8)
        scan = obs.scan
        assert scan is not None and scan.ranges.shape == (181,)
        assert scan.bearings[0] == pytest.approx(-math.pi / 2)
        assert scan.bearings[1] - scan.bearings[0] == pytest.approx(math.radians(180 / 181))
        assert not scan.valid[:5].any() and scan.valid[5:-5].all()
        assert np.all(scan.ranges[5:-5] > 1.99) and np.all(scan.ranges[5:-5] < 2.01)
        assert 0.0 <= obs.time - scan.stamp < 0.25  # the scan's age
    finally:
        backend.close()


def test_commands_are_clamped_and_converted(fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    fake = fake_robot()
    limits = RobotLimits(max_speed=0.5, max_reverse_speed=0.2, max_turn_rate=math.radians(40))
    backend = _open(fake.url, options=fast, limits=limits)
    try:
        backend.command(Command(2.0, -3.0))
        backend.command(Command(-1.0, 0.1))
        backend.command(Command(0.2, math.radians(-15)))
        assert fake.wait_for(lambda: len(fake.commands(Cmd.RVEL)) >= 3)
        assert fake.args(Cmd.VEL)[:3] == [500, -200, 200]
        assert fake.args(Cmd.RVEL)[:3] == [-40, 6, -15]
        with pytest.raises(BackendError, match="non-finite"):
            backend.command(Command(float("nan"), 0.0))
        assert fake.wait_for(lambda: fake.args(Cmd.VEL)[-1] == 0)  # stopped on the way out
    finally:
        backend.close()


def test_odometry_units_per_model(fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    fake = fake_robot(subtype="p3dx")  # 0.485 mm per position unit
    backend = _open(fake.url, options=replace(fast, odometry_origin="robot"))
    try:
        assert backend.params.dist_conv == 0.485
        fake.pose_mm = [505.0, -250.0, math.radians(90)]
        time.sleep(0.25)
        obs = backend.observe()
        assert obs.pose.x == pytest.approx(0.505, abs=0.002)
        assert obs.pose.y == pytest.approx(-0.250, abs=0.002)
        assert obs.pose.theta == pytest.approx(math.pi / 2, abs=0.002)
    finally:
        backend.close()


def test_odometry_starts_at_the_pose_at_connect(fake_robot: FakeRobot,
                                                fast: PioneerOptions) -> None:
    fake = fake_robot()
    fake.pose_mm = [3000.0, -1000.0, math.radians(30)]  # counters left by an earlier run
    start = _open(fake.url, options=fast)
    robot = _open(fake_robot(pose_mm=[3000.0, -1000.0, 0.5]).url,
                         options=replace(fast, odometry_origin="robot"))
    try:
        first = start.observe().pose
        assert (first.x, first.y, first.theta) == pytest.approx((0.0, 0.0, 0.0))
        theirs = robot.observe().pose
        assert (theirs.x, theirs.y, theirs.theta) == pytest.approx((3.0, -1.0, 0.5), abs=2e-3)
    finally:
        start.close()
        robot.close()


def test_model_override_from_the_url(fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    fake = fake_robot(subtype="p3dx")
    backend = _open(fake.url + "?model=p3dx-sh&max_speed=0.3", options=fast)
    try:
        assert backend.params.dist_conv == 1.0 and backend.limits.max_speed == 0.3
    finally:
        backend.close()
    with pytest.raises(BackendError, match="unknown option `speed`"):
        open_backend("pioneer", fake.url + "?speed=1", options=fast)
    with pytest.raises(BackendError, match="unknown Pioneer model `p9`; known: p2de"):
        open_backend("pioneer", fake.url + "?model=p9", options=fast)
    with pytest.raises(BackendError, match="`max_speed` must be a number"):
        open_backend("pioneer", fake.url + "?max_speed=fast", options=fast)


def test_robot_drives_and_odometry_follows(fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    fake = fake_robot()
    backend = _open(fake.url, options=fast)
    try:
        t0 = time.monotonic()
        while time.monotonic() - t0 < 0.6:
            _tick(backend, Command(0.4, 0.0))
        obs = backend.observe()
        assert obs.v == pytest.approx(0.4)
        assert 0.12 < obs.pose.x < 0.32  # 0.4 m/s for ~0.5 s of SIPs
    finally:
        backend.close()
    assert fake.wait_for(lambda: fake.v_mm == 0.0)


def test_keepalive_holds_the_watchdog_and_deadman_stops_a_silent_runtime(
        fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    fake = fake_robot(watchdog=0.3)
    backend = _open(fake.url, options=fast)
    try:
        backend.command(Command(0.3, 0.0))
        assert fake.wait_for(lambda: fake.v_mm == 300)
        # the runtime goes silent: the backend stops the robot itself after 0.4 s ...
        assert fake.wait_for(lambda: fake.v_mm == 0.0, timeout=1.5)
        stopped_at = fake.commands(Cmd.VEL)[-1].t
        assert stopped_at - fake.commands(Cmd.VEL)[0].t == pytest.approx(0.4, abs=0.15)
        assert backend.stats["deadman_stops"] == 1
        # ... and PULSEs keep the firmware watchdog (0.3 s here) from ever tripping
        time.sleep(0.8)
        assert fake.watchdog_trips == 0
        pulses = [r.t for r in fake.commands(Cmd.PULSE) if r.t > stopped_at]
        assert len(pulses) >= 5 and max(np.diff(pulses)) < 0.3
        backend.observe()  # still connected and fresh
    finally:
        backend.close()


def test_without_keepalive_the_watchdog_would_trip(fake_robot: FakeRobot,
                                                   fast: PioneerOptions) -> None:
    # the control experiment for the test above: the fake's watchdog does trip on silence
    fake = fake_robot(watchdog=0.3)
    backend = _open(fake.url, options=replace(fast, keepalive=10.0))
    try:
        time.sleep(0.8)
        assert fake.watchdog_trips >= 1
    finally:
        backend.close()


def test_advance_waits_for_the_deadline_and_reports_lateness(fake_robot: FakeRobot,
                                                             fast: PioneerOptions) -> None:
    fake = fake_robot()
    backend = _open(fake.url, options=fast)
    try:
        dt = 0.05
        t0 = time.monotonic()
        lateness = [_tick(backend, Command(0.1, 0.0), dt) for _ in range(6)]
        elapsed = time.monotonic() - t0
        assert elapsed == pytest.approx(6 * dt, abs=0.04)
        assert max(lateness) < 0.03
        # a slow tick: the work takes 80 ms of a 50 ms period
        backend.observe()
        time.sleep(0.08)
        start = time.monotonic()
        late = backend.advance(dt)
        assert late >= 0.025 and time.monotonic() - start < 0.01  # no wait when late
        # the next tick starts on a fresh grid: on time again
        assert _tick(backend, Command(0.1, 0.0), dt) < 0.03
    finally:
        backend.close()


def test_lost_connection_mid_run_ends_with_clear_error(fake_robot: FakeRobot,
                                                       fast: PioneerOptions) -> None:
    fake = fake_robot(behaviour="drop", drop_after=0.3)
    backend = _open(fake.url, "sim", options=fast)
    t0 = time.monotonic()
    with pytest.raises(BackendError, match=r"lost the robot .*closed the connection"):
        while time.monotonic() - t0 < 3.0:
            _tick(backend, Command(0.2, 0.0), 0.1)
    assert time.monotonic() - t0 < 0.8  # noticed within a tick or two
    backend.close()
    backend.close()  # idempotent
    with pytest.raises(BackendError, match="closed"):
        backend.command(Command(0.1, 0.0))
    with pytest.raises(BackendError, match="closed"):
        backend.observe()
    backend.stop()  # harmless after close


def test_robot_that_never_answers(fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    fake = fake_robot(behaviour="silent")
    t0 = time.monotonic()
    with pytest.raises(BackendError, match=r"no answer from a Pioneer .* after 2 handshake "
                                           r"attempt\(s\) \(no reply to SYNC0\)"):
        open_backend("pioneer", fake.url, options=fast)
    assert time.monotonic() - t0 < 1.0
    assert len(fake.commands(Cmd.SYNC0, "sync")) == 2


def test_nothing_listening_is_a_clear_error() -> None:
    import socket

    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    with pytest.raises(BackendError, match=r"cannot connect to tcp://127.0.0.1:\d+"):
        open_backend("pioneer", f"tcp://127.0.0.1:{port}")


def test_close_stops_and_ends_the_session(fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    fake = fake_robot()
    backend = _open(fake.url, "sim", options=fast)
    backend.command(Command(0.3, 0.5))
    assert fake.wait_for(lambda: fake.v_mm == 300)
    backend.close()
    assert fake.wait_for(lambda: fake.commands(Cmd.CLOSE) != [])
    # STOP and zero speeds, keep-alives while a SIP confirms the stop, laser off, CLOSE
    sent = [(r.cmd, r.arg) for r in fake.received]
    stop = max(i for i, c in enumerate(sent) if c == (Cmd.STOP, None))
    assert sent[stop:stop + 3] == [(Cmd.STOP, None), (Cmd.VEL, 0), (Cmd.RVEL, 0)]
    assert sent[-2:] == [(Cmd.SIM_LRF_ENABLE, 0), (Cmd.CLOSE, None)]
    assert set(sent[stop + 3:-2]) <= {(Cmd.PULSE, None)}
    assert backend.goodbye == "stopped"
    assert fake.v_mm == 0 and fake.w_deg == 0
    backend.close()
    assert len(fake.commands(Cmd.CLOSE)) == 1


def test_stale_scan_ends_the_run(fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    fake = fake_robot()
    backend = _open(fake.url, "sim", options=fast)
    try:
        backend.observe()
        backend.command(Command(0.2, 0.0))
        fake.send_laser = False
        time.sleep(0.7)
        with pytest.raises(BackendError, match=r"laser scan is 0\.\d+ s old \(limit 0\.50 s\)"):
            backend.observe()
        assert fake.wait_for(lambda: fake.v_mm == 0)  # stopped before raising
    finally:
        backend.close()


def test_silent_robot_mid_run_ends_the_run(fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    fake = fake_robot()
    backend = _open(fake.url, options=fast)
    try:
        backend.observe()
        fake.send_sips = False
        time.sleep(0.7)
        with pytest.raises(BackendError, match="sent no data for"):
            backend.observe()
    finally:
        backend.close()


def test_no_laser_packets_is_a_clear_error_at_connect(fake_robot: FakeRobot,
                                                      fast: PioneerOptions) -> None:
    fake = fake_robot(send_laser=False)
    with pytest.raises(BackendError, match="no laser scan within 1.0 s"):
        open_backend("pioneer", fake.url, "sim", options=fast)
    assert fake.wait_for(lambda: fake.commands(Cmd.CLOSE) != [])


def test_corrupted_stream_resynchronises(fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    fake = fake_robot(corrupt_every=10)
    backend = _open(fake.url, "sim", options=replace(fast, max_scan_age=1.0))
    try:
        time.sleep(1.0)
        obs = backend.observe()
        stats = backend.stats
        assert stats["rejected"] > 0 and stats["sips"] >= 4
        assert obs.scan is not None
    finally:
        backend.close()


def test_session_left_open_is_closed_and_reopened(fake_robot: FakeRobot,
                                                  fast: PioneerOptions) -> None:
    fake = fake_robot(open_session=True)
    backend = _open(fake.url, options=fast)
    try:
        first_close = fake.commands(Cmd.CLOSE)[0].t  # the stale session was closed first
        assert first_close < fake.commands(Cmd.ENABLE)[0].t
        backend.observe()
    finally:
        backend.close()


def test_serial_line_over_a_pty_with_baud_probing(fake_robot: FakeRobot,
                                                  fast: PioneerOptions) -> None:
    fake = fake_robot(serial=True, baud=115200)
    url = f"serial://{fake.device}"  # no baud: probe 9600, then 115200
    backend = _open(url, "sim", options=replace(fast, sync_retries=1))
    try:
        assert backend.info.subtype == "p3dx-sh"
        assert "115200" in backend._transport.description
        for _ in range(3):
            _tick(backend, Command(0.2, 0.1), 0.1)
        assert fake.wait_for(lambda: 200 in fake.args(Cmd.VEL))
        assert backend.observe().scan is not None
    finally:
        backend.close()
    assert fake.wait_for(lambda: fake.commands(Cmd.CLOSE) != [])


def test_serial_line_dropped_mid_run(fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    fake = fake_robot(serial=True)
    backend = _open(fake.url + "?baud=9600", options=fast)
    try:
        backend.observe()
        fake.drop()
        t0 = time.monotonic()
        with pytest.raises(BackendError, match="lost the robot|sent no data"):
            while time.monotonic() - t0 < 2.0:
                _tick(backend, Command(0.1, 0.0), 0.1)
    finally:
        backend.close()


def test_serial_without_pyserial_names_the_extra(monkeypatch: pytest.MonkeyPatch,
                                                 fake_robot: FakeRobot,
                                                 fast: PioneerOptions) -> None:
    fake = fake_robot(serial=True)
    monkeypatch.setitem(sys.modules, "serial", None)
    with pytest.raises(BackendError, match=r"pip install 'mdle\[serial\]'"):
        open_backend("pioneer", fake.url + "?baud=9600", options=fast)


@pytest.mark.parametrize("url,message", [
    ("http://x", "expected tcp://HOST:PORT"),
    ("tcp://:8101", "no host"),
    ("tcp://h:99999", "port is not a number"),
    ("serial://", "no device"),
    ("serial:///dev/x?baud=fast", "baud `fast` is not a whole number"),
    ("sim", "a Pioneer is reached at"),
])
def test_bad_connect_urls(url: str, message: str) -> None:
    with pytest.raises(BackendError, match=message):
        open_backend("pioneer", url)


def test_bad_laser_and_kind() -> None:
    with pytest.raises(BackendError, match="unknown hardware backend `roomba`"):
        open_backend("roomba", "tcp://localhost:8101")
    with pytest.raises(BackendError, match="expected `sim` or lms200"):
        open_backend("pioneer", "tcp://localhost:8101", "tcp://localhost:1")


@pytest.fixture
def default_sigterm() -> Iterator[None]:
    """SIGTERM unhandled (SIG_DFL) for the test, as in a program that never set it."""
    old = signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


def test_sigterm_becomes_system_exit_while_connected(fake_robot: FakeRobot,
                                                     fast: PioneerOptions,
                                                     default_sigterm: None) -> None:
    assert threading.current_thread() is threading.main_thread()
    before = signal.getsignal(signal.SIGTERM)
    fake = fake_robot()
    backend = _open(fake.url, options=replace(fast, handle_sigterm=True))
    try:
        handler = signal.getsignal(signal.SIGTERM)
        assert callable(handler) and handler is not before
        backend.command(Command(0.3, 0.0))
        with pytest.raises(SystemExit) as info:
            handler(signal.SIGTERM, None)
        assert info.value.code == 143
    finally:
        backend.close()  # what the runtime's finally block does
    assert signal.getsignal(signal.SIGTERM) is before
    assert fake.wait_for(lambda: fake.v_mm == 0 and fake.commands(Cmd.CLOSE) != [])


def test_a_sigterm_handler_already_there_stays_the_one_owner(fake_robot: FakeRobot,
                                                             fast: PioneerOptions) -> None:
    """Under mdle's command line its SignalGuard owns SIGTERM: the driver leaves it so,
    and the guard's Interrupted still ends in the driver's goodbye (stop, then CLOSE)."""
    from mdle.console.signals import Interrupted, SignalGuard

    guard = SignalGuard().install(deferred=False)
    try:
        owner = signal.getsignal(signal.SIGTERM)
        fake = fake_robot()
        backend = _open(fake.url, options=replace(fast, handle_sigterm=True))
        try:
            assert signal.getsignal(signal.SIGTERM) is owner   # not replaced
            backend.command(Command(0.3, 0.0))
            assert fake.wait_for(lambda: fake.v_mm == 300)
            with pytest.raises(Interrupted) as info:
                signal.raise_signal(signal.SIGTERM)
                time.sleep(1.0)   # the handler runs between bytecodes: never gets here
            assert info.value.signum == signal.SIGTERM
        finally:
            backend.close()   # what the runtime's finally block does
        assert signal.getsignal(signal.SIGTERM) is owner       # still the guard's
    finally:
        guard.restore()
    assert fake.wait_for(lambda: fake.v_mm == 0 and fake.commands(Cmd.CLOSE) != [])
    stop = fake.commands(Cmd.STOP)
    assert stop and stop[-1].t < fake.commands(Cmd.CLOSE)[-1].t


def test_random_commands_arrive_clamped_and_rounded(fake_robot: FakeRobot,
                                                    fast: PioneerOptions) -> None:
    from hypothesis import given, settings
    from hypothesis import strategies as st

    fake = fake_robot()
    backend = _open(fake.url, options=fast)
    lim = backend.limits
    finite = st.floats(-10.0, 10.0, allow_nan=False)

    @settings(max_examples=40, deadline=None, database=None)
    @given(v=finite, w=finite)
    def check(v: float, w: float) -> None:
        n = len(fake.commands(Cmd.RVEL))
        backend.command(Command(v, w))
        assert fake.wait_for(lambda: len(fake.commands(Cmd.RVEL)) > n)
        want_v = round(min(max(v, -lim.max_reverse_speed), lim.max_speed) * 1000)
        want_w = round(math.degrees(min(max(w, -lim.max_turn_rate), lim.max_turn_rate)))
        assert fake.args(Cmd.VEL)[-1] == want_v and fake.args(Cmd.RVEL)[-1] == want_w
        assert abs(want_v) <= 750 and abs(want_w) <= 100

    try:
        check()
    finally:
        backend.close()


def test_simulator_laser_options(fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    fake = fake_robot()
    fake.scan_mm = lambda i: np.full(181, 8000)
    backend = _open(fake.url, "sim?max_range=8", options=fast)
    try:
        scan = backend.observe().scan
        assert scan is not None and scan.max_range == 8.0 and not scan.valid.any()
    finally:
        backend.close()
    with pytest.raises(BackendError, match="unknown option\\(s\\) fov; known: max_range"):
        open_backend("pioneer", fake.url, "sim?fov=90", options=fast)
    with pytest.raises(BackendError, match=r"`max_range` must be a number of m in \[0.1, "):
        open_backend("pioneer", fake.url, "sim?max_range=far", options=fast)
