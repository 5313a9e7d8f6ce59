"""Simulator laser packets (0x60/0x61): decoding, reassembly, bearings, no-returns."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mdle.drivers import arcos, arcos_laser
from mdle.drivers.arcos_laser import ScanAssembler


def _feed(assembler: ScanAssembler, packets: list[bytes], stamp: float = 1.0) -> list:
    reader = arcos.PacketReader()
    scans = []
    for body in reader.feed(b"".join(packets)):
        scan = assembler.add(arcos_laser.decode_laser_packet(body), stamp)
        if scan is not None:
            scans.append(scan)
    return scans


def test_enable_command_bytes() -> None:
    # SIM_LRF_ENABLE 230 (0xE6), integer 1, laser index 0
    packet = arcos_laser.enable_command(1, 0)
    body = bytes([0xE6, 0x3B, 0x01, 0x00, 0x00])
    assert packet == b"\xfa\xfb" + bytes([len(body) + 2]) + body + \
        arcos.checksum(body).to_bytes(2, "big")


def test_181_reading_scan_arrives_in_six_packets_with_simulator_bearings() -> None:
    ranges = np.arange(181) * 10 + 500
    packets = arcos_laser.encode_laser_packets(ranges, pose=(100, -200, 45))
    assert len(packets) == 6
    first = arcos_laser.decode_laser_packet(arcos.PacketReader().feed(packets[0])[0])
    assert first.pose == (100, -200, 45) and first.total == 181 and len(first.ranges_mm) == 32
    (scan,) = _feed(ScanAssembler(), packets, stamp=3.5)
    assert scan.started == 3.5
    assert np.allclose(scan.ranges, ranges / 1000.0)
    assert scan.bearings[0] == pytest.approx(-math.pi / 2)
    assert np.diff(scan.bearings) == pytest.approx(np.full(180, math.radians(180 / 181)))
    assert scan.valid.all()


def test_no_return_is_flagged_invalid_and_reads_max_range() -> None:
    ranges = np.full(181, 2000)
    ranges[[0, 90, 180]] = 32000
    (scan,) = _feed(ScanAssembler(max_range_mm=32000), arcos_laser.encode_laser_packets(ranges))
    assert not scan.valid[[0, 90, 180]].any() and scan.valid.sum() == 178
    assert scan.ranges[90] == scan.max_range == 32.0


def test_extended_packets_decode() -> None:
    ranges = np.arange(181) + 300
    packets = arcos_laser.encode_laser_packets(ranges, extended=True)
    (scan,) = _feed(ScanAssembler(), packets)
    assert np.allclose(scan.ranges, ranges / 1000.0)


def test_missing_packet_drops_the_scan_and_the_next_one_assembles() -> None:
    a = arcos_laser.encode_laser_packets(np.full(181, 1000))
    b = arcos_laser.encode_laser_packets(np.full(181, 2000))
    asm = ScanAssembler()
    scans = _feed(asm, a[:3] + a[4:] + b)
    assert len(scans) == 1 and np.allclose(scans[0].ranges, 2.0)
    assert asm.dropped == 1


@settings(max_examples=100, deadline=None)
@given(ranges=st.lists(st.integers(1, 32000), min_size=1, max_size=400),
       per_packet=st.integers(1, 32), extended=st.booleans(), data=st.data())
def test_random_scans_split_across_packets_round_trip(ranges: list[int], per_packet: int,
                                                      extended: bool,
                                                      data: st.DataObject) -> None:
    packets = arcos_laser.encode_laser_packets(ranges, per_packet=per_packet, extended=extended)
    # a second scan right behind, with one corrupted byte somewhere in the first
    stream = bytearray(b"".join(packets))
    pos = data.draw(st.integers(0, len(stream) - 1), label="byte")
    corrupt = data.draw(st.booleans(), label="corrupt")
    if corrupt:
        stream[pos] ^= 0x5A
    after = arcos_laser.encode_laser_packets(list(reversed(ranges)), per_packet=per_packet,
                                             extended=extended)
    tail = arcos.encode_sip(arcos.Sip(0, 0, 0)) * 10  # the stream goes on
    asm = ScanAssembler(max_range_mm=32000)
    reader = arcos.PacketReader()
    scans = []
    for body in reader.feed(bytes(stream) + b"".join(after) + tail):
        if body[0] in arcos_laser.LASER_IDS:
            scan = asm.add(arcos_laser.decode_laser_packet(body), 0.0)
            if scan is not None:
                scans.append(scan)
    want_last = np.asarray(list(reversed(ranges)))
    assert np.allclose(scans[-1].ranges[want_last < 32000], want_last[want_last < 32000] / 1000)
    assert np.array_equal(scans[-1].valid, want_last < 32000)
    if not corrupt:
        assert len(scans) == 2
        assert np.allclose(scans[0].ranges * 1000, np.minimum(ranges, 32000))
    else:
        assert len(scans) in (1, 2)  # a scan with a corrupted packet never comes out wrong
        if len(scans) == 2:
            assert np.allclose(scans[0].ranges * 1000, np.minimum(ranges, 32000))


def test_garbage_packet_contents_never_raise_out_of_the_assembler() -> None:
    asm = ScanAssembler()
    assert asm.add(arcos_laser.LaserPacket(total=0, first=0, ranges_mm=()), 0.0) is None
    assert asm.add(arcos_laser.LaserPacket(total=5, first=9, ranges_mm=(1,)), 0.0) is None
    scan = asm.add(arcos_laser.LaserPacket(total=2, first=0, ranges_mm=(1, 2, 3)), 0.0)
    assert scan is not None and scan.ranges.shape == (2,)
    with pytest.raises(ValueError):
        arcos_laser.decode_laser_packet(b"\x60\x01")


def test_no_return_is_the_simulators_32767_and_is_invalid() -> None:
    # AMRISim sends 32767 mm for a beam without a return: no reading, not a 32 m hit
    ranges = np.full(181, 1500)
    ranges[[0, 1, 180]] = arcos_laser.NO_RETURN_MM
    ranges[2] = 32000  # a real (if far) hit below the no-return code
    (scan,) = _feed(ScanAssembler(), arcos_laser.encode_laser_packets(ranges))
    assert scan.max_range == pytest.approx(32.767)
    assert not scan.valid[[0, 1, 180]].any() and scan.valid[2:180].all()
    assert np.all(scan.ranges[[0, 1, 180]] == pytest.approx(32.767))
    assert scan.ranges[2] == pytest.approx(32.0)
