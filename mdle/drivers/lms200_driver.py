"""A SICK LMS-200 on a serial line: find its baud rate, switch, stream, read scans.

:class:`Lms200Driver` probes the scanner's current rate (9600, 19200, 38400, 500 k),
switches it to the rate asked for, starts continuous output (mode 0x24) and runs a
reader thread that keeps the newest complete 0xB0 scan with its timestamp. It is a
:class:`~mdle.drivers.pioneer.ScanSource`, so a :class:`PioneerBackend` can use it as its
laser. Timeouts follow the facts note: 1 s per message, 3 s for a mode switch, 3 retries.
"""

from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass

import numpy as np

from mdle.core.backend import Scan
from mdle.core.errors import BackendError
from mdle.drivers import lms200
from mdle.drivers.arcos_laser import BEARING_CACHE_SIZE
from mdle.drivers.lms200 import Ack, Telegram, TelegramReader
from mdle.drivers.transport import Transport, TransportClosed, read_or_fail

__all__ = ["Lms200Driver", "Lms200Options", "scan_angle_for"]

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Lms200Options:
    """Choices and timeouts of an :class:`Lms200Driver` (seconds unless stated)."""

    baud: int = 38400
    """The rate to run at (38400 is the least for 10 Hz scans on RS-232)."""
    probe_bauds: tuple[int, ...] = (9600, 19200, 38400, 500000)
    """Rates tried, after ``baud`` itself, to find the scanner's current one."""
    reply_timeout: float = 1.0
    mode_timeout: float = 3.0
    retries: int = 3
    variant: tuple[int, int] | None = None
    """(angle deg, resolution in 0.01 deg) to configure, or None to keep the scanner's."""
    max_range: float = 8.183
    """Metres reported for beams without a return (the 8 m / mm mode's range)."""
    poll: float = 0.02


def scan_angle_for(count: int) -> float:
    """Return the scan angle (deg) an LMS-200 scan of ``count`` values covers."""
    return 100.0 if count in (101, 201, 401) else 180.0


class Lms200Driver:
    """Streams scans from a SICK LMS-200; implements ``ScanSource``.

    Parameters
    ----------
    transport : Transport
        The scanner's serial line (owned and closed by the driver).
    options : Lms200Options

    Raises
    ------
    BackendError
        The scanner answers at none of the rates, refuses the baud or mode switch.
    """

    def __init__(self, transport: Transport, options: Lms200Options | None = None) -> None:
        self._transport = transport
        self._opt = opt = options or Lms200Options()
        if opt.baud not in lms200.BAUD_CODES:
            raise BackendError(f"the LMS-200 cannot run at {opt.baud} baud; choose one of "
                               f"{', '.join(map(str, lms200.BAUD_CODES))}")
        self._reader = TelegramReader()
        self._lock = threading.Lock()
        self._scan: Scan | None = None
        self._failure: str | None = None
        self._halt = threading.Event()
        self._closed = False
        self._thread: threading.Thread | None = None
        self._bearings: dict[tuple[int, float], np.ndarray] = {}
        self.scans = 0
        self.baud = 0
        try:
            self._configure()
            self._thread = threading.Thread(target=self._run, name="mdle-lms200-reader",
                                            daemon=True)
            self._thread.start()
        except BaseException:
            self._transport.close()
            raise

    # ------------------------------------------------------------------ ScanSource

    def latest(self) -> Scan | None:
        """Return the newest complete scan (stamp: ``time.monotonic()`` when it was measured)."""
        with self._lock:
            return self._scan

    def failure(self) -> str | None:
        """Why scans stopped (the line failed), or None."""
        with self._lock:
            return self._failure

    def close(self) -> None:
        """Stop the stream (mode 0x25) and release the line (idempotent, never raises)."""
        if self._closed:
            return
        self._closed = True
        self._halt.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=1.0)
        try:
            self._transport.write(lms200.mode_command(lms200.MODE_REQUEST))
        except (TransportClosed, OSError):
            pass
        self._transport.finish(0.2)  # let the stop-streaming request leave the line

    # ------------------------------------------------------------------ setup

    def _configure(self) -> None:
        opt = self._opt
        current = self._probe()
        if current != opt.baud:
            reply = self._request(lms200.baud_command(opt.baud), 0xA0, opt.mode_timeout)
            if reply.data[:1] != b"\x00":
                raise BackendError(f"the LMS-200 refused to switch to {opt.baud} baud "
                                   f"(reply {reply.data.hex(' ')})")
            self._transport.set_baud(opt.baud)
            self._reader = TelegramReader()
            self._request(lms200.status_request(), 0xB1, opt.reply_timeout)
        self.baud = opt.baud
        if opt.variant is not None:
            reply = self._request(lms200.variant_command(*opt.variant), 0xBB, opt.mode_timeout)
            if reply.data[:1] != b"\x01":
                raise BackendError(f"the LMS-200 refused the variant {opt.variant}")
        reply = self._request(lms200.mode_command(lms200.MODE_CONTINUOUS), 0xA0,
                              opt.mode_timeout)
        if reply.data[:1] != b"\x00":
            raise BackendError(f"the LMS-200 refused continuous output "
                               f"(reply {reply.data.hex(' ')})")

    def _probe(self) -> int:
        """Find the rate the scanner listens at.

        It answers a stop-streaming request (or is heard streaming) only at the right one.
        """
        opt = self._opt
        order = [opt.baud] + [b for b in opt.probe_bauds if b != opt.baud]
        for baud in order:
            self._transport.set_baud(baud)
            self._reader = TelegramReader()
            try:
                self._request(lms200.mode_command(lms200.MODE_REQUEST), 0xA0,
                              opt.reply_timeout, retries=1, any_telegram=True)
            except BackendError:
                continue
            return baud
        raise BackendError(f"no answer from an LMS-200 on {self._transport.description} "
                           f"(tried {', '.join(map(str, order))} baud): check power, cable "
                           f"and port")

    def _request(self, packet: bytes, reply_cmd: int, timeout: float, *,
                 retries: int | None = None, any_telegram: bool = False) -> Telegram:
        """Send ``packet`` and wait for the reply ``reply_cmd``; NAK or silence retries."""
        tries = retries if retries is not None else self._opt.retries
        naks = self._opt.retries  # a NAK is an answer: resend at once, on top of ``tries``
        what = f"0x{packet[4]:02X}"
        attempt = 0
        while attempt < max(1, tries):
            try:
                self._transport.write(packet)
            except TransportClosed as exc:
                raise BackendError(f"the LMS-200 line {self._transport.description} "
                                   f"failed: {exc}") from None
            deadline = time.monotonic() + timeout
            nak = False
            while not nak and time.monotonic() < deadline:
                try:
                    data = self._transport.read(min(0.05, max(0.0, deadline - time.monotonic())))
                except TransportClosed as exc:
                    raise BackendError(f"the LMS-200 line {self._transport.description} "
                                       f"failed: {exc}") from None
                for item in self._reader.feed(data):
                    if isinstance(item, Ack):
                        nak = nak or not item.ok
                    elif item.cmd == reply_cmd or any_telegram:
                        return item
            if nak and naks > 0:
                naks -= 1
                continue
            attempt += 1
        raise BackendError(f"the LMS-200 on {self._transport.description} did not answer "
                           f"command {what} ({tries} tries, {timeout} s each)")

    # ------------------------------------------------------------------ reader thread

    def _run(self) -> None:
        """Read telegrams and publish scans; never raises."""
        while not self._halt.is_set():
            data = read_or_fail(self._transport, self._opt.poll, self._set_failure)
            if data is None:
                return
            if not data:
                continue
            now = time.monotonic()
            for item in self._reader.feed(data):
                if isinstance(item, Telegram) and item.cmd == 0xB0:
                    try:
                        scan = self._to_scan(item, now)
                    except Exception:  # noqa: BLE001 - malformed content, valid CRC
                        _log.debug("dropped a malformed 0xB0 telegram", exc_info=True)
                        continue
                    with self._lock:
                        self._scan = scan
                        self.scans += 1

    def _to_scan(self, tel: Telegram, now: float) -> Scan:
        mv = lms200.decode_measured_values(tel.data)
        count = len(mv.values)
        angle = float(self._opt.variant[0]) if self._opt.variant else scan_angle_for(count)
        key = (count, angle)
        bearings = self._bearings.get(key)
        if bearings is None:
            bearings = lms200.lms_bearings(count, angle)
            bearings.setflags(write=False)
            if len(self._bearings) >= BEARING_CACHE_SIZE:
                del self._bearings[next(iter(self._bearings))]  # the oldest size
            self._bearings[key] = bearings
        max_range = self._opt.max_range
        ranges = np.where(mv.valid, mv.ranges_mm / 1000.0, max_range)
        ranges.setflags(write=False)
        valid = mv.valid
        valid.setflags(write=False)
        # the scan was measured before its bytes crossed the line: 10 bits per byte
        transfer = (len(tel.data) + 8) * 10.0 / max(self.baud, 1)
        return Scan(ranges, bearings, valid, now - transfer, max_range)

    def _set_failure(self, why: str) -> None:
        with self._lock:
            if self._failure is None:
                self._failure = f"{self._transport.description}: {why}"
