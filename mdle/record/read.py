"""Read an MCAP recording of a run back as a trace (for plots, the REPL).

The file is read record by record with the mcap library's stream reader and the ROS 2
messages decoded with mcap-ros2-support: the header from the ``mdle`` Metadata record,
the ``start``, ``event`` and ``end`` records from ``/mdle/events``, the samples from
``/mdle/state``, the scans from ``/scan`` (their geometry as ``laser`` records, with the
mount from ``/tf_static``). A file cut off by a kill is read up to its last whole chunk
(``Trace.truncated``).
"""

from __future__ import annotations

import base64
import contextlib
import json
import math
import os
import struct
from typing import Any

from mdle.core.errors import Diagnostic, Span
from mdle.core.userfile import UserFileError, open_user_file, os_reason
from mdle.record import MissingExtraError, require
from mdle.record.trace import TRACE_FORMAT, TRACE_VERSION, Trace, TraceError

__all__ = ["read_recording"]


def _error(path: str, message: str, hint: str | None = None) -> TraceError:
    return TraceError(Diagnostic(Span(path, 1, 1, 1, 1), message, hint=hint))


def read_recording(path: str | os.PathLike[str]) -> Trace:
    """Read an MCAP file written by ``mdle run --record`` or ``mdle export``.

    ``path`` may also be a rosbag2 folder (``--rosbag``).

    Raises
    ------
    TraceError
        The MCAP libraries are missing, the file is not MCAP, or it is not an mdle
        recording (no ``/mdle/state`` topic).
    """
    path = os.fspath(path)
    try:
        require("reading an MCAP recording")
    except MissingExtraError as exc:
        raise TraceError(exc.diagnostics) from None
    source = path
    if os.path.isdir(path):
        from mdle.record.rosbag import mcap_in

        found = mcap_in(path)
        if found is None:
            raise _error(path, "no .mcap file in this rosbag2 folder")
        source = found

    try:  # a regular file only: a FIFO or a device is refused, not read until it ends
        f = open_user_file(source)
    except UserFileError as exc:
        raise TraceError(Diagnostic(None, f"cannot read `{source}`: {exc.reason}")) from None
    with f:
        try:
            return _read(path, f)
        except OSError as exc:
            raise TraceError(Diagnostic(None, f"cannot read `{source}`: "
                                              f"{os_reason(exc)}")) from None


def _read(path: str, f: Any) -> Trace:
    from mcap.exceptions import McapError
    from mcap.records import Channel, Message, Metadata, Schema
    from mcap.stream_reader import StreamReader
    from mcap_ros2.decoder import DecoderFactory

    factory = DecoderFactory()
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    decoders: dict[int, Any] = {}
    header: dict[str, Any] | None = None
    events: list[dict[str, Any]] = []
    samples: list[dict[str, Any]] = []
    extra: list[dict[str, Any]] = []
    lasers: list[dict[str, Any]] = []
    scans: list[dict[str, Any]] = []
    end: dict[str, Any] | None = None
    mount = [0.0, 0.0, 0.0]
    geometry: tuple[Any, ...] | None = None
    truncated = False
    has_state = False
    reader = StreamReader(f, validate_crcs=True, record_size_limit=1 << 30)
    try:
        for record in reader.records:
            if isinstance(record, Schema):
                schemas[record.id] = record
            elif isinstance(record, Channel):
                channels[record.id] = record
                has_state = has_state or record.topic == "/mdle/state"
            elif isinstance(record, Metadata) and record.name == "mdle":
                try:
                    header = json.loads(record.metadata.get("header", ""))
                except json.JSONDecodeError:
                    header = None
            elif isinstance(record, Message):
                ch = channels.get(record.channel_id)
                if ch is None:
                    continue
                topic = ch.topic
                if topic not in ("/mdle/state", "/mdle/events", "/scan", "/tf_static"):
                    continue
                dec = decoders.get(ch.id)
                if dec is None:
                    dec = decoders[ch.id] = _decoder(factory, ch.message_encoding,
                                                     schemas.get(ch.schema_id))
                if dec is None:
                    continue
                msg = dec(record.data)
                if topic == "/mdle/state":
                    samples.append(json.loads(msg.data))
                elif topic == "/mdle/events":
                    rec = json.loads(msg.data)
                    kind = rec.get("type")
                    if kind == "event":
                        events.append(rec)
                    elif kind == "end":
                        end = rec
                    else:
                        extra.append(rec)
                elif topic == "/tf_static":
                    for tr in msg.transforms:
                        if tr.child_frame_id == "laser":
                            q = tr.transform.rotation
                            mount = [tr.transform.translation.x, tr.transform.translation.y,
                                     2.0 * math.atan2(q.z, q.w)]
                else:
                    g = (msg.angle_min, msg.angle_max, msg.angle_increment, len(msg.ranges),
                         msg.range_min, msg.range_max, msg.scan_time, msg.time_increment,
                         tuple(mount))
                    if g != geometry:
                        geometry = g
                        lasers.append({"type": "laser", "frame": msg.header.frame_id,
                                       "mount": list(mount), "angle_min": msg.angle_min,
                                       "angle_max": msg.angle_max,
                                       "angle_increment": msg.angle_increment,
                                       "count": len(msg.ranges), "range_min": msg.range_min,
                                       "range_max": msg.range_max, "scan_time": msg.scan_time,
                                       "time_increment": msg.time_increment})
                    stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
                    ranges = struct.pack(f"<{len(msg.ranges)}f", *msg.ranges)
                    scans.append({"type": "scan", "t": record.log_time / 1e9, "stamp": stamp,
                                  "ranges": base64.b64encode(ranges).decode("ascii")})
    except (McapError, EOFError, struct.error, ValueError) as exc:
        if not channels:  # not even the start of an MCAP file
            raise _error(path, f"not a readable MCAP file ({type(exc).__name__}: {exc})"
                         ) from None
        truncated = True  # cut short (a kill) or damaged: what came before it stands
    except Exception as exc:  # the library's EndOfFile and record errors
        if type(exc).__name__ != "EndOfFile" or not channels:
            raise _error(path, f"not a readable MCAP file ({type(exc).__name__}: {exc})"
                         ) from None
        truncated = True
    robots = sorted(c.topic[1:-len("/mdle/state")] for c in channels.values()
                    if c.topic.endswith("/mdle/state") and c.topic != "/mdle/state")
    if not has_state and robots:
        raise _error(path, f"a team's recording (robots {', '.join(robots)}): it is read "
                           "robot by robot in Foxglove, PlotJuggler or rosbags",
                     hint="for mdle plot, write the team's traces: mdle run --team ... "
                          "--trace run.jsonl gives run.NAME.jsonl")
    if not has_state:
        raise _error(path, "not an mdle recording: no /mdle/state topic",
                     hint="mdle reads the MCAP files `mdle run --record` and `mdle export` "
                          "write")
    if header is None:
        header = {}
    header = {"type": "header", "format": TRACE_FORMAT, "version": TRACE_VERSION,
              **{k: v for k, v in header.items() if k not in ("type", "format")}}
    return Trace(path, header, tuple(events), tuple(samples), end, truncated, tuple(extra),
                 tuple(lasers), tuple(scans))


def _decoder(factory: Any, encoding: str, schema: Any) -> Any:
    """Return the library's decoder for a channel, keeping its words off standard error.

    The ROS 2 message parser prints ``Error processing ...`` on standard error before it
    raises on a damaged schema; the raise becomes mdle's own message, the print is dropped.
    """
    import io

    with contextlib.redirect_stderr(io.StringIO()):
        return factory.decoder_for(encoding, schema)
