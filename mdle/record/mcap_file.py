"""A chunked, indexed MCAP writer that keeps up with a control loop and survives a kill.

The file is laid out as the MCAP specification describes and the mcap library writes
it: magic, Header, then (outside any chunk) every Schema and Channel and the run's
Metadata, then Chunks of Message records, each followed by its MessageIndex records;
at :meth:`McapFile.finish` a DataEnd, the summary (schemas, channels, statistics, chunk
and metadata indexes, summary offsets), the Footer and the closing magic.

The mcap library's record classes write the header, schemas, channels, metadata and the
summary; its per-message path (a dataclass and seven stream writes each, about 6 us) is
too slow for a 30 us tick budget, so the records written as a run goes (messages,
chunks, message indexes) are packed here with :mod:`struct` and numpy, and checked
against the library's reader in the tests.

Records are packed straight into the open chunk's buffer (allocated once, reused for
every chunk). Durability: a chunk is closed once it holds ``chunk_size`` bytes (at the
next record or :meth:`McapFile.tick`) or has been open for ``max_age`` seconds of wall
time, and goes to the operating system at once (with its indexes) with an unbuffered
write. A process killed outright leaves a file whose closed
chunks a recovering reader (one that reads records until the file ends) reads back in
full; everything else ends the file properly with :meth:`finish`.
"""

from __future__ import annotations

import os
import struct
import time
import zlib
from collections.abc import Callable, Mapping, Sequence
from typing import IO

import numpy as np

__all__ = ["MAGIC", "CHUNK_SIZE", "MAX_CHUNK_AGE", "McapFile", "MessageTally"]

MAGIC = b"\x89MCAP0\r\n"

#: Bytes of messages (uncompressed) after which a chunk is closed: 64 KiB is about 25
#: ticks of a simulated run with a 181-beam scan, or 2.5 s at 10 Hz.
CHUNK_SIZE = 64 * 1024

#: Longest wall time (s) a chunk stays open, so a slow (real-time) run reaches the disk
#: at least this often: a kill loses at most this much.
MAX_CHUNK_AGE = 1.0

_MESSAGE = struct.Struct("<BQHIQQ")   # opcode, length, channel, sequence, log, publish
_MESSAGE_OP = 0x05
_INDEX_OP = 0x07
_INDEX_HEAD = struct.Struct("<BQHI")  # opcode, length, channel, entries' byte length
_CHUNK_OP = 0x06
_SLACK = 16 * 1024  # room past chunk_size for the records that fill a chunk
_CHUNK_HEAD = struct.Struct("<BQQQQII")  # opcode, length, start, end, size, crc, name length


class MessageTally:
    """Messages so far: per channel, in all, and the span of their log times (ns).

    A channel's count is its next message's sequence number. A recording's file keeps one,
    and so does the outlet that feeds it (which may have no file: a live view alone).
    """

    def __init__(self) -> None:
        self.per_channel: list[int] = [0]  # by channel id; ids start at 1
        self.messages = 0
        self.first = 2**64 - 1
        self.last = 0

    def add_channel(self) -> int:
        """Count a new channel; return its id."""
        self.per_channel.append(0)
        return len(self.per_channel) - 1

    def count(self, channel: int, n: int = 1) -> None:
        """Count ``n`` more messages on ``channel``."""
        self.per_channel[channel] += n
        self.messages += n

    def span(self, first: int, last: int) -> None:
        """Widen the span of log times to hold ``first`` to ``last``."""
        self.first = min(self.first, first)
        self.last = max(self.last, last)

    def channel_counts(self) -> dict[int, int]:
        """Messages per channel id."""
        return {i: n for i, n in enumerate(self.per_channel) if i}

    @property
    def time_range(self) -> tuple[int, int] | None:
        """(first, last) log time (ns), None without messages."""
        return (self.first, self.last) if self.messages else None


class McapFile:
    """Write one MCAP file.

    Parameters
    ----------
    path : str or path-like
        The file to create (overwritten).
    profile, library : str
        The Header's profile (``ros2``) and writer name.
    compression : {"lz4", ""}
        Chunk compression.
    chunk_size : int
        Uncompressed bytes after which a chunk is closed.
    max_age : float
        Seconds of wall time after which :meth:`tick` closes an open chunk.
    clock : callable
        Wall clock (injectable for tests).

    Register schemas and channels first (:meth:`schema`, :meth:`channel`), then add
    messages; :meth:`finish` ends the file; :meth:`close` abandons it as it stands.
    """

    def __init__(self, path: str | os.PathLike[str], *, profile: str = "ros2",
                 library: str = "mdle", compression: str = "lz4",
                 chunk_size: int = CHUNK_SIZE, max_age: float = MAX_CHUNK_AGE,
                 clock: Callable[[], float] = time.monotonic) -> None:
        from mcap.data_stream import RecordBuilder
        from mcap.records import Header

        if compression not in ("lz4", ""):
            raise ValueError(f"unknown compression {compression!r} (lz4 or '')")
        if compression == "lz4":
            import lz4.frame

            self._compress: Callable[[memoryview], bytes] | None = lz4.frame.compress
        else:
            self._compress = None
        self.path = os.fspath(path)
        self._compression = compression
        self._chunk_size = int(chunk_size)
        self._max_age = float(max_age)
        self._clock = clock
        self._file: IO[bytes] | None = open(self.path, "wb", buffering=0)
        self._pos = 0
        self._builder = RecordBuilder()
        self._schemas: list[object] = []
        self._channels: list[object] = []
        self._metadata_index: list[object] = []
        self._chunk_index: list[object] = []
        self.tally = MessageTally()           # of the closed chunks' spans, and every count
        # the open chunk's records: one buffer, filled in place and reused for every chunk
        self._buf = bytearray(self._chunk_size + _SLACK)
        self._used = 0
        self._entries: list[list[tuple[int, int]]] = [[]]  # per channel: (time, offset)
        # per channel: add_block's (log times, offsets in the chunk)
        self._blocks: list[list[tuple[np.ndarray, np.ndarray]]] = [[]]
        self._chunk_start = 2**64 - 1
        self._chunk_end = 0
        self._close_at = clock() + self._max_age
        self.finished = False
        self._out(MAGIC)
        Header(profile=profile, library=library).write(self._builder)
        self._emit()

    # ------------------------------------------------------------------ low level

    def _out(self, data: bytes | bytearray | memoryview) -> None:
        """Write everything to the file now."""
        if self._file is None:
            raise OSError(f"the recording `{self.path}` is closed")
        view = memoryview(data)
        while view:
            n = self._file.write(view)
            if not n:
                raise OSError(f"cannot write the recording `{self.path}`")
            view = view[n:]
            self._pos += n

    def _out_all(self, pieces: Sequence[bytes | bytearray | memoryview]) -> None:
        """Write ``pieces`` one after the other, in one system call when it takes them all."""
        if self._file is None:
            raise OSError(f"the recording `{self.path}` is closed")
        n = os.writev(self._file.fileno(), pieces)
        self._pos += n
        if n < sum(len(p) for p in pieces):  # a short write: the rest as it comes
            self._out(memoryview(b"".join(pieces))[n:])

    def _emit(self) -> None:
        """Write what the record builder holds."""
        self._out(self._builder.end())

    # ------------------------------------------------------------------ registration

    def schema(self, name: str, encoding: str, data: bytes) -> int:
        """Register a schema; returns its id."""
        from mcap.records import Schema

        record = Schema(id=len(self._schemas) + 1, name=name, encoding=encoding, data=data)
        self._schemas.append(record)
        record.write(self._builder)
        self._emit()
        return record.id

    def channel(self, topic: str, schema_id: int, message_encoding: str = "cdr",
                metadata: Mapping[str, str] | None = None) -> int:
        """Register a channel; returns its id."""
        from mcap.records import Channel

        record = Channel(id=len(self._channels) + 1, topic=topic,
                         message_encoding=message_encoding, schema_id=schema_id,
                         metadata=dict(metadata or {}))
        self._channels.append(record)
        self.tally.add_channel()
        self._entries.append([])
        self._blocks.append([])
        record.write(self._builder)
        self._emit()
        return record.id

    def metadata(self, name: str, data: Mapping[str, str]) -> None:
        """Write a Metadata record (between chunks)."""
        from mcap.records import Metadata, MetadataIndex

        self.close_chunk()
        offset = self._pos
        Metadata(name=name, metadata=dict(data)).write(self._builder)
        length = self._builder.count
        self._emit()
        self._metadata_index.append(MetadataIndex(offset=offset, length=length, name=name))

    # ------------------------------------------------------------------ messages

    def add(self, channel: int, ns: int, data: bytes) -> None:
        """Add a message on ``channel`` logged at ``ns`` (nanoseconds)."""
        pos = self._reserve(31 + len(data), ns)
        seq = self.tally.per_channel[channel]
        self.tally.count(channel)
        self._entries[channel].append((ns, pos))
        _MESSAGE.pack_into(self._buf, pos, _MESSAGE_OP, 22 + len(data), channel, seq, ns, ns)
        self._buf[pos + 31:pos + 31 + len(data)] = data

    def _reserve(self, size: int, ns: int) -> int:
        """Make room for ``size`` bytes of records logged at ``ns``; return their offset.

        A chunk already full is closed first; the buffer grows for a large record.
        """
        pos = self._used
        if pos >= self._chunk_size:
            self.close_chunk()
            pos = 0
        end = pos + size
        if end > len(self._buf):
            self._buf.extend(bytes(end - len(self._buf)))
        self._used = end
        if ns < self._chunk_start:
            self._chunk_start = ns
        if ns > self._chunk_end:
            self._chunk_end = ns
        return pos

    def count(self, channel: int) -> int:
        """Messages on ``channel`` so far (the next one's sequence number)."""
        return self.tally.per_channel[channel]

    def add_block(self, data: bytes, index: Sequence[tuple[int, np.ndarray, np.ndarray]],
                  first: int, last: int) -> None:
        """Add ready Message records, sequence numbers counted on from :meth:`count`.

        ``index`` gives, per channel, each record's log time (ns) and offset in ``data``
        (arrays); ``first`` and ``last`` are the earliest and latest log times. The
        records go into the open chunk as they are, copied once.
        """
        pos = self._reserve(len(data), first)
        if last > self._chunk_end:
            self._chunk_end = last
        self._buf[pos:pos + len(data)] = data
        for channel, times, offsets in index:
            self._blocks[channel].append((times, offsets + pos))
            self.tally.count(channel, len(times))

    def tick(self) -> None:
        """Close the open chunk if it is full or has been open for ``max_age`` of wall time."""
        if self._used >= self._chunk_size or self._clock() >= self._close_at:
            self.close_chunk()

    def close_chunk(self) -> None:
        """Write the open chunk and its message indexes to the file (if it has messages)."""
        from mcap.records import ChunkIndex

        self._close_at = self._clock() + self._max_age
        used = self._used
        if not used:
            return
        with memoryview(self._buf) as whole, whole[:used] as raw:
            # compressed, checked and written from the buffer itself: no copy
            data = self._compress(raw) if self._compress is not None else raw
            start, end = self._chunk_start, self._chunk_end
            chunk_offset = self._pos
            # the Chunk record packed directly (the library's writer copies it through a
            # seekable buffer twice): start, end, uncompressed size and CRC, compression,
            # data
            comp = self._compression.encode()
            head = _CHUNK_HEAD.pack(_CHUNK_OP, 8 + 8 + 8 + 4 + 4 + len(comp) + 8 + len(data),
                                    start, end, used, zlib.crc32(raw), len(comp))
            pieces = [head, comp, struct.pack("<Q", len(data)), data]
            chunk_length = len(head) + len(comp) + 8 + len(data)
            index_offsets: dict[int, int] = {}
            at = chunk_offset + chunk_length
            for ch, body in self._index_bodies():
                piece = _INDEX_HEAD.pack(_INDEX_OP, 6 + len(body), ch, len(body)) + body
                index_offsets[ch] = at
                at += len(piece)
                pieces.append(piece)
            self._used = 0
            self._chunk_start, self._chunk_end = 2**64 - 1, 0
            self.tally.span(start, end)
            # one write: the chunk and its indexes reach the OS together
            self._out_all(pieces)
            size = len(data)
            del data, pieces  # no view of the buffer outlives the write
        self._chunk_index.append(ChunkIndex(
            message_start_time=start, message_end_time=end, chunk_start_offset=chunk_offset,
            chunk_length=chunk_length, message_index_offsets=index_offsets,
            message_index_length=at - chunk_offset - chunk_length,
            compression=self._compression, compressed_size=size, uncompressed_size=used))

    def _index_bodies(self) -> list[tuple[int, bytes]]:
        """Return the open chunk's message index entries per channel (and forget them)."""
        out = []
        for ch, (entries, blocks) in enumerate(zip(self._entries, self._blocks, strict=True)):
            if not (entries or blocks):
                continue
            tables = [np.asarray(entries, dtype="<u8")] if entries else []
            if blocks:
                times = np.concatenate([t for t, _ in blocks])
                table = np.empty((len(times), 2), "<u8")
                table[:, 0] = times
                table[:, 1] = np.concatenate([o for _, o in blocks])
                tables.append(table)
            table = tables[0] if len(tables) == 1 else np.concatenate(tables)
            if entries and blocks:  # both ways on one channel: in the chunk's order
                table = table[np.argsort(table[:, 1], kind="stable")]
            out.append((ch, table.tobytes()))
            entries.clear()
            blocks.clear()
        return out

    # ------------------------------------------------------------------ the end

    @property
    def message_count(self) -> int:
        """Messages added so far."""
        return self.tally.messages

    def channel_counts(self) -> dict[int, int]:
        """Messages per channel id so far."""
        return self.tally.channel_counts()

    @property
    def time_range(self) -> tuple[int, int] | None:
        """(first, last) log time of the messages so far (ns), None without messages."""
        if not self.tally.messages:
            return None
        return (min(self.tally.first, self._chunk_start), max(self.tally.last, self._chunk_end))

    def finish(self) -> None:
        """Close the last chunk, write the summary and footer, close the file."""
        from mcap.opcode import Opcode
        from mcap.records import DataEnd, Footer, Statistics, SummaryOffset

        if self.finished or self._file is None:
            return
        self.close_chunk()
        DataEnd(data_section_crc=0).write(self._builder)
        self._emit()
        summary_start = self._pos
        b = self._builder
        offsets = []

        def group(opcode: int, records: list[object]) -> None:
            if not records:
                return
            start = b.count
            for r in records:
                r.write(b)  # type: ignore[attr-defined]
            offsets.append(SummaryOffset(group_opcode=opcode, group_start=summary_start + start,
                                         group_length=b.count - start))

        span = self.time_range or (0, 0)
        stats = Statistics(
            message_count=self.tally.messages, schema_count=len(self._schemas),
            channel_count=len(self._channels), attachment_count=0,
            metadata_count=len(self._metadata_index), chunk_count=len(self._chunk_index),
            message_start_time=span[0], message_end_time=span[1],
            channel_message_counts={i: n for i, n in self.channel_counts().items() if n})
        group(Opcode.SCHEMA, self._schemas)
        group(Opcode.CHANNEL, self._channels)
        group(Opcode.STATISTICS, [stats])
        group(Opcode.CHUNK_INDEX, self._chunk_index)
        group(Opcode.METADATA_INDEX, self._metadata_index)
        offset_start = summary_start + b.count
        for o in offsets:
            o.write(b)
        summary = b.end()
        crc = zlib.crc32(summary)
        crc = zlib.crc32(struct.pack("<BQQQ", Opcode.FOOTER, 20, summary_start, offset_start),
                         crc)
        self._out(summary)
        Footer(summary_start=summary_start, summary_offset_start=offset_start,
               summary_crc=crc).write(self._builder)
        self._emit()
        self._out(MAGIC)
        self.finished = True
        self.close()

    def close(self) -> None:
        """Close the file as it stands (after :meth:`finish`, or to abandon it)."""
        if self._file is not None:
            try:
                self._file.close()
            finally:
                self._file = None
