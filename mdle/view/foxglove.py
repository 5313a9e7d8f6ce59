"""``mdle run --foxglove [HOST:]PORT``: a live view of the run in Foxglove, over WebSocket.

A :class:`FoxgloveServer` serves, through a :class:`FoxgloveSink` per run, the run's ROS 2
messages (the very bytes a recording
holds: :mod:`mdle.record.outlet`) with the foxglove-sdk's WebSocket server (the
``foxglove.websocket.v1`` protocol), each topic a channel of ``cdr`` messages with its
``ros2msg`` schema, so the Foxglove app decodes them as it decodes the MCAP file.

The server has a context of its own (no global state), binds to 127.0.0.1 unless told
otherwise, and stops when the run ends. Latched topics (``/map``, ``/obstacles``,
``/tf_static`` published once, ``/mdle/active`` the current state) are sent again to a
client that subscribes later, at the run's next batch of ticks, as a ROS 2
transient-local publisher would.
"""

from __future__ import annotations

import threading
from typing import Any

from mdle.core.errors import Diagnostic, MdleError

try:  # the optional extra: without it, FoxgloveSink says how to install it
    from foxglove.websocket import ServerListener
except ImportError:  # pragma: no cover - the class is only made with the SDK
    ServerListener = object  # type: ignore[assignment,misc]

__all__ = ["DEFAULT_PORT", "FoxgloveServer", "FoxgloveSink", "LiveRuns", "parse_address"]

#: Foxglove's usual WebSocket port.
DEFAULT_PORT = 8765


def parse_address(text: str) -> tuple[str, int]:
    """Read ``[HOST:]PORT`` (``8765``, ``127.0.0.1:8765``, ``0.0.0.0:9000``).

    Port 0 picks a free port. Raises MdleError naming the option and the problem.
    """
    host, sep, port = text.rpartition(":")
    if not sep:
        host = "127.0.0.1"
    host = host.strip("[]") or "127.0.0.1"
    try:
        number = int(port)
    except ValueError:
        raise MdleError(Diagnostic(None, f"--foxglove `{text}`: expected [HOST:]PORT, "
                                         f"a port number, got `{port}`",
                                   hint=f"e.g. --foxglove {DEFAULT_PORT} or "
                                        f"--foxglove 127.0.0.1:{DEFAULT_PORT}")) from None
    if not 0 <= number <= 65535:
        raise MdleError(Diagnostic(None, f"--foxglove `{text}`: the port must be 0-65535"))
    return host, number


class FoxgloveServer:
    """A foxglove-sdk WebSocket server with a context of its own.

    Parameters
    ----------
    host, port : str, int
        Where to listen (port 0: a free one, see :attr:`port`).
    name : str
        The server's name, shown by Foxglove.

    Runs come and go (the REPL's): each run's :class:`FoxgloveSink` advertises its
    channels on the server and closes them when the run ends; :meth:`stop` ends the
    server.

    Raises
    ------
    MdleError
        The foxglove-sdk is not installed, or the server cannot listen there.
    """

    def __init__(self, host: str = "127.0.0.1", port: int = DEFAULT_PORT,
                 name: str = "mdle") -> None:
        try:
            import foxglove
        except ImportError:
            raise MdleError(Diagnostic(None, "--foxglove needs the foxglove-sdk",
                                       hint="pip install 'mdle[foxglove]'")) from None
        self.foxglove = foxglove
        self.context = foxglove.Context()
        self.sink: FoxgloveSink | None = None  # the run being shown
        try:
            self.server = foxglove.start_server(
                name=name, host=host, port=port, context=self.context,
                server_listener=_Listener(self))
        except Exception as exc:  # noqa: BLE001 - the SDK raises its own error types
            raise MdleError(Diagnostic(None, f"--foxglove: cannot listen on {host}:{port} "
                                             f"({exc})")) from None
        self.host = host
        self.stopped = False

    @property
    def port(self) -> int:
        """The port the server listens on."""
        return int(self.server.port)

    def subscribed(self, server_channel_id: int) -> None:
        """Note a subscription (the server's thread) for the run being shown."""
        sink = self.sink
        if sink is not None:
            sink.subscribed(server_channel_id)

    def stop(self) -> None:
        """Stop the server (clients see it close); safe to repeat."""
        if not self.stopped:
            self.stopped = True
            self.server.stop()


class FoxgloveSink:
    """One run's messages, served live (a :class:`~mdle.record.outlet.LiveSink`).

    ``server`` is the :class:`FoxgloveServer`; with ``owns_server`` (``mdle run``)
    closing the sink stops it, otherwise (the REPL) only this run's channels close.
    """

    def __init__(self, server: FoxgloveServer, owns_server: bool = False) -> None:
        self._server = server
        self._owns = owns_server
        self._channels: dict[int, Any] = {}
        self._by_server_id: dict[int, int] = {}
        self._latched: dict[int, tuple[bytes, int]] = {}
        self._latched_ids: set[int] = set()
        self._resend: set[int] = set()
        self._lock = threading.Lock()
        server.sink = self

    def channel(self, channel_id: int, topic: str, schema_name: str, schema_data: bytes,
                latched: bool) -> None:
        """Advertise a topic of CDR messages with its ``ros2msg`` schema."""
        fg = self._server.foxglove
        ch = fg.Channel(topic, message_encoding="cdr", context=self._server.context,
                        schema=fg.Schema(name=schema_name, encoding="ros2msg",
                                         data=schema_data))
        self._channels[channel_id] = ch
        self._by_server_id[int(ch.id())] = channel_id
        if latched:
            self._latched_ids.add(channel_id)

    def add(self, channel_id: int, ns: int, data: bytes) -> None:
        """Send a message to the clients subscribed to its topic."""
        if channel_id in self._latched_ids:  # kept first: a subscriber never misses it
            self._latched[channel_id] = (data, ns)
        self._channels[channel_id].log(data, log_time=ns)

    def subscribed(self, server_channel_id: int) -> None:
        """Note a subscription (the server's thread): a latched topic's message goes again."""
        channel_id = self._by_server_id.get(server_channel_id)
        # only a message sent before the subscription: a later one reaches the client
        if channel_id is not None and channel_id in self._latched:
            with self._lock:
                self._resend.add(channel_id)

    def tick(self) -> None:
        """Send latched messages again to clients that subscribed since the last call."""
        if not self._resend:
            return
        with self._lock:
            resend, self._resend = self._resend, set()
        for channel_id in sorted(resend):
            kept = self._latched.get(channel_id)
            if kept is not None:
                self._channels[channel_id].log(kept[0], log_time=kept[1])

    def close(self) -> None:
        """Close this run's channels (and the server, if this sink owns it)."""
        if self._server.sink is self:
            self._server.sink = None
        channels, self._channels = self._channels, {}
        for ch in channels.values():
            ch.close()
        if self._owns:
            self._server.stop()


class _Listener(ServerListener):
    """The server's callbacks: note subscriptions (they come on the server's thread)."""

    def __init__(self, server: FoxgloveServer) -> None:
        self._server = server

    def on_subscribe(self, client: Any, channel: Any) -> None:
        """Take a client's subscription to ``channel``."""
        self._server.subscribed(int(channel.id))


class LiveRuns:
    """An observer that shows every run of a session live (``mdle repl --foxglove``).

    Each run gets a recorder without a file (:class:`~mdle.record.recorder.McapRecorder`)
    whose messages go to ``server`` through a sink of its own: the run's channels are
    advertised when it starts and closed when it ends; the server stays up for the
    next run until :meth:`close`.
    """

    def __init__(self, server: FoxgloveServer) -> None:
        self.server = server
        self._run: Any = None  # the current run's recorder

    def on_start(self, scheduler: Any) -> None:
        """Advertise the run's topics and start recording it."""
        from mdle.record.describe import body_header
        from mdle.record.recorder import McapRecorder

        backend = scheduler.backend
        world = getattr(backend, "world", None)
        header: dict[str, Any] = {"backend": "sim" if world is not None else "robot",
                                  "rate": scheduler.rate, **body_header(backend)}
        if world is not None:
            header["world"] = {"name": getattr(world, "name", "")}
        self._run = McapRecorder(None, header, world, live=[FoxgloveSink(self.server)])
        self._run.on_start(scheduler)

    def on_event(self, event: Any) -> None:
        """Pass an element's start or end on."""
        if self._run is not None:
            self._run.on_event(event)

    def on_tick(self, sample: Any) -> None:
        """Pass a tick on."""
        if self._run is not None:
            self._run.on_tick(sample)

    def on_end(self, result: Any) -> None:
        """End the run: its last messages, then its channels close."""
        run, self._run = self._run, None
        if run is not None:
            run.on_end(result)

    def close(self) -> None:
        """Stop the server (after the session)."""
        run, self._run = self._run, None
        if run is not None:
            run.close()
        self.server.stop()
