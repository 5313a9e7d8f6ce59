"""LMS-200 codec: golden vectors from the facts note, CRC, measured values, resync."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mdle.drivers import lms200
from mdle.drivers.lms200 import Ack, Telegram, TelegramReader

GOLDEN = [
    ("mode 0x24 continuous", lms200.mode_command(lms200.MODE_CONTINUOUS),
     "02 00 02 00 20 24 34 08"),
    ("mode 0x25 stop", lms200.mode_command(lms200.MODE_REQUEST), "02 00 02 00 20 25 35 08"),
    ("baud 38400", lms200.baud_command(38400), "02 00 02 00 20 40 50 08"),
    ("status request", lms200.status_request(), "02 00 01 00 31 15 12"),
    ("variant 100/0.25", lms200.variant_command(100, 25), "02 00 05 00 3B 64 00 19 00 E7 72"),
]


@pytest.mark.parametrize("name,got,expected", GOLDEN, ids=[g[0] for g in GOLDEN])
def test_lms200_golden_vectors(name: str, got: bytes, expected: str) -> None:
    assert got == bytes.fromhex(expected)


@pytest.mark.parametrize("name,got,expected", GOLDEN, ids=[g[0] for g in GOLDEN])
def test_lms200_golden_crc(name: str, got: bytes, expected: str) -> None:
    raw = bytes.fromhex(expected)
    assert lms200.crc16(raw[:-2]) == raw[-2] | (raw[-1] << 8)
    (tel,) = TelegramReader(reply=False).feed(raw)
    assert isinstance(tel, Telegram)
    assert lms200.encode_telegram(tel.cmd, tel.data) == raw


def test_crc_is_not_a_textbook_crc16() -> None:
    # CRC-16/ARC and /BUYPASS of the continuous-mode telegram differ from SICK's 0x0834
    import binascii

    data = bytes.fromhex("02 00 02 00 20 24")
    assert lms200.crc16(data) == 0x0834
    assert binascii.crc_hqx(data, 0) != 0x0834


def test_baud_and_variant_refuse_impossible_settings() -> None:
    with pytest.raises(ValueError, match="cannot run at 57600"):
        lms200.baud_command(57600)
    with pytest.raises(ValueError, match="unsupported LMS-200 variant"):
        lms200.variant_command(120, 25)


def test_reader_reports_ack_nak_and_replies() -> None:
    reply = lms200.encode_telegram(0xA0, b"\x00", address=0x80, status=0x10)
    items = TelegramReader().feed(b"\x15\x06" + reply)
    assert items == [Ack(False), Ack(True), Telegram(0x80, 0xA0, b"\x00", 0x10)]


values_strategy = st.lists(st.integers(0, 0xFFFF), min_size=1, max_size=401)


@settings(max_examples=150, deadline=None)
@given(values=values_strategy, unit=st.sampled_from([0, 1, 2]), partial=st.integers(0, 3),
       cuts=st.lists(st.integers(0, 2000), max_size=8))
def test_measured_values_round_trip_split_anywhere(values: list[int], unit: int, partial: int,
                                                    cuts: list[int]) -> None:
    stream = b"\x06" + lms200.encode_measured_values(values, unit=unit, partial=partial)
    points = sorted({c % (len(stream) + 1) for c in cuts} | {0, len(stream)})
    reader = TelegramReader()
    items = []
    for a, b in itertools.pairwise(points):
        items += reader.feed(stream[a:b])
    assert items[0] == Ack(True)
    tel = items[1]
    assert isinstance(tel, Telegram) and tel.cmd == 0xB0 and len(items) == 2
    mv = lms200.decode_measured_values(tel.data)
    raw = np.asarray(values, dtype=np.uint16)
    assert np.array_equal(mv.values, raw)
    assert mv.partial == partial
    scale = {0: 10.0, 1: 1.0, 2: 100.0}[unit]
    assert np.allclose(mv.ranges_mm, (raw & 0x1FFF) * scale)
    expected_valid = ((raw >> 13) == 0) & ((raw & 0x1FFF) < 8183) & ((raw & 0x1FFF) > 0)
    assert np.array_equal(mv.valid, expected_valid)


def test_measured_values_flags_and_error_codes_are_invalid() -> None:
    words = [1500, 1500 | 0x2000, 8191, 8183, 8182, 0]
    (tel,) = TelegramReader().feed(lms200.encode_measured_values(words))
    assert isinstance(tel, Telegram)
    mv = lms200.decode_measured_values(tel.data)
    assert mv.valid.tolist() == [True, False, False, False, True, False]
    assert mv.flags.tolist() == [0, 1, 0, 0, 0, 0]


def test_measured_values_too_short_is_refused() -> None:
    with pytest.raises(ValueError, match="announces 5 values"):
        lms200.decode_measured_values(b"\x05\x40\x01\x00")


@settings(max_examples=150, deadline=None)
@given(first=values_strategy, second=values_strategy, data=st.data())
def test_corrupted_telegram_rejected_and_stream_resynchronises(first: list[int],
                                                               second: list[int],
                                                               data: st.DataObject) -> None:
    a = bytearray(lms200.encode_measured_values(first))
    b = lms200.encode_measured_values(second)
    pos = data.draw(st.integers(1, len(a) - 1), label="byte")
    a[pos] ^= data.draw(st.integers(1, 255), label="flip")
    # the stream goes on: a few more telegrams cover any false length that was read
    tail = [lms200.encode_measured_values([1000 + i] * 361) for i in range(2)]
    reader = TelegramReader()
    items = reader.feed(bytes(a) + b + b"".join(tail))
    tels = [i for i in items if isinstance(i, Telegram)]
    assert [lms200.decode_measured_values(t.data).values.tolist() for t in tels] == [
        second, [1000] * 361, [1001] * 361]
    assert reader.rejected + reader.skipped > 0


def test_bearings_span_the_scan_angle() -> None:
    b = lms200.lms_bearings(181)
    assert b[0] == pytest.approx(-np.pi / 2) and b[-1] == pytest.approx(np.pi / 2)
    assert np.diff(b) == pytest.approx(np.full(180, np.pi / 180))
    assert lms200.lms_bearings(401, 100.0)[0] == pytest.approx(np.radians(-50))
