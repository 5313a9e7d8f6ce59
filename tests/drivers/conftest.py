"""Fake hardware for the driver tests: an ARCOS server and a SICK LMS-200.

Both speak their protocol over real byte streams: the ARCOS fake over a TCP socket on
127.0.0.1 or over a pseudo-terminal pair (the serial path), the LMS-200 fake over a
pseudo-terminal. Each runs in its own thread, records what it received and can
misbehave on request (stay silent, drop the link, corrupt bytes, pause data). Tests get
them through fixtures (pytest runs with ``--import-mode=importlib``).
"""

from __future__ import annotations

import math
import os
import select
import socket
import termios
import threading
import time
import tty
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import TypeVar

import numpy as np
import pytest

from mdle.drivers import arcos, arcos_laser, lms200
from mdle.drivers.arcos import Cmd
from mdle.drivers.lms200_driver import Lms200Options
from mdle.drivers.pioneer import PioneerOptions

#: Short timeouts so every test stays fast.
FAST = PioneerOptions(sync_timeout=0.15, sync_retries=2, first_sip_timeout=1.0,
                      sip_timeout=0.5, first_scan_timeout=1.0, max_scan_age=0.5,
                      keepalive=0.1, command_timeout=0.4, poll=0.01)
FAST_LMS = Lms200Options(reply_timeout=0.2, mode_timeout=0.3, retries=2, poll=0.01)

#: What AMRISim sends for a laser beam without a return (mm).
NO_RETURN_MM = 32767

_BAUD_CONST = {9600: termios.B9600, 19200: termios.B19200, 38400: termios.B38400,
               115200: termios.B115200, 500000: getattr(termios, "B500000", -1)}


class _Link:
    """One end of a byte stream for a fake: a socket or a pty master."""

    def __init__(self, sock: socket.socket | None = None, fd: int | None = None) -> None:
        self.sock, self.fd = sock, fd
        self.closed = False

    def fileno(self) -> int:
        if self.sock is not None:
            return self.sock.fileno()
        assert self.fd is not None, "a link has a socket or a file descriptor"
        return self.fd

    def recv(self, timeout: float) -> bytes | None:
        """Bytes, ``b""`` on timeout, None when the peer has gone."""
        if self.closed:
            return None
        try:
            ready, _, _ = select.select([self.fileno()], [], [], timeout)
            if not ready:
                return b""
            data = self.sock.recv(65536) if self.sock is not None else os.read(self.fileno(), 65536)
        except OSError:
            return None
        return data or None

    def send(self, data: bytes) -> bool:
        if self.closed:
            return False
        try:
            if self.sock is not None:
                self.sock.sendall(data)
            else:
                os.write(self.fileno(), data)
            return True
        except OSError:
            return False

    def baud(self) -> int | None:
        """The rate the client set on the pty (None on a socket)."""
        if self.fd is None:
            return None
        speed = termios.tcgetattr(self.fd)[5]
        return next((b for b, c in _BAUD_CONST.items() if c == speed), None)

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        try:
            if self.sock is not None:
                self.sock.shutdown(socket.SHUT_RDWR)
                self.sock.close()
            elif self.fd is not None:
                os.close(self.fd)
        except OSError:
            pass


def _open_pty() -> tuple[int, int, str]:
    """A raw pty pair: master fd, slave fd (held open so the master never reads EIO
    before the client opens the device by name), device name."""
    master, slave = os.openpty()
    tty.setraw(master)
    return master, slave, os.ttyname(slave)


def _close_fd(fd: int) -> None:
    try:
        os.close(fd)
    except OSError:
        pass


@dataclass
class Received:
    """A command the fake received: time (s since the fake started), number, argument."""

    t: float
    cmd: int
    arg: int | bytes | None
    extra: bytes = b""
    phase: str = "session"
    """``sync`` during the handshake (where 0, 1, 2 are SYNC0..2), else ``session``."""


@dataclass
class FakeArcos:
    """An ARCOS server: handshake, SIPs every ``sip_period``, simulator laser packets.

    ``behaviour``: ``"normal"``, ``"silent"`` (never answers), ``"drop"`` (closes the
    link ``drop_after`` seconds after OPEN). ``baud`` (pty only): answer only when the
    client's line runs at this rate. ``open_session``: SIPs are already flowing when
    the client arrives (a session left open by a crashed client).
    """

    subtype: str = "p3dx-sh"
    behaviour: str = "normal"
    drop_after: float = 0.5
    sip_period: float = 0.1
    watchdog: float = 2.0
    serial: bool = False
    baud: int | None = None
    open_session: bool = False
    corrupt_every: int = 0
    scan_mm: Callable[[int], np.ndarray] | None = None
    received: list[Received] = field(default_factory=list)
    watchdog_trips: int = 0
    sips_sent: int = 0
    scans_sent: int = 0
    laser_mode: int = 0
    send_laser: bool = True
    send_sips: bool = True
    read_every: float = 0.0
    """Read the client's bytes only this often (a server busy elsewhere), while SIPs go
    out on time; like AMRISim, a failed write ends the session before reading more."""
    stop_lag: float = 0.0
    """The wheels keep turning this long after STOP or zero velocities (a ramp down)."""
    decel_mm: float = 0.0
    """With a zero command the wheels ramp down at this rate (mm/s^2; the turn rate stops
    at once), reported SIP by SIP as the firmware does; 0: they stop at once."""
    ignore_stop: bool = False
    """Never stop the wheels (a robot that does not obey: the goodbye must not hang)."""
    vanish_on_stop: bool = False
    """Cut the link the moment a STOP arrives (the robot switched off mid-goodbye)."""
    write_failed: bool = False
    """A write to the client failed (it reset the connection)."""
    client_gone: bool = False
    """The client's end of stream (or reset) was read."""
    pose_mm: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])  # x, y, theta rad
    v_mm: float = 0.0
    w_deg: float = 0.0
    motors: bool = False

    def __post_init__(self) -> None:
        self.t0 = time.monotonic()
        self._halt = threading.Event()
        self._stop_due: float | None = None
        self._ramp_from: tuple[float, float] | None = None  # (speed mm/s, when) of a ramp down
        self.link: _Link | None = None
        self.dist_conv = arcos.robot_params(self.subtype).dist_conv
        if self.serial:
            self._master, self._slave, self.device = _open_pty()
            self.url = f"serial://{self.device}" + (f"?baud={self.baud}" if self.baud else "")
            self.link = _Link(fd=self._master)
            target = self._serve
        else:
            self._server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            self._server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            self._server.bind(("127.0.0.1", 0))
            self._server.listen(1)
            self._server.settimeout(0.05)  # here: stop() may close it before the thread runs
            self.port = self._server.getsockname()[1]
            self.url = f"tcp://127.0.0.1:{self.port}"
            target = self._accept
        self._thread = threading.Thread(target=target, daemon=True)
        self._thread.start()

    # -------------------------------------------------------------- queries for tests

    def commands(self, cmd: int, phase: str = "session") -> list[Received]:
        """What arrived with number ``cmd`` in the handshake or the session."""
        return [r for r in list(self.received) if r.cmd == cmd and r.phase == phase]

    def args(self, cmd: int) -> list[int | bytes | None]:
        return [r.arg for r in self.commands(cmd)]

    def wait_for(self, pred: Callable[[], bool], timeout: float = 2.0) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if pred():
                return True
            time.sleep(0.005)
        return pred()

    def drop(self) -> None:
        """Cut the link now (robot switched off, cable pulled)."""
        if self.link is not None:
            self.link.close()
        if self.serial and self._slave >= 0:
            _close_fd(self._slave)
            self._slave = -1

    def stop(self) -> None:
        self._halt.set()
        self.drop()
        if not self.serial:
            self._server.close()
        self._thread.join(timeout=2.0)

    # -------------------------------------------------------------- server

    def _accept(self) -> None:
        while not self._halt.is_set():
            try:
                sock, _ = self._server.accept()
            except (TimeoutError, OSError):
                continue
            self.link = _Link(sock=sock)
            self._serve()
            return

    def _serve(self) -> None:
        link = self.link
        assert link is not None
        reader = arcos.PacketReader()
        opened = self.open_session
        opened_at = time.monotonic()
        next_sip = time.monotonic()
        last_rx = time.monotonic()
        sent = 0
        stage = 3 if opened else 0
        next_read = time.monotonic()
        self._stop_due = None
        while not self._halt.is_set():
            if time.monotonic() >= next_read:
                data = link.recv(0.005)
                next_read = time.monotonic() + self.read_every
            else:
                time.sleep(0.005)
                data = b""
            if data is None:
                # the client went away: like the simulators, end the session, stop, hang up
                self.client_gone = True
                self.v_mm = self.w_deg = 0.0
                self.motors = False
                link.close()
                return
            now = time.monotonic()
            if self._stop_due is not None and now >= self._stop_due:
                self._stop_due = None
                self.v_mm = self.w_deg = 0.0
            if self._ramp_from is not None:
                v0, since = self._ramp_from
                left = max(abs(v0) - self.decel_mm * (now - since), 0.0)
                self.v_mm = math.copysign(left, v0)
                if left == 0.0:
                    self._ramp_from = None
            if data and self.baud is not None and link.baud() != self.baud:
                data = b""  # garbled at the wrong rate: nothing decodes
            if data:
                for body in reader.feed(data):
                    last_rx = now
                    try:
                        cmd, arg, extra = arcos.decode_command(body)
                    except ValueError:
                        continue
                    phase = "session" if opened or stage >= 3 else "sync"
                    self.received.append(Received(now - self.t0, cmd, arg, extra, phase))
                    if self.behaviour == "silent":
                        continue
                    if not opened and stage < 3:
                        # the sync steps must come in order; anything else restarts them
                        if cmd == stage == 2:
                            link.send(arcos.encode_sync2(arcos.SyncInfo(
                                "FakeSim", "Pioneer", self.subtype)))
                        elif cmd == stage:
                            link.send(arcos.encode_command(cmd))
                        stage = stage + 1 if cmd == stage else 0
                        continue
                    opened, sent = self._command(cmd, arg, opened, sent)
                    if cmd == Cmd.OPEN:
                        opened_at = now
                        next_sip = now
                    if cmd == Cmd.CLOSE:
                        self.motors = False
                        stage = 0
            if not opened:
                continue
            if self.behaviour == "drop" and now - opened_at > self.drop_after:
                link.close()
                return
            if now - last_rx > self.watchdog:
                # the firmware watchdog: silence stops the motors (counted once per silence)
                self.watchdog_trips += 1
                self.v_mm = self.w_deg = 0.0
                last_rx = now
            if now >= next_sip:
                next_sip += self.sip_period
                self._integrate(self.sip_period)
                sent = self._send_cycle(link, sent)
                if self.write_failed:
                    return

    def _command(self, cmd: int, arg: object, opened: bool, sent: int) -> tuple[bool, int]:
        if cmd == Cmd.CLOSE:
            return False, sent
        if cmd == Cmd.ENABLE:
            self.motors = arg == 1
        elif cmd == Cmd.STOP and self.vanish_on_stop:
            self.drop()
        elif self.ignore_stop and (cmd == Cmd.STOP or arg == 0):
            pass
        elif self.decel_mm and (cmd == Cmd.STOP or (cmd == Cmd.VEL and arg == 0)):
            if self._ramp_from is None and self.v_mm:
                self._ramp_from = (self.v_mm, time.monotonic())
            self.w_deg = 0.0
        elif self.stop_lag and (cmd == Cmd.STOP or (cmd in (Cmd.VEL, Cmd.RVEL) and arg == 0)):
            if self._stop_due is None:
                self._stop_due = time.monotonic() + self.stop_lag
        elif cmd == Cmd.VEL and isinstance(arg, int):
            self.v_mm = float(arg)
            self._ramp_from = None
        elif cmd == Cmd.RVEL and isinstance(arg, int):
            self.w_deg = float(arg)
        elif cmd == Cmd.STOP:
            self.v_mm = self.w_deg = 0.0
        elif cmd == Cmd.SIM_LRF_ENABLE and isinstance(arg, int):
            self.laser_mode = arg
        return True, sent

    def _integrate(self, dt: float) -> None:
        if not self.motors:
            return
        x, y, th = self.pose_mm
        w = math.radians(self.w_deg)
        x += self.v_mm * dt * math.cos(th)
        y += self.v_mm * dt * math.sin(th)
        self.pose_mm = [x, y, math.remainder(th + w * dt, math.tau)]

    def _send_cycle(self, link: _Link, sent: int) -> int:
        packets: list[bytes] = []
        if self.send_sips:
            x, y, th = self.pose_mm
            half = self.w_deg * math.pi / 180 * 170  # wheel speed difference for a 340 mm base
            sip = arcos.Sip(
                x=round(x / self.dist_conv) & 0x7FFF,
                y=round(y / self.dist_conv) & 0x7FFF,
                theta=round(th / 0.001534), left_vel=int(self.v_mm - half),
                right_vel=int(self.v_mm + half), battery=128, flags=int(self.motors),
                rot_vel=round(self.w_deg * 10), moving=bool(self.v_mm))
            packets.append(arcos.encode_sip(sip))
            self.sips_sent += 1
        if self.laser_mode and self.send_laser:
            scan = (self.scan_mm or _default_scan)(self.scans_sent)
            packets += arcos_laser.encode_laser_packets(
                scan, extended=self.laser_mode == 2,
                pose=(int(self.pose_mm[0]), int(self.pose_mm[1]),
                      int(math.degrees(self.pose_mm[2]))))
            self.scans_sent += 1
        for p in packets:
            sent += 1
            if self.corrupt_every and sent % self.corrupt_every == 0:
                bad = bytearray(p)
                bad[len(bad) // 2] ^= 0xFF
                p = b"\x00\xfa" + bytes(bad)
            if not link.send(p):
                self.write_failed = not link.closed
                break
        return sent


def _default_scan(i: int) -> np.ndarray:
    """A wall 2 m ahead-ish with no return (AMRISim's 32767) on the far left and right."""
    scan = np.full(181, 2000 + (i % 5), dtype=int)
    scan[:5] = NO_RETURN_MM
    scan[-5:] = NO_RETURN_MM
    return scan


@dataclass
class FakeLms200:
    """A SICK LMS-200 on a pty: ACK + replies, baud switching, continuous 0xB0 output.

    It listens at ``baud`` and ignores bytes sent at any other rate (it reads the
    client's rate off the pty); ``streaming`` starts it in continuous mode. ``nak_first``
    NAKs the first request; ``silent`` never answers; ``corrupt_every`` flips a byte in
    every n-th scan telegram.
    """

    baud: int = 9600
    streaming: bool = False
    period: float = 0.05
    count: int = 181
    nak_first: bool = False
    silent: bool = False
    corrupt_every: int = 0
    received: list[tuple[int, bytes]] = field(default_factory=list)
    scans_sent: int = 0

    def __post_init__(self) -> None:
        self._master, self._slave, self.device = _open_pty()
        self.link = _Link(fd=self._master)
        self.url = f"lms200://{self.device}"
        self._halt = threading.Event()
        self._naks = 1 if self.nak_first else 0
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def values(self, i: int) -> np.ndarray:
        v = np.full(self.count, 1500 + i % 7, dtype=np.uint16)
        v[0] = 8191  # no return
        v[1] = 1200 | 0x2000  # a flagged (dazzled) value
        return v

    def drop(self) -> None:
        """Cut the line now (scanner unplugged)."""
        self.link.close()
        if self._slave >= 0:
            _close_fd(self._slave)
            self._slave = -1

    def stop(self) -> None:
        self._halt.set()
        self.drop()
        self._thread.join(timeout=2.0)

    def _serve(self) -> None:
        reader = lms200.TelegramReader(reply=False)
        next_scan = time.monotonic()
        while not self._halt.is_set():
            data = self.link.recv(0.005)
            if data is None:
                return
            if data and self.link.baud() == self.baud and not self.silent:
                for tel in reader.feed(data):
                    if isinstance(tel, lms200.Telegram):
                        self.received.append((tel.cmd, tel.data))
                        self._reply(tel)
            if self.streaming and time.monotonic() >= next_scan:
                next_scan = time.monotonic() + self.period
                packet = lms200.encode_measured_values(self.values(self.scans_sent))
                self.scans_sent += 1
                if self.corrupt_every and self.scans_sent % self.corrupt_every == 0:
                    bad = bytearray(packet)
                    bad[len(bad) // 3] ^= 0x55
                    packet = bytes(bad)
                if self.link.baud() == self.baud:
                    self.link.send(packet)

    def _reply(self, tel: lms200.Telegram) -> None:
        if self._naks:
            self._naks -= 1
            self.link.send(bytes([lms200.NAK]))
            return
        out = bytes([lms200.ACK])
        new_baud = None
        if tel.cmd == 0x20:
            code = tel.data[0]
            bauds = {c: b for b, c in lms200.BAUD_CODES.items()}
            if code in bauds:
                new_baud = bauds[code]
            elif code == lms200.MODE_CONTINUOUS:
                self.streaming = True
            elif code == lms200.MODE_REQUEST:
                self.streaming = False
            out += lms200.encode_telegram(0xA0, b"\x00", address=0x80, status=0x10)
        elif tel.cmd == 0x31:
            out += lms200.encode_telegram(0xB1, b"LMS200;30106" + bytes(20), address=0x80,
                                          status=0x10)
        elif tel.cmd == 0x3B:
            out += lms200.encode_telegram(0xBB, b"\x01" + tel.data, address=0x80, status=0x10)
        self.link.send(out)
        if new_baud is not None:
            time.sleep(0.01)
            self.baud = new_baud


_Fake = TypeVar("_Fake", FakeArcos, FakeLms200)


def _started(cls: Callable[..., _Fake]) -> Iterator[Callable[..., _Fake]]:
    """Yield a factory of ``cls`` fakes; stop every one it made afterwards."""
    made: list[_Fake] = []

    def make(**kw: object) -> _Fake:
        fake = cls(**kw)
        made.append(fake)
        return fake

    yield make
    for fake in made:
        fake.stop()


@pytest.fixture
def fake_robot() -> Iterator[Callable[..., FakeArcos]]:
    """Factory of started :class:`FakeArcos` servers, stopped after the test."""
    yield from _started(FakeArcos)


@pytest.fixture
def fake_lms() -> Iterator[Callable[..., FakeLms200]]:
    """Factory of started :class:`FakeLms200` scanners, stopped after the test."""
    yield from _started(FakeLms200)


@pytest.fixture
def fast() -> PioneerOptions:
    """Pioneer options with short timeouts."""
    return FAST


@pytest.fixture
def fast_lms() -> Lms200Options:
    """LMS-200 options with short timeouts."""
    return FAST_LMS
