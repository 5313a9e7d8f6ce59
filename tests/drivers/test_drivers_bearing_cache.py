"""The laser drivers keep the bearings of a few scan sizes, not of every size ever seen.

A stream of packets (or telegrams) of ever new sizes, from a confused simulator or line
noise that passes the checksum, must not grow memory: 8,000 sizes once took 256 MB.
"""

from __future__ import annotations

import numpy as np

from mdle.drivers.arcos_laser import (
    BEARING_CACHE_SIZE,
    MAX_READINGS_PER_PACKET,
    LaserPacket,
    ScanAssembler,
)


def test_scan_assembler_bounds_its_bearing_cache() -> None:
    asm = ScanAssembler()
    made = 0
    for total in range(1, 400):
        scan = None
        for first in range(0, total, MAX_READINGS_PER_PACKET):
            n = min(MAX_READINGS_PER_PACKET, total - first)
            scan = asm.add(LaserPacket(total, first, (1000,) * n), 0.0)
        assert scan is not None and len(scan.bearings) == total
        made += 1
        assert len(asm._bearings) <= BEARING_CACHE_SIZE
    assert made == 399
    # the size in use stays cached: the same array again
    again = [asm.add(LaserPacket(5, 0, (1000,) * 5), 0.0) for _ in range(2)]
    assert again[0] is not None and again[1] is not None
    assert again[0].bearings is again[1].bearings
    assert np.allclose(again[0].bearings[0], -np.pi / 2)
