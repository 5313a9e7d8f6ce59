"""Connection URLs and the TCP / serial byte streams."""

from __future__ import annotations

import os
import socket
import termios
import tty

import pytest

from mdle.core.errors import BackendError
from mdle.drivers.transport import (
    DEFAULT_TCP_PORT,
    SerialTransport,
    TcpTransport,
    TransportClosed,
    parse_url,
)


@pytest.mark.parametrize("url,scheme,host,port,path,baud,options", [
    ("tcp://localhost:8101", "tcp", "localhost", 8101, "", None, {}),
    ("tcp://10.0.0.7", "tcp", "10.0.0.7", DEFAULT_TCP_PORT, "", None, {}),
    ("tcp://robot:9000?model=p3dx&dist_conv=0.5", "tcp", "robot", 9000, "", None,
     {"model": "p3dx", "dist_conv": "0.5"}),
    ("serial:///dev/ttyUSB0?baud=9600", "serial", "", 0, "/dev/ttyUSB0", 9600, {}),
    ("serial:///dev/ttyS0", "serial", "", 0, "/dev/ttyS0", None, {}),
    ("serial://COM3?baud=115200", "serial", "", 0, "COM3", 115200, {}),
    ("lms200:///dev/ttyUSB1?baud=38400", "lms200", "", 0, "/dev/ttyUSB1", 38400, {}),
    ("sim", "sim", "", 0, "", None, {}),
    ("sim?max_range=8", "sim", "", 0, "", None, {"max_range": "8"}),
])
def test_parse_url(url: str, scheme: str, host: str, port: int, path: str, baud: int | None,
                   options: dict[str, str]) -> None:
    ep = parse_url(url)
    assert (ep.scheme, ep.host, ep.port, ep.path, ep.baud, ep.options) == (
        scheme, host, port, path, baud, options)


@pytest.mark.parametrize("url,message", [
    ("localhost:8101", "expected tcp://HOST:PORT"),
    ("udp://x:1", "expected tcp://HOST:PORT"),
    ("serial:///dev/x?baud=-3", "baud must be positive"),
    ("tcp://h:1?model=a&model=b", "`model` given twice"),
    ("lms200://", "no device"),
])
def test_parse_url_errors_name_the_url(url: str, message: str) -> None:
    with pytest.raises(BackendError, match=message) as info:
        parse_url(url)
    assert url in str(info.value)


def test_tcp_stream_reads_writes_and_reports_the_end() -> None:
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(1)
    port = server.getsockname()[1]
    t = TcpTransport("127.0.0.1", port, connect_timeout=1.0)
    peer, _ = server.accept()
    try:
        assert t.read(0.01) == b""  # nothing yet: a timeout, not an error
        t.write(b"\xfa\xfb")
        assert peer.recv(10) == b"\xfa\xfb"
        peer.sendall(b"abc")
        assert t.read(0.5) == b"abc"
        peer.close()
        with pytest.raises(TransportClosed, match="closed the connection"):
            t.read(0.5)
    finally:
        t.close()
        t.close()  # idempotent
        server.close()
    with pytest.raises(TransportClosed):
        t.write(b"x")


def test_serial_stream_over_a_pty_sets_the_baud() -> None:
    master, slave = os.openpty()
    tty.setraw(master)
    t = SerialTransport(os.ttyname(slave), 9600)
    try:
        assert termios.tcgetattr(master)[5] == termios.B9600
        t.set_baud(38400)
        assert termios.tcgetattr(master)[5] == termios.B38400
        assert "38400" in t.description
        t.write(b"\x02\x00")
        assert os.read(master, 10) == b"\x02\x00"
        os.write(master, b"\x06")
        assert t.read(0.5) == b"\x06"
        assert t.read(0.01) == b""
    finally:
        t.close()
        os.close(master)
        os.close(slave)


def test_missing_serial_device_is_a_clear_error() -> None:
    with pytest.raises(BackendError, match="cannot open serial line /dev/mdle-no-such-tty"):
        SerialTransport("/dev/mdle-no-such-tty", 9600)
