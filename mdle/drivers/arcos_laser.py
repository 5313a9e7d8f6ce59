"""The Pioneer simulators' laser packets (0x60 and extended 0x61) and scan reassembly.

MobileSim and AMRISim send a simulated SICK scan inside ARCOS packets of at most 32
readings. :func:`decode_laser_packet` reads one packet; :class:`ScanAssembler` puts a
scan back together by each packet's index of first reading and hands out the scan once
``first + n >= total``. Reading 0 looks at the robot's right (-90 deg) and bearings
grow counter-clockwise in steps of ``fov / total`` (180/181 deg for the simulators'
181-reading scan); readings at the maximum range are no-returns and are flagged invalid.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

import numpy as np

from mdle.drivers.arcos import Cmd, encode_command, frame

__all__ = [
    "LASER_IDS",
    "MAX_READINGS_PER_PACKET",
    "NO_RETURN_MM",
    "AssembledScan",
    "LaserPacket",
    "ScanAssembler",
    "decode_laser_packet",
    "enable_command",
    "encode_laser_packets",
    "sim_bearings",
]

LASER_IDS = frozenset({0x60, 0x61})
#: What MobileSim/AMRISim send for a beam without a return (mm): a range at or above it
#: is no reading at all, never a hit 32 m away.
NO_RETURN_MM = 32767
MAX_READINGS_PER_PACKET = 32
#: Scan sizes whose bearings are kept (a laser has one or two; a stream of garbage
#: packets of every size must not grow the cache without bound).
BEARING_CACHE_SIZE = 8

_HEAD60 = struct.Struct("<hhhHHB")  # x y theta(deg) total first n
_HEAD61 = struct.Struct("<HHB")  # total first n
_READ61 = struct.Struct("<HBH")  # range reflectance reserved


@dataclass(frozen=True)
class LaserPacket:
    """One laser packet: ``n`` readings (mm) starting at index ``first`` of ``total``.

    ``pose`` is the odometric pose the simulator attached (x mm, y mm, theta deg; 0x60
    only); ``reflectance`` the per-reading reflectance (0x61 only).
    """

    total: int
    first: int
    ranges_mm: tuple[int, ...]
    pose: tuple[int, int, int] | None = None
    reflectance: tuple[int, ...] | None = None
    laser_index: int = 0
    flags: int = 0


def decode_laser_packet(body: bytes) -> LaserPacket:
    """Decode a 0x60 or 0x61 packet body (``ID + payload``); ValueError if malformed."""
    if not body or body[0] not in LASER_IDS:
        raise ValueError("not a simulator laser packet")
    p = body[1:]
    if body[0] == 0x60:
        if len(p) < _HEAD60.size:
            raise ValueError("laser packet 0x60 too short")
        x, y, th, total, first, n = _HEAD60.unpack_from(p)
        if len(p) < _HEAD60.size + 2 * n:
            raise ValueError(f"laser packet 0x60 announces {n} readings, carries fewer")
        ranges = struct.unpack_from(f"<{n}H", p, _HEAD60.size)
        return LaserPacket(total, first, tuple(ranges), pose=(x, y, th))
    if len(p) < _HEAD61.size:
        raise ValueError("laser packet 0x61 too short")
    total, first, n = _HEAD61.unpack_from(p)
    end = _HEAD61.size + _READ61.size * n
    if len(p) < end + 2:
        raise ValueError(f"laser packet 0x61 announces {n} readings, carries fewer")
    triples = [_READ61.unpack_from(p, _HEAD61.size + _READ61.size * i) for i in range(n)]
    return LaserPacket(total, first, tuple(t[0] for t in triples),
                       reflectance=tuple(t[1] for t in triples),
                       laser_index=p[end], flags=p[end + 1])


def encode_laser_packets(ranges_mm: np.ndarray | list[int], *, extended: bool = False,
                         pose: tuple[int, int, int] = (0, 0, 0),
                         per_packet: int = MAX_READINGS_PER_PACKET) -> list[bytes]:
    """Return the packets a simulator sends for one scan (for test servers and round trips)."""
    values = [int(r) for r in ranges_mm]
    total = len(values)
    out = []
    for first in range(0, total, per_packet):
        chunk = values[first: first + per_packet]
        if extended:
            body = bytes([0x61]) + _HEAD61.pack(total, first, len(chunk))
            body += b"".join(_READ61.pack(r, 0, 0) for r in chunk) + b"\x00\x00"
        else:
            body = bytes([0x60]) + _HEAD60.pack(*pose, total, first, len(chunk))
            body += struct.pack(f"<{len(chunk)}H", *chunk)
        out.append(frame(body))
    return out


def enable_command(mode: int = 1, laser_index: int = 0) -> bytes:
    """SIM_LRF_ENABLE: 1 for 0x60 packets, 2 for extended 0x61, 0 to switch off."""
    return encode_command(Cmd.SIM_LRF_ENABLE, mode, bytes([laser_index]))


def sim_bearings(total: int, fov_deg: float = 180.0) -> np.ndarray:
    """Bearings (rad) of a simulator scan of ``total`` readings: -fov/2 + i * fov/total."""
    step = math.radians(fov_deg) / total
    return -math.radians(fov_deg) / 2.0 + step * np.arange(total, dtype=float)


@dataclass(frozen=True, eq=False)
class AssembledScan:
    """A complete scan in SI: ranges (m), bearings (rad), valid mask, max range (m).

    ``started`` is the caller's timestamp of the scan's first packet (seconds).
    """

    ranges: np.ndarray
    bearings: np.ndarray
    valid: np.ndarray
    max_range: float
    started: float


class ScanAssembler:
    """Reassembles scans from laser packets; never raises on odd input.

    A packet whose ``total`` differs from the scan in progress, or whose ``first`` goes
    back (a new scan began before the old one completed), restarts assembly; a scan
    that completes with gaps is dropped (counted in ``dropped``).

    Parameters
    ----------
    max_range_mm : int
        The value the simulator sends for no return (:data:`NO_RETURN_MM` unless the
        simulator is configured otherwise); readings at or beyond it, and zero, are
        invalid (and hold ``max_range`` metres).
    fov_deg : float
        The laser's field of view.
    """

    def __init__(self, max_range_mm: int = NO_RETURN_MM, fov_deg: float = 180.0) -> None:
        self.max_range_mm = max_range_mm
        self.fov_deg = fov_deg
        self.dropped = 0
        self._total = 0
        self._next = 0
        self._values: np.ndarray = np.zeros(0, dtype=np.uint16)
        self._filled: np.ndarray = np.zeros(0, dtype=bool)
        self._started = 0.0
        self._bearings: dict[int, np.ndarray] = {}

    def add(self, packet: LaserPacket, stamp: float) -> AssembledScan | None:
        """Add one packet received at ``stamp``; return the scan it completes, if any."""
        total, first, n = packet.total, packet.first, len(packet.ranges_mm)
        if total <= 0 or first >= total or n == 0:
            return None
        if total != self._total or first < self._next or first == 0:
            if self._filled.any() and not self._filled.all():
                self.dropped += 1
            self._total = total
            self._values = np.zeros(total, dtype=np.uint16)
            self._filled = np.zeros(total, dtype=bool)
            self._started = stamp
        end = min(first + n, total)
        self._values[first:end] = packet.ranges_mm[: end - first]
        self._filled[first:end] = True
        self._next = end
        if end < total:
            return None
        complete = bool(self._filled.all())
        values, self._filled = self._values, np.zeros(total, dtype=bool)
        self._next = total
        if not complete:
            self.dropped += 1
            return None
        bearings = self._bearings.get(total)
        if bearings is None:
            bearings = sim_bearings(total, self.fov_deg)
            bearings.setflags(write=False)
            if len(self._bearings) >= BEARING_CACHE_SIZE:
                del self._bearings[next(iter(self._bearings))]  # the oldest size
            self._bearings[total] = bearings
        valid = (values < self.max_range_mm) & (values > 0)
        max_range = self.max_range_mm / 1000.0
        ranges = np.where(valid, values / 1000.0, max_range)
        ranges.setflags(write=False)
        valid.setflags(write=False)
        return AssembledScan(ranges, bearings, valid, max_range, self._started)
