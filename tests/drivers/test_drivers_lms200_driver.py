"""Lms200Driver against the fake LMS-200 on a pseudo-terminal."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np
import pytest

from mdle.core.backend import Command, Scan
from mdle.core.errors import BackendError
from mdle.drivers import open_backend
from mdle.drivers.lms200_driver import Lms200Driver, Lms200Options
from mdle.drivers.pioneer import PioneerBackend, PioneerOptions
from mdle.drivers.transport import SerialTransport

if TYPE_CHECKING:
    from tests.drivers.conftest import FakeArcos, FakeLms200

    FakeRobot = Callable[..., FakeArcos]
    FakeLms = Callable[..., FakeLms200]


def _wait_scan(driver: Lms200Driver, timeout: float = 1.0) -> Scan:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        scan = driver.latest()
        if scan is not None:
            return scan
        time.sleep(0.01)
    raise AssertionError("no scan")


def test_probe_switch_baud_and_stream(fake_lms: FakeLms, fast_lms: Lms200Options) -> None:
    fake = fake_lms(baud=9600)  # just powered up
    driver = Lms200Driver(SerialTransport(fake.device, 9600), replace(fast_lms, baud=38400))
    try:
        assert driver.baud == 38400 and fake.baud == 38400 and fake.streaming
        cmds = [c for c, _ in fake.received]
        # stop request found the rate, then baud switch, status check, continuous mode
        assert cmds[0] == 0x20 and fake.received[0][1] == b"\x25"
        assert (0x20, b"\x40") in fake.received and 0x31 in cmds
        assert fake.received[-1] == (0x20, b"\x24")
        scan = _wait_scan(driver)
        assert scan.ranges.shape == (181,)
        assert scan.bearings[0] == pytest.approx(-math.pi / 2)
        assert scan.bearings[-1] == pytest.approx(math.pi / 2)
        assert not scan.valid[0] and not scan.valid[1] and scan.valid[2:].all()
        assert scan.ranges[0] == pytest.approx(8.183)
        assert np.all(np.abs(scan.ranges[2:] - 1.5) < 0.01)
        assert time.monotonic() - scan.stamp < 0.3
        first = driver.scans
        time.sleep(0.3)
        assert driver.scans - first >= 3  # a scan every 50 ms
    finally:
        driver.close()
    deadline = time.monotonic() + 1.0
    while fake.received[-1] != (0x20, b"\x25") and time.monotonic() < deadline:
        time.sleep(0.01)
    assert fake.received[-1] == (0x20, b"\x25")  # streaming stopped on close


def test_scanner_already_streaming_at_the_target_rate(fake_lms: FakeLms,
                                                      fast_lms: Lms200Options) -> None:
    fake = fake_lms(baud=38400, streaming=True)
    driver = Lms200Driver(SerialTransport(fake.device, 9600), fast_lms)
    try:
        assert (0x20, b"\x40") not in fake.received  # no switch needed
        _wait_scan(driver)
    finally:
        driver.close()


def test_probe_finds_500k(fake_lms: FakeLms, fast_lms: Lms200Options) -> None:
    fake = fake_lms(baud=500000)
    driver = Lms200Driver(SerialTransport(fake.device, 9600), replace(fast_lms, baud=9600))
    try:
        assert fake.baud == 9600 and driver.baud == 9600
        _wait_scan(driver)
    finally:
        driver.close()


def test_nak_is_retried(fake_lms: FakeLms, fast_lms: Lms200Options) -> None:
    fake = fake_lms(baud=38400, nak_first=True)
    driver = Lms200Driver(SerialTransport(fake.device, 38400), fast_lms)
    try:
        _wait_scan(driver)
        assert [c for c, _ in fake.received][:2] == [0x20, 0x20]
    finally:
        driver.close()


def test_corrupted_telegrams_are_dropped_and_the_stream_recovers(fake_lms: FakeLms,
                                                                 fast_lms: Lms200Options) -> None:
    fake = fake_lms(baud=38400, corrupt_every=2)
    driver = Lms200Driver(SerialTransport(fake.device, 38400), fast_lms)
    try:
        _wait_scan(driver)
        time.sleep(0.5)
        assert driver.failure() is None
        sent = fake.scans_sent
        assert sent // 2 - 2 <= driver.scans <= sent - sent // 2 + 1
        assert driver._reader.rejected > 0
    finally:
        driver.close()


def test_no_scanner_is_a_clear_error(fake_lms: FakeLms, fast_lms: Lms200Options) -> None:
    fake = fake_lms(silent=True)
    t0 = time.monotonic()
    with pytest.raises(BackendError, match=r"no answer from an LMS-200 on .* \(tried 38400, "
                                           r"9600, 19200, 500000 baud\)"):
        Lms200Driver(SerialTransport(fake.device, 9600), fast_lms)
    assert time.monotonic() - t0 < 2.0


def test_unplugged_scanner_is_reported(fake_lms: FakeLms, fast_lms: Lms200Options) -> None:
    fake = fake_lms(baud=38400)
    driver = Lms200Driver(SerialTransport(fake.device, 38400), fast_lms)
    try:
        _wait_scan(driver)
        fake.drop()
        deadline = time.monotonic() + 1.0
        while driver.failure() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        assert driver.failure() is not None
    finally:
        driver.close()


def test_pioneer_with_an_lms200_laser(fake_robot: FakeRobot, fake_lms: FakeLms,
                                      fast: PioneerOptions, fast_lms: Lms200Options) -> None:
    robot = fake_robot()
    laser = fake_lms(baud=9600)
    backend = open_backend("pioneer", robot.url, laser.url + "?baud=38400", options=fast,
                           laser_options=fast_lms)
    try:
        assert robot.laser_mode == 0  # the simulator laser stays off
        obs = backend.observe()
        assert obs.scan is not None and obs.scan.ranges.shape == (181,)
        assert 0.0 <= obs.time - obs.scan.stamp < 0.3
        backend.command(Command(0.1, 0.0))
        # the laser unplugged mid-run ends the run
        laser.drop()
        time.sleep(0.2)
        with pytest.raises(BackendError, match="lost the laser"):
            backend.observe()
        assert robot.wait_for(lambda: robot.v_mm == 0)
    finally:
        backend.close()


def test_variant_100_degrees_quarter_degree(fake_lms: FakeLms, fast_lms: Lms200Options) -> None:
    fake = fake_lms(baud=38400, count=401)
    driver = Lms200Driver(SerialTransport(fake.device, 38400),
                          replace(fast_lms, variant=(100, 25)))
    try:
        assert (0x3B, bytes.fromhex("64 00 19 00")) in fake.received
        scan = _wait_scan(driver)
        assert scan.ranges.shape == (401,)
        assert scan.bearings[0] == pytest.approx(math.radians(-50))
        assert scan.bearings[1] - scan.bearings[0] == pytest.approx(math.radians(0.25))
    finally:
        driver.close()


def test_slow_lms_line_widens_the_scan_age_limit(fake_robot: FakeRobot, fake_lms: FakeLms,
                                                 fast: PioneerOptions,
                                                 fast_lms: Lms200Options) -> None:
    robot = fake_robot()
    laser = fake_lms(baud=9600, period=0.4)  # a 181-value scan takes 0.39 s at 9600 baud
    backend = open_backend("pioneer", robot.url, laser.url + "?baud=9600", options=fast,
                           laser_options=fast_lms)
    try:
        assert isinstance(backend, PioneerBackend)
        assert backend._max_scan_age == pytest.approx(2.5 * 372 * 10 / 9600)
        t0 = time.monotonic()
        while time.monotonic() - t0 < 1.2:  # scans 0.4 s apart never count as stale
            backend.observe()
            backend.advance(0.1)
    finally:
        backend.close()
