"""Where a run's ROS 2 messages go: an MCAP file, live views, or both, from one source.

:class:`~mdle.record.topics.RosRecording` (and :class:`~mdle.record.tick.TickEncoder`) make
each message once and hand it to an :class:`Outlet`, which gives the very same bytes to
the MCAP file (``--record``, ``--rosbag``) and to every live sink (``--foxglove``):
what a recording holds is what the live view showed. Several recordings (a team's
robots) may share one outlet, so they share one file and one live view.

A live sink is any object with the :class:`LiveSink` methods; the outlet registers
each schema and channel with it, then calls :meth:`LiveSink.add` with a message's CDR
bytes. Ticks come in blocks of ready MCAP Message records
(:meth:`Outlet.add_block`); the outlet cuts the messages out of them for the sinks.
"""

from __future__ import annotations

import struct
from collections.abc import Mapping, Sequence
from typing import Protocol

import numpy as np

from mdle.record.mcap_file import McapFile, MessageTally

__all__ = ["LiveSink", "Outlet"]

_LENGTH = struct.Struct("<Q")


class LiveSink(Protocol):
    """A live view of the messages (a WebSocket server, say)."""

    def channel(self, channel_id: int, topic: str, schema_name: str, schema_data: bytes,
                latched: bool) -> None:
        """Register a channel: its id, topic, ``ros2msg`` schema, and QoS durability."""

    def add(self, channel_id: int, ns: int, data: bytes) -> None:
        """Publish one CDR message logged at ``ns`` (nanoseconds)."""

    def tick(self) -> None:
        """Catch up on requests, between batches (from the run's thread)."""

    def close(self) -> None:
        """Stop serving."""


class Outlet:
    """Hand every message to an MCAP file (optional) and to live sinks.

    Parameters
    ----------
    file : McapFile or None
        The recording, if one was asked for.
    live : sequence of LiveSink
        Live views.

    It offers the part of :class:`~mdle.record.mcap_file.McapFile`'s interface that a
    recording uses, and counts messages itself (sequence numbers, time range) so that a
    live view works without a file. Schemas are registered once per name and text, so
    recordings sharing the outlet share them.
    """

    def __init__(self, file: McapFile | None = None, live: Sequence[LiveSink] = ()) -> None:
        self.file = file
        self.live = list(live)
        self._schemas: dict[tuple[str, bytes], int] = {}
        self._schema_of: dict[int, tuple[str, bytes]] = {}
        self._topics: dict[str, int] = {}
        self.tally = MessageTally()
        self.finished = False

    # ------------------------------------------------------------------ registration

    def schema(self, name: str, encoding: str, data: bytes) -> int:
        """Register a schema (once per name and text); returns its id."""
        key = (name, data)
        found = self._schemas.get(key)
        if found is not None:
            return found
        sid = self.file.schema(name, encoding, data) if self.file is not None \
            else len(self._schemas) + 1
        self._schemas[key] = sid
        self._schema_of[sid] = key
        return sid

    def channel(self, topic: str, schema_id: int, message_encoding: str = "cdr",
                metadata: Mapping[str, str] | None = None, *, latched: bool = False) -> int:
        """Register a channel; returns its id. A topic may be registered only once."""
        if topic in self._topics:
            raise ValueError(f"the topic {topic} is registered twice")
        cid = self.file.channel(topic, schema_id, message_encoding, metadata) \
            if self.file is not None else len(self.tally.per_channel)
        if cid != self.tally.add_channel():
            raise AssertionError("the file's channel ids and the outlet's disagree")
        self._topics[topic] = cid
        name, data = self._schema_of[schema_id]
        for sink in self.live:
            sink.channel(cid, topic, name, data, latched)
        return cid

    def has(self, topic: str) -> bool:
        """Return True when ``topic`` is registered."""
        return topic in self._topics

    def metadata(self, name: str, data: Mapping[str, str]) -> None:
        """Write a Metadata record into the file (a live view has none)."""
        if self.file is not None:
            self.file.metadata(name, data)

    # ------------------------------------------------------------------ messages

    def count(self, channel: int) -> int:
        """Messages on ``channel`` so far (the next one's sequence number)."""
        return self.tally.per_channel[channel]

    def add(self, channel: int, ns: int, data: bytes) -> None:
        """Add a message on ``channel`` logged at ``ns``."""
        if self.file is not None:
            self.file.add(channel, ns, data)
        self.tally.count(channel)
        self.tally.span(ns, ns)
        for sink in self.live:
            sink.add(channel, ns, data)

    def add_block(self, data: bytes, index: Sequence[tuple[int, np.ndarray, np.ndarray]],
                  first: int, last: int) -> None:
        """Add ready Message records (see :meth:`McapFile.add_block`)."""
        if self.file is not None:
            self.file.add_block(data, index, first, last)
        for channel, times, _ in index:
            self.tally.count(channel, len(times))
        self.tally.span(first, last)
        if not self.live:
            return
        # the messages in the block's order: (offset, channel, log time)
        found = sorted((int(o), ch, int(t)) for ch, times, offsets in index
                       for t, o in zip(times.tolist(), offsets.tolist(), strict=True))
        for offset, channel, ns in found:
            length = _LENGTH.unpack_from(data, offset + 1)[0]
            body = data[offset + 31:offset + 9 + length]  # after the 22 bytes of fields
            for sink in self.live:
                sink.add(channel, ns, body)

    def tick(self) -> None:
        """Between batches: the file may close its chunk, live sinks catch up."""
        if self.file is not None:
            self.file.tick()
        for sink in self.live:
            sink.tick()

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
        return self.tally.time_range

    def finish(self) -> None:
        """End the file (summary, index) and stop the live sinks."""
        if self.finished:
            return
        self.finished = True
        try:
            if self.file is not None:
                self.file.finish()
        finally:
            self._stop_live()

    def close(self) -> None:
        """Abandon the file as it stands and stop the live sinks."""
        self.finished = True
        try:
            if self.file is not None:
                self.file.close()
        finally:
            self._stop_live()

    def _stop_live(self) -> None:
        sinks, self.live = self.live, []
        for sink in sinks:
            sink.close()
