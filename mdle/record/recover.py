"""``mdle recover``: a recording cut off by a kill or a power cut, made whole again.

A killed ``mdle run --record`` leaves an MCAP file without its summary and footer (and a
``--rosbag`` folder without ``metadata.yaml``), which the usual readers refuse. Every
chunk closed before the kill is whole on disk (:mod:`mdle.record.mcap_file`), so the file
is read record by record, CRCs checked, up to the first record that is cut short or
damaged; schemas, channels, metadata and the messages of every whole chunk are written
again, with the mcap library's writer, into a finished file (summary, indexes, footer).
The file is replaced only once the new one is complete. A rosbag2 folder also gets its
``metadata.yaml`` (:mod:`mdle.record.rosbag`).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

from mdle.core.errors import Diagnostic, MdleError

__all__ = ["RecoverReport", "recover"]


@dataclass(frozen=True)
class RecoverReport:
    """What :func:`recover` did.

    ``path`` the MCAP file written, ``messages`` its messages, ``complete`` True when
    the file was finished already (nothing lost), ``span`` the first and last log time
    (ns), ``counts`` messages per topic, ``stopped`` why reading stopped (empty when
    the file was read to its end).
    """

    path: str
    messages: int
    complete: bool
    span: tuple[int, int] | None
    counts: dict[str, int] = field(default_factory=dict)
    stopped: str = ""


def recover(source: str | os.PathLike[str], output: str | os.PathLike[str] | None = None
            ) -> RecoverReport:
    """Make a cut-off recording (an MCAP file or a rosbag2 folder) readable.

    ``output`` (an MCAP file) keeps the source as it is; without it the source is
    replaced. Raises MdleError when the source is not an MCAP recording.
    """
    from mdle.record import require

    require("mdle recover")
    src = os.fspath(source)
    folder = src if os.path.isdir(src) else None
    if folder is not None:
        mcaps = sorted(p for p in os.listdir(folder) if p.endswith(".mcap"))
        if not mcaps:
            raise MdleError(Diagnostic(None, f"`{src}`: no .mcap file in this folder"))
        src = os.path.join(folder, mcaps[0])
    try:
        with open(src, "rb") as f:
            data = f.read()
    except OSError as exc:
        raise MdleError(Diagnostic(None, f"cannot read `{src}`: {exc.strerror}")) from None
    from mdle.record.mcap_file import MAGIC

    if not data.startswith(MAGIC):
        raise MdleError(Diagnostic(None, f"`{src}` is not an MCAP file (no MCAP magic at "
                                         "its start)"))
    complete = len(data) >= 16 and data.endswith(MAGIC)
    target = os.fspath(output) if output is not None else src
    tmp = target + ".recovering"
    try:
        report = _rewrite(src, data, tmp, complete)
        os.replace(tmp, target)
    except OSError as exc:
        raise MdleError(Diagnostic(None, f"cannot write `{target}`: {exc.strerror}")) \
            from None
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    report = RecoverReport(target, report.messages, report.complete, report.span,
                           report.counts, report.stopped)
    if folder is not None and output is None:
        _bag_metadata(folder, os.path.basename(target), report)
    return report


def _rewrite(src: str, data: bytes, out: str, complete: bool) -> RecoverReport:
    """Write every whole record of ``data`` into a finished MCAP file ``out``."""
    import io

    from mcap.records import Channel, Header, Message, Metadata, Schema
    from mcap.stream_reader import StreamReader
    from mcap.writer import CompressionType, Writer

    channels: dict[int, Channel] = {}
    schema_ids: dict[int, int] = {}
    channel_ids: dict[int, int] = {}
    counts: dict[str, int] = {}
    first, last, n = 2**64 - 1, 0, 0
    stopped = ""
    with open(out, "wb") as f:
        writer = Writer(f, compression=CompressionType.LZ4)
        started = False
        try:
            for record in StreamReader(io.BytesIO(data), validate_crcs=True,
                                       record_size_limit=1 << 30).records:
                if isinstance(record, Header):
                    writer.start(profile=record.profile, library=record.library)
                    started = True
                elif isinstance(record, Schema):
                    schema_ids[record.id] = writer.register_schema(
                        record.name, record.encoding, record.data)
                elif isinstance(record, Channel):
                    channels[record.id] = record
                    channel_ids[record.id] = writer.register_channel(
                        record.topic, record.message_encoding,
                        schema_ids.get(record.schema_id, 0), dict(record.metadata))
                elif isinstance(record, Metadata):
                    writer.add_metadata(record.name, dict(record.metadata))
                elif isinstance(record, Message) and record.channel_id in channel_ids:
                    writer.add_message(channel_ids[record.channel_id], record.log_time,
                                       record.data, record.publish_time, record.sequence)
                    topic = channels[record.channel_id].topic
                    counts[topic] = counts.get(topic, 0) + 1
                    first, last, n = min(first, record.log_time), max(last, record.log_time), \
                        n + 1
        except Exception as exc:  # noqa: BLE001 - the library's EndOfFile, CRC, record errors
            if not started:
                raise MdleError(Diagnostic(None, f"`{src}` is not a readable MCAP file "
                                                 f"({type(exc).__name__})")) from None
            stopped = f"{type(exc).__name__} {exc}".strip()
        if not started:
            raise MdleError(Diagnostic(None, f"`{src}` has no MCAP header"))
        writer.finish()
    return RecoverReport(out, n, complete and not stopped, (first, last) if n else None,
                         counts, stopped)


def _bag_metadata(folder: str, name: str, report: RecoverReport) -> None:
    """Write a rosbag2 folder's ``metadata.yaml`` from the recovered file's channels."""
    from mdle.record.rosbag import write_metadata
    from mdle.record.topics import Topic

    topics = []
    for topic, kind, qos in _channels(os.path.join(folder, name)):
        topics.append(Topic(topic, kind, latched="durability: 1" in qos))
    write_metadata(folder, name, topics, report.counts, report.span or (0, 0))


def _channels(path: str) -> list[tuple[str, str, str]]:
    """Return (topic, type, offered QoS text) of each channel of a finished MCAP file."""
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    if summary is None:
        return []
    out: list[tuple[str, str, str]] = []
    for ch in summary.channels.values():
        schema = summary.schemas.get(ch.schema_id)
        out.append((ch.topic, schema.name if schema is not None else "",
                    ch.metadata.get("offered_qos_profiles", "")))
    return out
