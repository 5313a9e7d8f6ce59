"""The Pioneer backend's goodbye: stop, wait for a SIP showing the wheels stopped, CLOSE,
and end the stream so that even a server that reads slowly gets every byte."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING

from mdle.core.backend import Command
from mdle.drivers import open_backend
from mdle.drivers.arcos import Cmd
from mdle.drivers.pioneer import PioneerBackend, PioneerOptions

if TYPE_CHECKING:
    from tests.drivers.conftest import FakeArcos

    FakeRobot = Callable[..., FakeArcos]


def _driving(fake: FakeArcos, fast: PioneerOptions, laser: str | None = None
             ) -> PioneerBackend:
    backend = open_backend("pioneer", fake.url, laser, options=fast)
    assert isinstance(backend, PioneerBackend)
    backend.command(Command(0.3, 0.2))
    assert fake.wait_for(lambda: fake.v_mm == 300, timeout=3.0)
    return backend


def _tail(fake: FakeArcos) -> list[tuple[int, object]]:
    """The session's commands from the last STOP on, PULSEs left out."""
    sent = [(r.cmd, r.arg) for r in fake.received if r.phase == "session"]
    stop = max(i for i, c in enumerate(sent) if c == (Cmd.STOP, None))
    return [c for c in sent[stop:] if c != (Cmd.PULSE, None)]


def test_a_slow_reader_gets_the_stop_and_the_close(fake_robot: FakeRobot,
                                                   fast: PioneerOptions) -> None:
    # The server reads its input only every 0.25 s while it keeps writing SIPs, and, as
    # AMRISim did, gives up at the first failed write. Closing the socket at once with
    # SIPs unread resets the connection, so its next SIP write failed before it ever
    # read the final STOP and CLOSE.
    fake = fake_robot(read_every=0.25)
    backend = _driving(fake, replace(fast, sync_timeout=0.6), "sim")
    backend.close()
    assert fake.wait_for(lambda: fake.client_gone or fake.write_failed, timeout=3.0)
    assert not fake.write_failed, "the server's write failed: the connection was reset"
    assert _tail(fake) == [(Cmd.STOP, None), (Cmd.VEL, 0), (Cmd.RVEL, 0),
                           (Cmd.SIM_LRF_ENABLE, 0), (Cmd.CLOSE, None)]
    assert fake.v_mm == 0 and fake.w_deg == 0


def test_close_waits_for_a_sip_showing_the_wheels_stopped(fake_robot: FakeRobot,
                                                          fast: PioneerOptions) -> None:
    fake = fake_robot(stop_lag=0.3)  # the wheels ramp down for 0.3 s
    backend = _driving(fake, fast)
    backend.close()
    assert backend.goodbye == "stopped"
    stop = fake.commands(Cmd.STOP)[-1].t
    close = fake.commands(Cmd.CLOSE)[-1].t
    assert 0.3 <= close - stop < 0.55  # after the ramp, before the bound
    assert _tail(fake) == [(Cmd.STOP, None), (Cmd.VEL, 0), (Cmd.RVEL, 0), (Cmd.CLOSE, None)]


def test_close_waits_for_the_wheels_to_ramp_down_at_the_robots_deceleration(
        fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    # The robot brakes at its limit, 0.3 m/s^2 (a P3-DX's), so from 0.3 m/s its wheels
    # turn for 1 s: a fixed 0.5 s wait sent CLOSE at about 150 mm/s.
    fake = fake_robot(decel_mm=300.0)
    backend = _driving(fake, fast)
    assert backend.limits.max_decel == 0.3
    backend.close()
    assert backend.goodbye == "stopped"
    stop = fake.commands(Cmd.STOP)[-1].t
    close = fake.commands(Cmd.CLOSE)[-1].t
    assert 0.95 <= close - stop < 0.5 + 1.0  # after the ramp, within the bound
    assert fake.v_mm == 0


def test_the_wait_is_bounded_when_the_wheels_never_stop(fake_robot: FakeRobot,
                                                        fast: PioneerOptions) -> None:
    fake = fake_robot(ignore_stop=True)
    backend = _driving(fake, replace(fast, goodbye_timeout=0.3))
    # the bound: 0.3 s, plus the stop at the limits from 0.3 m/s and 0.2 rad/s
    ramp = max(0.3 / backend.limits.max_decel, 0.2 / backend.limits.max_turn_accel)
    t0 = time.monotonic()
    backend.close()
    took = time.monotonic() - t0
    assert backend.goodbye == "not confirmed"
    assert 0.3 + ramp <= took < 0.3 + ramp + 1.0  # the wait, then at most the stream's bound
    assert fake.wait_for(lambda: fake.commands(Cmd.CLOSE) != [])
    assert _tail(fake)[-1] == (Cmd.CLOSE, None)


def test_a_server_that_vanishes_mid_goodbye(fake_robot: FakeRobot,
                                            fast: PioneerOptions) -> None:
    fake = fake_robot(vanish_on_stop=True)
    backend = _driving(fake, fast, "sim")
    t0 = time.monotonic()
    backend.close()  # never raises
    assert time.monotonic() - t0 < 1.0
    assert backend.goodbye == "link lost"
    assert fake.commands(Cmd.STOP) and not fake.commands(Cmd.CLOSE)
    backend.close()  # idempotent


def test_a_link_already_gone_closes_at_once(fake_robot: FakeRobot,
                                            fast: PioneerOptions) -> None:
    fake = fake_robot()
    backend = _driving(fake, fast)
    fake.drop()
    assert backend._lost.wait(2.0)
    t0 = time.monotonic()
    backend.close()
    assert time.monotonic() - t0 < 0.5
    assert backend.goodbye == "link lost"


def test_the_goodbye_over_a_serial_line(fake_robot: FakeRobot, fast: PioneerOptions) -> None:
    fake = fake_robot(serial=True)
    backend = open_backend("pioneer", fake.url + "?baud=9600", options=fast)
    assert isinstance(backend, PioneerBackend)
    backend.command(Command(0.2, 0.0))
    assert fake.wait_for(lambda: fake.v_mm == 200)
    backend.close()
    assert backend.goodbye == "stopped"
    assert fake.wait_for(lambda: fake.commands(Cmd.CLOSE) != [])
    assert _tail(fake) == [(Cmd.STOP, None), (Cmd.VEL, 0), (Cmd.RVEL, 0), (Cmd.CLOSE, None)]
