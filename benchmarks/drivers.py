"""Driver codec cost: what the reader threads spend per robot cycle and per laser scan.

One Pioneer cycle is a SIP and a 181-reading simulator scan in six 0x60 packets (100 ms
of data); one LMS-200 scan is a 181-value 0xB0 telegram. Each is cut from the byte
stream in pieces of 64 bytes (as a socket or serial line delivers them), checked,
decoded and, for the laser, reassembled into SI arrays. The target is well under 1 ms per
cycle, so a reader thread uses under 1 % of a core at 10 Hz.

Run: ``python benchmarks/drivers.py [--cycles N]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from mdle.drivers import arcos, arcos_laser, lms200


def _chunks(data: bytes, size: int = 64) -> list[bytes]:
    return [data[i: i + size] for i in range(0, len(data), size)]


def pioneer_cycle_us(cycles: int) -> float:
    """Microseconds to deframe, decode and assemble one SIP + one simulator scan."""
    ranges = np.linspace(300, 8000, 181).astype(int)
    stream = arcos.encode_sip(arcos.Sip(100, 200, 300, 150, 160, rot_vel=12)) + b"".join(
        arcos_laser.encode_laser_packets(ranges))
    pieces = _chunks(stream)
    reader = arcos.PacketReader()
    odo = arcos.Odometer()
    asm = arcos_laser.ScanAssembler()
    scans = 0
    t0 = time.perf_counter()
    for _ in range(cycles):
        for piece in pieces:
            for body in reader.feed(piece):
                if body[0] in arcos.SIP_IDS:
                    odo.update(arcos.decode_sip(body))
                elif asm.add(arcos_laser.decode_laser_packet(body), 0.0) is not None:
                    scans += 1
    elapsed = time.perf_counter() - t0
    assert scans == cycles
    return elapsed / cycles * 1e6


def lms_scan_us(cycles: int) -> float:
    """Microseconds to cut, CRC-check and decode one 181-value 0xB0 telegram."""
    telegram = lms200.encode_measured_values(np.full(181, 1500))
    pieces = _chunks(telegram)
    reader = lms200.TelegramReader()
    t0 = time.perf_counter()
    for _ in range(cycles):
        for piece in pieces:
            for item in reader.feed(piece):
                lms200.decode_measured_values(item.data)  # type: ignore[union-attr]
    return (time.perf_counter() - t0) / cycles * 1e6


def main() -> None:
    """Print the time of one driver cycle."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=2000)
    args = parser.parse_args()
    print(f"pioneer cycle (SIP + 181-reading scan): {pioneer_cycle_us(args.cycles):8.1f} us")
    print(f"LMS-200 scan (181 values, CRC):         {lms_scan_us(args.cycles):8.1f} us")


if __name__ == "__main__":
    main()
