"""Byte streams to robots and sensors: TCP sockets and serial lines, named by URLs.

URLs ``mdle run`` accepts:

* ``tcp://HOST:PORT``: a TCP connection (MobileSim/AMRISim listen on 8101, the default).
* ``serial:///dev/ttyUSB0?baud=9600``: a serial line (``serial://COM3`` on Windows);
  without ``baud`` the robot driver probes the usual rates.
* ``lms200:///dev/ttyUSB1?baud=38400``: a SICK LMS-200 on its own serial line; ``baud``
  is the rate to run at (the driver finds the scanner's current rate and switches).
* ``sim``: the Pioneer simulators' laser, delivered over the robot connection.

Any other query parameter is kept in :attr:`Endpoint.options` for the driver (for
example ``tcp://localhost:8101?model=p3dx`` or ``sim?max_range=8``). Serial lines need
pyserial (``pip install 'mdle[serial]'``), imported only when a serial URL is opened.
"""

from __future__ import annotations

import select
import socket
import sys
import threading
import time
import urllib.parse
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

from mdle.core.errors import BackendError

__all__ = [
    "DEFAULT_TCP_PORT",
    "Endpoint",
    "SerialTransport",
    "TcpTransport",
    "Transport",
    "TransportClosed",
    "open_transport",
    "parse_url",
    "read_or_fail",
]

DEFAULT_TCP_PORT = 8101
_SCHEMES = ("tcp", "serial", "lms200", "sim")
#: Fastest serial rate a URL may ask for (beyond any UART a robot or laser has).
_MAX_BAUD = 4_000_000


@dataclass(frozen=True)
class Endpoint:
    """A parsed connection URL.

    ``scheme`` is ``tcp``, ``serial``, ``lms200`` or ``sim``; ``host``/``port`` for TCP;
    ``path`` (device) and ``baud`` (None: not given) for serial lines; ``options`` the
    other query parameters as strings.
    """

    scheme: str
    url: str
    host: str = ""
    port: int = 0
    path: str = ""
    baud: int | None = None
    options: dict[str, str] = field(default_factory=dict)


def parse_url(url: str) -> Endpoint:
    """Parse a connection URL; raises BackendError naming the URL and what is wrong.

    >>> parse_url("tcp://localhost:8101").port
    8101
    >>> parse_url("serial:///dev/ttyUSB0?baud=9600").baud
    9600
    """
    text = url.strip()
    if text == "sim" or text.startswith("sim?"):
        query = text[4:]
        return Endpoint("sim", text, options=_options(text, query))
    try:
        parts = urllib.parse.urlsplit(text)
    except ValueError as exc:  # e.g. an unclosed IPv6 bracket: tcp://[::1
        raise BackendError(f"cannot use connection `{url}`: {exc}") from None
    scheme = parts.scheme.lower()
    if scheme not in _SCHEMES or "://" not in text:
        raise BackendError(f"cannot use connection `{url}`: expected tcp://HOST:PORT, "
                           f"serial:///dev/DEVICE?baud=N, lms200:///dev/DEVICE?baud=N or sim")
    options = _options(text, parts.query)
    baud = None
    if "baud" in options:
        raw = options.pop("baud")
        try:
            baud = int(raw)
        except ValueError:
            raise BackendError(f"cannot use connection `{url}`: baud `{raw}` is not a "
                               f"whole number") from None
        if baud <= 0:
            raise BackendError(f"cannot use connection `{url}`: baud must be positive")
        if baud > _MAX_BAUD:
            raise BackendError(f"cannot use connection `{url}`: baud must be at most "
                               f"{_MAX_BAUD}, got {raw}")
    if scheme == "tcp":
        if not parts.hostname:
            raise BackendError(f"cannot use connection `{url}`: no host (tcp://HOST:PORT)")
        try:
            port = parts.port
        except ValueError:
            port = 0
        if port is None:
            port = DEFAULT_TCP_PORT
        elif not 1 <= port <= 65535:
            raise BackendError(f"cannot use connection `{url}`: the port is not a number "
                               f"in 1..65535")
        return Endpoint("tcp", text, host=parts.hostname, port=port, options=options)
    # serial:///dev/ttyUSB0 has an empty netloc; serial://COM3 keeps the device there
    path = (parts.netloc + parts.path) if parts.netloc else parts.path
    if not path:
        raise BackendError(f"cannot use connection `{url}`: no device "
                           f"(e.g. {scheme}:///dev/ttyUSB0)")
    return Endpoint(scheme, text, path=path, baud=baud, options=options)


def _options(url: str, query: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for key, value in urllib.parse.parse_qsl(query, keep_blank_values=True):
        if key in out:
            raise BackendError(f"cannot use connection `{url}`: `{key}` given twice")
        out[key] = value
    return out


class TransportClosed(Exception):
    """The stream ended or failed; the message says how (callers name the stream)."""


class Transport(Protocol):
    """A bidirectional byte stream.

    ``read`` may run in one thread while ``write`` runs in another.
    """

    description: str

    def read(self, timeout: float) -> bytes:
        """Return the bytes available within ``timeout`` seconds (``b""`` if none).

        Raises TransportClosed when the stream has ended.
        """
        ...

    def write(self, data: bytes) -> None:
        """Send all of ``data``; raises TransportClosed on failure."""
        ...

    def set_baud(self, baud: int) -> None:
        """Change the line rate (serial lines only)."""
        ...

    def close(self) -> None:
        """Release the stream (idempotent)."""
        ...

    def finish(self, timeout: float) -> None:
        """End the stream gracefully, then release it (idempotent, never raises).

        Everything written reaches the other end before the stream closes: waits at most
        ``timeout`` seconds for the bytes to leave and for the other end to finish.
        """
        ...


def read_or_fail(transport: Transport, timeout: float,
                 fail: Callable[[str], None]) -> bytes | None:
    """Read for a reader thread, which must never raise.

    Parameters
    ----------
    transport : Transport
    timeout : float
        Longest wait for bytes, seconds.
    fail : callable
        Called with the reason when the stream has ended or the transport itself failed.

    Returns
    -------
    bytes or None
        The bytes read (``b""`` if none came within ``timeout``), or None after ``fail``.
    """
    try:
        return transport.read(timeout)
    except TransportClosed as exc:
        fail(str(exc))
    except Exception as exc:  # noqa: BLE001 - a transport bug must end the reader, loudly
        fail(f"reading failed: {exc!r}")
    return None


class TcpTransport:
    """A TCP connection (plain socket); writes time out after ``write_timeout`` s."""

    def __init__(self, host: str, port: int, *, connect_timeout: float = 5.0,
                 write_timeout: float = 1.0) -> None:
        self.description = f"tcp://{host}:{port}"
        try:
            self._sock = socket.create_connection((host, port), timeout=connect_timeout)
        except OSError as exc:
            raise BackendError(f"cannot connect to {self.description}: "
                               f"{exc.strerror or exc} (is the robot or MobileSim/AMRISim "
                               f"running and listening there?)") from None
        self._sock.settimeout(write_timeout)
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._closed = False

    def read(self, timeout: float) -> bytes:
        """See :meth:`Transport.read`."""
        if self._closed:
            raise TransportClosed("connection closed")
        try:
            ready, _, _ = select.select([self._sock], [], [], max(0.0, timeout))
            if not ready:
                return b""
            data = self._sock.recv(65536)
        except (OSError, ValueError) as exc:
            raise TransportClosed(_why(exc)) from None
        if not data:
            raise TransportClosed("the other end closed the connection")
        return data

    def write(self, data: bytes) -> None:
        """See :meth:`Transport.write`."""
        if self._closed:
            raise TransportClosed("connection closed")
        try:
            self._sock.sendall(data)
        except OSError as exc:
            raise TransportClosed(_why(exc)) from None

    def set_baud(self, baud: int) -> None:
        """Do nothing: a TCP stream has no line rate."""

    def close(self) -> None:
        """See :meth:`Transport.close`."""
        if self._closed:
            return
        self._closed = True
        try:
            self._sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        self._sock.close()

    def finish(self, timeout: float) -> None:
        """Send FIN after the last bytes, read until the peer closes, then close.

        Closing a socket whose input was not all read makes the kernel send a reset (RST)
        instead of a FIN, and a reset can destroy the bytes the peer has not read yet: a
        server reading slowly would lose the final STOP and CLOSE. So: shut the sending
        side (the peer reads everything, then end of stream), then read and discard what
        still comes (SIPs in flight) until the peer closes its side or ``timeout`` passes.
        """
        if self._closed:
            return
        try:
            self._sock.shutdown(socket.SHUT_WR)
            deadline = time.monotonic() + timeout
            while (left := deadline - time.monotonic()) > 0:
                ready, _, _ = select.select([self._sock], [], [], left)
                if ready and not self._sock.recv(65536):
                    break  # the peer has read everything and closed: a clean end
        except (OSError, ValueError):
            pass  # reset or already gone: nothing more to hand over
        self.close()


def _why(exc: BaseException) -> str:
    """Say what an I/O error was, without the errno prefix when there is a text."""
    text = getattr(exc, "strerror", None)
    return str(text).lower() if text else str(exc)


def _import_serial() -> Any:
    try:
        import serial
    except ImportError:
        raise BackendError("serial lines need pyserial, which is not installed: "
                           "run `pip install 'mdle[serial]'` (or `pip install pyserial`)"
                           ) from None
    return serial


class SerialTransport:
    """A serial line through pyserial (8N1, no flow control)."""

    def __init__(self, path: str, baud: int = 9600, *, write_timeout: float = 1.0) -> None:
        serial = _import_serial()
        self.description = f"{path} at {baud} baud"
        self._path = path
        errors: list[type[BaseException]] = [serial.SerialException, OSError, ValueError,
                                             TypeError]
        try:  # pyserial lets termios.error (not an OSError) through from tcdrain and friends
            import termios

            errors.append(termios.error)
        except ImportError:
            pass
        self._errors = tuple(errors)
        try:
            self._ser = serial.Serial(path, baud, timeout=0, write_timeout=write_timeout)
        except self._errors as exc:
            raise BackendError(f"cannot open serial line {path}: {exc}") from None
        # select() works on serial file descriptors on POSIX; elsewhere poll with a timeout
        self._selectable = sys.platform != "win32"
        self._closed = False

    def read(self, timeout: float) -> bytes:
        """See :meth:`Transport.read`."""
        if self._closed:
            raise TransportClosed("serial line closed")
        try:
            if self._selectable:
                ready, _, _ = select.select([self._ser.fileno()], [], [], max(0.0, timeout))
                if not ready:
                    return b""
                return bytes(self._ser.read(max(1, self._ser.in_waiting)))
            waiting = self._ser.in_waiting
            if waiting:
                return bytes(self._ser.read(waiting))
            self._ser.timeout = timeout
            data = bytes(self._ser.read(1))
            self._ser.timeout = 0
            return data
        except self._errors as exc:
            raise TransportClosed(_why(exc)) from None

    def write(self, data: bytes) -> None:
        """See :meth:`Transport.write`."""
        if self._closed:
            raise TransportClosed("serial line closed")
        try:
            # no flush(): waiting for the bytes to leave (tcdrain) would block the tick
            self._ser.write(data)
        except self._errors as exc:
            raise TransportClosed(_why(exc)) from None

    def set_baud(self, baud: int) -> None:
        """See :meth:`Transport.set_baud`."""
        try:
            self._ser.reset_input_buffer()
            self._ser.baudrate = baud
        except self._errors as exc:
            raise TransportClosed(f"cannot set {baud} baud: {_why(exc)}") from None
        self.description = f"{self._path} at {baud} baud"

    def close(self) -> None:
        """See :meth:`Transport.close`."""
        if self._closed:
            return
        self._closed = True
        try:
            self._ser.close()
        except self._errors:
            pass

    def finish(self, timeout: float) -> None:
        """Let the written bytes leave the line (bounded), then close.

        A serial line has no end-of-stream to send: waiting until the output queue is
        empty is all there is. pyserial's ``flush`` (tcdrain) has no timeout, so it runs
        in a helper thread and is waited for ``timeout`` seconds at most.
        """
        if self._closed:
            return
        done = threading.Event()

        def drain() -> None:
            try:
                self._ser.flush()
            except self._errors:
                pass
            done.set()

        threading.Thread(target=drain, name="mdle-serial-drain", daemon=True).start()
        done.wait(timeout)
        self.close()


def open_transport(endpoint: Endpoint, *, baud: int | None = None,
                   connect_timeout: float = 5.0) -> Transport:
    """Open the byte stream an endpoint names (``baud`` overrides the URL's for serial)."""
    if endpoint.scheme == "tcp":
        return TcpTransport(endpoint.host, endpoint.port, connect_timeout=connect_timeout)
    if endpoint.scheme in ("serial", "lms200"):
        return SerialTransport(endpoint.path, baud or endpoint.baud or 9600)
    raise BackendError(f"`{endpoint.url}` is not a byte stream (sim rides on the robot's "
                       f"connection)")
