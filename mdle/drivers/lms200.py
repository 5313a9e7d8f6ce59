"""The SICK LMS-200 serial telegram protocol: framing, CRC, ACK/NAK, measured values.

Pure codec, no I/O. :func:`encode_telegram` builds a telegram towards the scanner;
:class:`TelegramReader` cuts the scanner's byte stream into ACK/NAK bytes and checked
reply telegrams (resynchronising after corrupted bytes); :func:`decode_measured_values`
reads a 0xB0 reply. Facts and golden vectors: ``shared/hardware/sick-lms200.md``.

Telegram: ``STX 0x02 | ADR | LEN (uint16 LE) | CMD | data | [STATUS] | CRC16 (LE)``;
LEN counts CMD, data and (in replies) the status byte.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

import numpy as np

__all__ = [
    "ACK",
    "BAUD_CODES",
    "HOST_ADDRESS",
    "MODE_CONTINUOUS",
    "MODE_INSTALLATION",
    "MODE_MEAN",
    "MODE_REQUEST",
    "NAK",
    "REPLY_ADDRESS",
    "STX",
    "Ack",
    "MeasuredValues",
    "Telegram",
    "TelegramReader",
    "baud_command",
    "crc16",
    "decode_measured_values",
    "encode_measured_values",
    "encode_telegram",
    "lms_bearings",
    "mode_command",
    "status_request",
    "variant_command",
]

STX = 0x02
ACK = 0x06
NAK = 0x15
HOST_ADDRESS = 0x00
REPLY_ADDRESS = 0x80

MODE_INSTALLATION = 0x00
MODE_CONTINUOUS = 0x24
MODE_REQUEST = 0x25
MODE_MEAN = 0x26

#: Mode-switch codes of the baud rates (command 0x20).
BAUD_CODES: dict[int, int] = {9600: 0x42, 19200: 0x41, 38400: 0x40, 500000: 0x48}

#: Largest LEN accepted while reading (a 361-value 0xB0 reply is about 730 bytes).
_MAX_LEN = 1024


def crc16(data: bytes) -> int:
    """SICK's CRC over ``data`` (STX through the last byte before the CRC).

    The scanner's own form of polynomial 0x8005 (not a textbook CRC-16): shift, XOR
    with the polynomial when the top bit was set, then XOR in the previous and the
    current byte as one 16-bit word.
    """
    crc = 0
    prev = 0
    for b in data:
        if crc & 0x8000:
            crc = ((crc & 0x7FFF) << 1) ^ 0x8005
        else:
            crc = (crc << 1) & 0xFFFF
        crc ^= (prev << 8) | b
        prev = b
    return crc & 0xFFFF


def encode_telegram(cmd: int, data: bytes = b"", *, address: int = HOST_ADDRESS,
                    status: int | None = None) -> bytes:
    """Return a complete telegram: STX, address, length, command, data, [status], CRC.

    ``status`` is only for replies (test scanners); the host never sends one.

    >>> mode_command(MODE_CONTINUOUS).hex(" ")
    '02 00 02 00 20 24 34 08'
    """
    body = bytes([cmd]) + data + (bytes([status]) if status is not None else b"")
    head = bytes([STX, address]) + struct.pack("<H", len(body))
    crc = crc16(head + body)
    return head + body + struct.pack("<H", crc)


def mode_command(mode: int, password: bytes = b"SICK_LMS") -> bytes:
    """Switch operating mode (0x20); installation mode carries the password."""
    data = bytes([mode]) + (password if mode == MODE_INSTALLATION else b"")
    return encode_telegram(0x20, data)


def baud_command(baud: int) -> bytes:
    """Switch the scanner's line rate (0x20 with 0x42/0x41/0x40/0x48)."""
    try:
        code = BAUD_CODES[baud]
    except KeyError:
        raise ValueError(f"the LMS-200 cannot run at {baud} baud; "
                         f"choose one of {', '.join(map(str, BAUD_CODES))}") from None
    return encode_telegram(0x20, bytes([code]))


def status_request() -> bytes:
    """Request the status telegram (0x31); the cheapest question to probe a baud rate."""
    return encode_telegram(0x31)


def variant_command(angle_deg: int, resolution_cdeg: int) -> bytes:
    """Set the scan angle (100 or 180 deg) and resolution (25, 50 or 100 hundredths of a deg)."""
    if angle_deg not in (100, 180) or resolution_cdeg not in (25, 50, 100):
        raise ValueError(f"unsupported LMS-200 variant {angle_deg} deg / "
                         f"{resolution_cdeg / 100} deg")
    return encode_telegram(0x3B, struct.pack("<HH", angle_deg, resolution_cdeg))


@dataclass(frozen=True)
class Telegram:
    """A checked telegram from the scanner: address, command, data, status byte."""

    address: int
    cmd: int
    data: bytes
    status: int


@dataclass(frozen=True)
class Ack:
    """An acknowledge byte (``ok`` True for ACK 0x06, False for NAK 0x15)."""

    ok: bool


class TelegramReader:
    """Cuts the scanner's byte stream into :class:`Ack` and :class:`Telegram` items.

    Bytes outside a telegram are ACK, NAK or garbage; a candidate telegram whose CRC
    fails is dropped by moving one byte past its STX and searching again. Never raises.

    Parameters
    ----------
    reply : bool
        Expect replies (a status byte before the CRC; scanner address). False reads
        host telegrams, as a test scanner does.
    """

    def __init__(self, reply: bool = True) -> None:
        self._buf = bytearray()
        self._reply = reply
        self.rejected = 0
        self.skipped = 0

    def feed(self, data: bytes) -> list[Ack | Telegram]:
        """Add received bytes; return the acknowledges and telegrams they complete."""
        self._buf += data
        buf = self._buf
        out: list[Ack | Telegram] = []
        while buf:
            b = buf[0]
            if b != STX:
                if b in (ACK, NAK):
                    out.append(Ack(b == ACK))
                else:
                    self.skipped += 1
                del buf[:1]
                continue
            if len(buf) < 4:
                break
            length = buf[2] | (buf[3] << 8)
            addr_ok = (buf[1] & 0x80) if self._reply else not (buf[1] & 0x80)
            if not addr_ok or length < (2 if self._reply else 1) or length > _MAX_LEN:
                self.rejected += 1
                self.skipped += 1
                del buf[:1]
                continue
            end = 4 + length
            if len(buf) < end + 2:
                break
            crc = buf[end] | (buf[end + 1] << 8)
            if crc16(bytes(buf[:end])) != crc:
                self.rejected += 1
                self.skipped += 1
                del buf[:1]
                continue
            body = bytes(buf[4:end])
            if self._reply:
                out.append(Telegram(buf[1], body[0], body[1:-1], body[-1]))
            else:
                out.append(Telegram(buf[1], body[0], body[1:], 0))
            del buf[: end + 2]
        return out


@dataclass(frozen=True, eq=False)
class MeasuredValues:
    """A decoded 0xB0 reply.

    Attributes
    ----------
    values : (N,) uint16 array
        The raw words as sent.
    ranges_mm : (N,) float array
        The range part converted to mm (the unit the header announces).
    flags : (N,) uint16 array
        The bits above the range part (dazzle and similar); nonzero marks a bad value.
    valid : (N,) bool array
        A surface within range: no flag and the value below the error codes.
    partial : int
        The partial-scan index (header bits 11-12).
    unit_mm : float
        Millimetres per range count (10 for cm, 1 for mm, 100 for dm).
    """

    values: np.ndarray
    ranges_mm: np.ndarray
    flags: np.ndarray
    valid: np.ndarray
    partial: int
    unit_mm: float


#: In the 8 m (mm) mode the range is the low 13 bits; 8183..8191 are error codes.
_RANGE_BITS = 13
_FIRST_ERROR_CODE = 8183
_UNITS_MM = {0: 10.0, 1: 1.0, 2: 100.0}


def decode_measured_values(data: bytes, range_bits: int = _RANGE_BITS) -> MeasuredValues:
    """Decode the data of a 0xB0 telegram (after the command byte, before the status).

    Raises ValueError if the telegram is shorter than its header announces.
    """
    if len(data) < 2:
        raise ValueError("measured-values telegram without a header")
    header = struct.unpack_from("<H", data)[0]
    count = header & 0x03FF
    if len(data) < 2 + 2 * count:
        raise ValueError(f"measured-values telegram announces {count} values, carries fewer")
    values = np.frombuffer(data, dtype="<u2", count=count, offset=2).astype(np.uint16)
    mask = (1 << range_bits) - 1
    raw = values & mask
    flags = values >> range_bits
    unit_mm = _UNITS_MM.get((header >> 14) & 0x3, 1.0)
    error_from = _FIRST_ERROR_CODE if range_bits == _RANGE_BITS else mask
    valid = (flags == 0) & (raw < error_from) & (raw > 0)
    return MeasuredValues(values=values, ranges_mm=raw.astype(float) * unit_mm, flags=flags,
                          valid=valid, partial=(header >> 11) & 0x3, unit_mm=unit_mm)


def encode_measured_values(values: np.ndarray | list[int], *, unit: int = 1,
                           partial: int = 0, status: int = 0x10) -> bytes:
    """Return a complete 0xB0 reply telegram for raw ``values`` (for test scanners)."""
    words = np.asarray(values, dtype=np.uint16)
    header = (len(words) & 0x03FF) | ((partial & 0x3) << 11) | ((unit & 0x3) << 14)
    data = struct.pack("<H", header) + words.astype("<u2").tobytes()
    return encode_telegram(0xB0, data, address=REPLY_ADDRESS, status=status)


def lms_bearings(count: int, angle_deg: float = 180.0) -> np.ndarray:
    """Bearings (rad) of ``count`` beams spread evenly over ``angle_deg``, right to left."""
    half = math.radians(angle_deg) / 2.0
    if count == 1:
        return np.zeros(1)
    return np.linspace(-half, half, count)
