"""Independent checks of MCAP files: the mcap library's strict reading and rosbags' reader.

``mcap_doctor`` reads a file as ``mcap doctor`` checks it, with the library's own
readers: every record in order with CRC validation to the footer and closing magic,
then the summary against the data (statistics, chunk indexes, message indexes, summary
offsets and CRC), and every message decoded by mcap-ros2-support from the file's own
schemas. ``read_rosbags`` reads every message with rosbags (an independent
implementation) and its ROS 2 Humble or Jazzy type store.
"""

from __future__ import annotations

import io
import struct
import zlib
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("mcap")
pytest.importorskip("rosbags")


def mcap_doctor(path: Path | str) -> dict[str, int]:
    """Validate an MCAP file strictly; return its message counts by topic."""
    from mcap.reader import SeekingReader
    from mcap.records import (
        Channel,
        Chunk,
        DataEnd,
        Footer,
        Header,
        Message,
        MessageIndex,
        Schema,
        Statistics,
    )
    from mcap.stream_reader import StreamReader, breakup_chunk
    from mcap_ros2.decoder import DecoderFactory

    data = Path(path).read_bytes()
    assert data[:8] == b"\x89MCAP0\r\n" and data[-8:] == b"\x89MCAP0\r\n", "magic"
    # 1. every record in order, CRCs checked, ends with a Footer and the magic
    records = list(StreamReader(io.BytesIO(data), validate_crcs=True).records)
    assert isinstance(records[0], Header) and records[0].profile == "ros2"
    assert isinstance(records[-1], Footer)
    assert sum(isinstance(r, DataEnd) for r in records) == 1
    schemas = {r.id: r for r in records if isinstance(r, Schema)}
    channels = {r.id: r for r in records if isinstance(r, Channel)}
    messages = [r for r in records if isinstance(r, Message)]
    assert all(c.schema_id in schemas for c in channels.values())
    assert all(m.channel_id in channels for m in messages)
    # 2. the summary describes the data
    reader = SeekingReader(io.BytesIO(data), validate_crcs=True)
    summary = reader.get_summary()
    assert summary is not None
    stats: Statistics = summary.statistics  # type: ignore[assignment]
    assert stats.message_count == len(messages)
    assert stats.channel_count == len(channels) and stats.schema_count == len(schemas)
    per_channel = Counter(m.channel_id for m in messages)
    assert {k: v for k, v in stats.channel_message_counts.items() if v} == dict(per_channel)
    if messages:
        assert stats.message_start_time == min(m.log_time for m in messages)
        assert stats.message_end_time == max(m.log_time for m in messages)
    assert stats.chunk_count == len(summary.chunk_indexes)
    indexed = 0
    for ci in summary.chunk_indexes:
        opcode, length = struct.unpack_from("<BQ", data, ci.chunk_start_offset)
        assert opcode == 0x06 and length + 9 == ci.chunk_length
        chunk = Chunk.read(_Stream(data, ci.chunk_start_offset + 9))
        assert chunk.message_start_time == ci.message_start_time
        assert chunk.message_end_time == ci.message_end_time
        assert len(chunk.data) == ci.compressed_size
        assert chunk.uncompressed_size == ci.uncompressed_size
        inner = breakup_chunk(chunk, validate_crc=True)
        assert chunk.uncompressed_crc != 0
        raw = _uncompressed(chunk)
        for ch_id, offset in ci.message_index_offsets.items():
            opcode, _ = struct.unpack_from("<BQ", data, offset)
            assert opcode == 0x07
            index = MessageIndex.read(_Stream(data, offset + 9))
            assert index.channel_id == ch_id
            for log_time, at in index.records:
                op, _ = struct.unpack_from("<BQ", raw, at)
                assert op == 0x05
                m = Message.read(_Stream(raw, at + 9), struct.unpack_from("<Q", raw, at + 1)[0])
                assert (m.channel_id, m.log_time) == (ch_id, log_time)
                indexed += 1
        in_chunk = len([r for r in inner if isinstance(r, Message)])
        assert in_chunk == sum(len(MessageIndex.read(_Stream(data, o + 9)).records)
                               for o in ci.message_index_offsets.values())
    assert indexed == len(messages), "every message is indexed"
    footer = records[-1]
    summary_bytes = data[footer.summary_start:len(data) - 8 - 9 - 20]
    crc = zlib.crc32(summary_bytes)
    crc = zlib.crc32(struct.pack("<BQQQ", 0x02, 20, footer.summary_start,
                                 footer.summary_offset_start), crc)
    assert crc == footer.summary_crc
    for so in summary.summary_offsets if hasattr(summary, "summary_offsets") else ():
        assert so.group_start >= footer.summary_start
    # 3. every message decodes with mcap-ros2-support from the file's own schemas
    decoded = 0
    for _schema, _channel, _message, _msg in SeekingReader(
            io.BytesIO(data), decoder_factories=[DecoderFactory()]).iter_decoded_messages(
            log_time_order=True):
        decoded += 1
    assert decoded == len(messages)
    return {channels[k].topic: v for k, v in per_channel.items()}


def _Stream(data: bytes, offset: int) -> Any:  # noqa: N802 - reads like the class it makes
    """A ReadDataStream over ``data`` from ``offset`` (for reading single records)."""
    from mcap.data_stream import ReadDataStream

    return ReadDataStream(io.BytesIO(data[offset:]))


def _uncompressed(chunk: Any) -> bytes:
    if chunk.compression == "lz4":
        import lz4.frame

        return bytes(lz4.frame.decompress(chunk.data))
    assert chunk.compression == ""
    return bytes(chunk.data)


@dataclass
class Msg:
    """A message read by rosbags: topic, log time (ns), type and the decoded message."""

    topic: str
    log_time: int
    msgtype: str
    msg: Any


def read_rosbags(path: Path | str, store: str = "humble") -> list[Msg]:
    """Read every message of an MCAP file or rosbag2 folder with rosbags' reader.

    Types the ROS distribution lacks (mdle's ``mdle_msgs/msg/Diagnostics``) are taken
    from the definitions the file carries, as a user of rosbags registers them.
    """
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE if store == "humble" else Stores.ROS2_JAZZY)
    from rosbags.typesys import get_types_from_msg

    out = []
    with Reader(Path(path)) as reader:
        for conn in reader.connections:  # mdle's own types, from the file's schemas
            if conn.msgtype not in ts.fielddefs:
                ts.register(get_types_from_msg(conn.msgdef.data, conn.msgtype))
        for conn, t, raw in reader.messages():
            out.append(Msg(conn.topic, t, conn.msgtype, ts.deserialize_cdr(raw, conn.msgtype)))
    return out


@pytest.fixture(params=["humble", "jazzy"])
def store(request: pytest.FixtureRequest) -> str:
    """Each ROS 2 distribution's type store."""
    return str(request.param)


@pytest.fixture
def doctor() -> Any:
    """The strict validator, :func:`mcap_doctor`."""
    return mcap_doctor


@pytest.fixture
def rosbags_read() -> Any:
    """The independent reader, :func:`read_rosbags`."""
    return read_rosbags
