"""The ARCOS (P2OS) client protocol of Pioneer robots: framing, commands, SIPs.

Pure codec, no I/O: :func:`encode_command` builds the bytes a client sends,
:class:`PacketReader` cuts a byte stream into checked packets (resynchronising after
corrupted bytes), :func:`decode_sip` reads a standard server information packet in
firmware units and :class:`Odometer` turns a stream of SIPs into SI odometry with the
15-bit position counters unwrapped. The per-model conversion factors live in
:data:`ROBOT_PARAMS`, keyed by the SYNC2 subtype. Facts: ``shared/hardware/pioneer-arcos.md``.

Wire layout (both directions): ``FA FB | N | ID | payload | CHK_hi CHK_lo`` where
``N = len(ID + payload) + 2``; multi-byte payload fields are little-endian while the
checksum is sent high byte first.
"""

from __future__ import annotations

import enum
import math
import struct
from dataclasses import dataclass, field, fields, replace

__all__ = [
    "HEADER",
    "MAX_BODY",
    "ROBOT_PARAMS",
    "SIP_IDS",
    "Cmd",
    "Odometer",
    "OdometryState",
    "PacketReader",
    "RobotParams",
    "Sip",
    "SyncInfo",
    "checksum",
    "decode_command",
    "decode_sip",
    "encode_command",
    "encode_sip",
    "encode_sync2",
    "frame",
    "parse_sync2",
    "robot_params",
]

HEADER = b"\xfa\xfb"
#: Largest ID + payload a packet can carry (N is one byte and counts the checksum).
MAX_BODY = 255 - 2

_INT_POS = 0x3B
_INT_NEG = 0x1B
_STRING = 0x2B


class Cmd(enum.IntEnum):
    """Client command numbers used by a motion client (and the simulators' extras)."""

    SYNC0 = 0
    PULSE = 0
    SYNC1 = 1
    OPEN = 1
    SYNC2 = 2
    CLOSE = 2
    ENABLE = 4
    SETA = 5
    SETV = 6
    SETO = 7
    SETRV = 10
    VEL = 11
    CONFIG = 18
    RVEL = 21
    STOP = 29
    VEL2 = 32
    ESTOP = 55
    SIM_SET_POSE = 224
    SIM_RESET = 225
    SIM_LRF_ENABLE = 230
    SIM_STAT = 237


#: Packet IDs of a standard SIP (0x33 on some firmware while the robot moves).
SIP_IDS = frozenset({0x32, 0x33})


def checksum(body: bytes) -> int:
    """Return the ARCOS checksum of ``ID + payload``.

    The sum of big-endian 16-bit words modulo 2**16; an odd last byte is XORed in.
    """
    n = len(body) - len(body) % 2
    words = struct.unpack(f">{n // 2}H", body[:n])
    total = sum(words) & 0xFFFF
    if len(body) % 2:
        total ^= body[-1]
    return total


def frame(body: bytes) -> bytes:
    """Wrap ``ID + payload`` into a complete packet (header, count, checksum)."""
    if not 1 <= len(body) <= MAX_BODY:
        raise ValueError(f"ARCOS packet body must hold 1..{MAX_BODY} bytes, got {len(body)}")
    return HEADER + bytes([len(body) + 2]) + body + struct.pack(">H", checksum(body))


def _encode_int(value: int) -> bytes:
    if not -0xFFFF <= value <= 0xFFFF:
        raise ValueError(f"ARCOS integer argument out of range: {value}")
    return bytes([_INT_POS if value >= 0 else _INT_NEG]) + struct.pack("<H", abs(value))


def encode_command(cmd: int, arg: int | str | bytes | None = None, extra: bytes = b"") -> bytes:
    """Return the packet for one client command.

    Parameters
    ----------
    cmd : int
        Command number (:class:`Cmd`), 0..255.
    arg : int, str, bytes or None
        An integer argument (sent as ``0x3B``/``0x1B`` and the magnitude, uint16 LE),
        a string (``0x2B``, length byte, bytes) or no argument.
    extra : bytes
        Raw bytes appended after the argument (e.g. the laser index of SIM_LRF_ENABLE).

    >>> encode_command(Cmd.VEL, 200).hex(" ")
    'fa fb 06 0b 3b c8 00 d3 3b'
    """
    if not 0 <= int(cmd) <= 255:
        raise ValueError(f"ARCOS command number out of range: {cmd}")
    body = bytes([int(cmd)])
    if isinstance(arg, bool):
        arg = int(arg)
    if isinstance(arg, int):
        body += _encode_int(arg)
    elif isinstance(arg, (str, bytes)):
        raw = arg.encode("latin-1") if isinstance(arg, str) else arg
        if len(raw) > 200:
            raise ValueError("ARCOS string argument longer than 200 bytes")
        body += bytes([_STRING, len(raw)]) + raw
    elif arg is not None:
        raise TypeError(f"unsupported ARCOS argument type: {type(arg).__name__}")
    return frame(body + extra)


def decode_command(body: bytes) -> tuple[int, int | bytes | None, bytes]:
    """Split a client packet body into (command, argument, extra bytes).

    The inverse of :func:`encode_command`, used by test servers and traces.
    Raises ValueError on a malformed argument.
    """
    cmd = body[0]
    rest = body[1:]
    if not rest:
        return cmd, None, b""
    kind = rest[0]
    if kind in (_INT_POS, _INT_NEG) and len(rest) >= 3:
        mag = struct.unpack_from("<H", rest, 1)[0]
        return cmd, (mag if kind == _INT_POS else -mag), rest[3:]
    if kind == _STRING and len(rest) >= 2 and len(rest) >= 2 + rest[1]:
        return cmd, rest[2:2 + rest[1]], rest[2 + rest[1]:]
    raise ValueError(f"malformed argument in ARCOS command {cmd}: {rest.hex(' ')}")


class PacketReader:
    """Cuts a byte stream into checked packet bodies (``ID + payload``).

    Feed it whatever the transport returned; it keeps partial packets between calls.
    Garbage, truncated packets and checksum failures are skipped by searching for the
    next header one byte further on, so one corrupted byte costs at most the packets
    it touches. It never raises.

    Attributes
    ----------
    rejected : int
        How many candidate packets failed the checksum (or had an impossible count).
    skipped : int
        How many bytes were discarded while resynchronising.
    """

    def __init__(self) -> None:
        self._buf = bytearray()
        self.rejected = 0
        self.skipped = 0

    def feed(self, data: bytes) -> list[bytes]:
        """Add received bytes; return the bodies of every packet completed by them."""
        self._buf += data
        out: list[bytes] = []
        buf = self._buf
        while True:
            start = buf.find(HEADER)
            if start < 0:
                # keep a trailing 0xFA: it may be the first half of the next header
                keep = 1 if buf[-1:] == b"\xfa" else 0
                self.skipped += len(buf) - keep
                del buf[: len(buf) - keep]
                break
            if start:
                self.skipped += start
                del buf[:start]
            if len(buf) < 3:
                break
            n = buf[2]
            if n < 3:  # an ID and two checksum bytes at least
                self.rejected += 1
                self.skipped += 1
                del buf[:1]
                continue
            if len(buf) < 3 + n:
                break
            body = bytes(buf[3: 1 + n])
            chk = (buf[1 + n] << 8) | buf[2 + n]
            if checksum(body) != chk:
                self.rejected += 1
                self.skipped += 1
                del buf[:1]
                continue
            out.append(body)
            del buf[: 3 + n]
        return out


@dataclass(frozen=True)
class SyncInfo:
    """The robot's identity from the SYNC2 reply: name, type and subtype (model)."""

    name: str
    type: str
    subtype: str


def parse_sync2(payload: bytes) -> SyncInfo:
    """Read the three NUL-terminated strings of a SYNC2 reply payload (after the ID)."""
    parts = payload.split(b"\x00")
    texts = [p.decode("latin-1", "replace").strip() for p in parts[:3]]
    texts += [""] * (3 - len(texts))
    return SyncInfo(*texts)


def encode_sync2(info: SyncInfo) -> bytes:
    """Return the server's SYNC2 reply packet (for test servers)."""
    payload = b"".join(s.encode("latin-1") + b"\x00" for s in (info.name, info.type, info.subtype))
    return frame(bytes([Cmd.SYNC2]) + payload)


@dataclass(frozen=True)
class Sip:
    """A standard SIP in firmware units, as the robot sent it.

    Positions are the raw 15-bit counters (0..32767; unwrap with :class:`Odometer`);
    ``theta`` in angle units, wheel velocities in velocity units, ``battery`` in
    decivolts, ``rot_vel`` in 0.1 deg/s (None when the firmware omits it), sonar ranges
    in range units. ``stall`` bit 0 is the left wheel, bit 8 the right; ``flags`` bit 0
    means the motors are enabled.
    """

    x: int
    y: int
    theta: int
    left_vel: int = 0
    right_vel: int = 0
    battery: int = 120
    stall: int = 0
    control: int = 0
    flags: int = 0
    compass: int = 0
    sonars: tuple[tuple[int, int], ...] = ()
    rot_vel: int | None = None
    moving: bool = False

    @property
    def motors_enabled(self) -> bool:
        """Whether the motors are on (flags bit 0)."""
        return bool(self.flags & 1)

    @property
    def stalled(self) -> bool:
        """Whether either wheel is stalled (stall bits 0 and 8)."""
        return bool(self.stall & 0x0101)


_SIP_HEAD = struct.Struct("<HHhhhBHhHBB")  # x y theta l r battery stall control flags compass n
# grip asel analog din dout bat10 chg rotvel fault lat temp soc
_SIP_TAIL = struct.Struct("<BBBBBhBhHhbb")


def decode_sip(body: bytes) -> Sip:
    """Decode a standard SIP body (``ID + payload``, ID 0x32 or 0x33).

    Raises ValueError when the packet is too short for what it announces.
    """
    if not body or body[0] not in SIP_IDS:
        raise ValueError("not a standard SIP")
    p = body[1:]
    if len(p) < _SIP_HEAD.size:
        raise ValueError(f"SIP too short: {len(p)} bytes")
    x, y, th, lv, rv, bat, stall, control, flags, compass, ns = _SIP_HEAD.unpack_from(p)
    off = _SIP_HEAD.size
    if len(p) < off + 3 * ns:
        raise ValueError(f"SIP announces {ns} sonar readings but is {len(p)} bytes long")
    sonars = tuple(struct.unpack_from("<BH", p, off + 3 * i) for i in range(ns))
    off += 3 * ns
    rot_vel = None
    if len(p) >= off + 10:  # up to and including the rotational velocity
        rot_vel = struct.unpack_from("<h", p, off + 8)[0]
    return Sip(x=x & 0x7FFF, y=y & 0x7FFF, theta=th, left_vel=lv, right_vel=rv, battery=bat,
               stall=stall, control=control, flags=flags, compass=compass,
               sonars=sonars, rot_vel=rot_vel, moving=body[0] == 0x33)


def encode_sip(sip: Sip) -> bytes:
    """Return the packet a server sends for ``sip`` (used by test servers and round trips)."""
    payload = _SIP_HEAD.pack(sip.x & 0x7FFF, sip.y & 0x7FFF, sip.theta, sip.left_vel,
                             sip.right_vel, sip.battery, sip.stall, sip.control, sip.flags,
                             sip.compass, len(sip.sonars))
    payload += b"".join(struct.pack("<BH", i, r) for i, r in sip.sonars)
    if sip.rot_vel is not None:
        payload += _SIP_TAIL.pack(0, 0, 0, 0, 0, sip.battery, 0, sip.rot_vel, 0, 0, -127, 0)
    return frame(bytes([0x33 if sip.moving else 0x32]) + payload)


@dataclass(frozen=True)
class RobotParams:
    """Per-model conversion factors and working limits of a Pioneer.

    Conversions multiply firmware units into mm, mm/s or radians; limits are SI and
    become the backend's :class:`~mdle.core.backend.RobotLimits`.
    """

    dist_conv: float = 1.0
    """mm per position unit."""
    angle_conv: float = 0.001534
    """radians per heading unit (2 pi / 4096)."""
    vel_conv: float = 1.0
    """mm/s per wheel-velocity unit."""
    diff_conv: float = 0.0056
    """rad/s per mm/s of half the wheel-speed difference (used when the SIP lacks a
    rotational velocity)."""
    range_conv: float = 1.0
    """mm per sonar range unit."""
    max_speed: float = 0.75
    max_reverse_speed: float = 0.75
    max_turn_rate: float = math.radians(100.0)
    max_accel: float = 0.3
    max_decel: float = 0.3
    max_turn_accel: float = math.radians(100.0)
    radius: float = 0.26


#: Known models by SYNC2 subtype. ``p3dx-sh`` and friends report mm; plain ``p3dx``
#: (old P2OS firmware) reports 0.485 mm units.
ROBOT_PARAMS: dict[str, RobotParams] = {
    "p3dx-sh": RobotParams(),
    "p3dx": RobotParams(dist_conv=0.485),
    "p2dx": RobotParams(dist_conv=0.485),
    "p2de": RobotParams(dist_conv=0.969),
    "p3at-sh": RobotParams(diff_conv=0.0034, max_speed=0.7, max_reverse_speed=0.7,
                           radius=0.33),
    "p3at": RobotParams(dist_conv=0.465, diff_conv=0.0034, max_speed=0.7,
                        max_reverse_speed=0.7, radius=0.33),
    "peoplebot-sh": RobotParams(radius=0.27),
    "powerbot": RobotParams(radius=0.45, max_speed=1.0, max_reverse_speed=0.5),
}

_DEFAULT_MODEL = "p3dx-sh"


def robot_params(subtype: str, overrides: dict[str, float] | None = None) -> RobotParams:
    """Return the parameters for a SYNC2 subtype, with ``overrides`` (field name -> value) applied.

    Unknown subtypes fall back to ``p3dx-sh`` (the simulators' default). Raises
    ValueError for an override naming no field.
    """
    base = ROBOT_PARAMS.get(subtype.strip().lower(), ROBOT_PARAMS[_DEFAULT_MODEL])
    if not overrides:
        return base
    names = {f.name for f in fields(RobotParams)}
    bad = sorted(set(overrides) - names)
    if bad:
        raise ValueError(f"unknown robot parameter(s) {', '.join(bad)}; "
                         f"known: {', '.join(sorted(names))}")
    return replace(base, **{k: float(v) for k, v in overrides.items()})


@dataclass(frozen=True)
class OdometryState:
    """Odometry in SI from one SIP: pose (m, m, rad in (-pi, pi]), speeds, flags."""

    x: float
    y: float
    theta: float
    v: float
    omega: float
    stalled: bool
    motors_enabled: bool
    battery: float


def _wrap15(delta: int) -> int:
    """Return a 15-bit counter difference mapped into [-16384, 16383]."""
    return ((delta + 0x4000) & 0x7FFF) - 0x4000


@dataclass
class Odometer:
    """Unwraps the 15-bit SIP position counters and converts to SI.

    The first SIP defines the origin of the unwrapped sum (its raw position), so a
    session starting anywhere on the 15-bit circle reads correctly; later SIPs add
    their wrapped deltas. Successive SIPs must be less than half the counter range
    (16384 units) apart, which at 100 ms per SIP is far beyond any Pioneer's speed.
    """

    params: RobotParams = field(default_factory=RobotParams)
    relative: bool = False
    """Report poses relative to the first SIP's (the pose at connect becomes (0, 0, 0))."""
    _raw: tuple[int, int] | None = None
    _sum: tuple[int, int] = (0, 0)
    _origin: tuple[float, float, float] | None = None

    def update(self, sip: Sip) -> OdometryState:
        """Fold in one SIP and return the odometry it implies."""
        if self._raw is None:
            sx, sy = _wrap15(sip.x), _wrap15(sip.y)
        else:
            sx = self._sum[0] + _wrap15(sip.x - self._raw[0])
            sy = self._sum[1] + _wrap15(sip.y - self._raw[1])
        self._raw = (sip.x, sip.y)
        self._sum = (sx, sy)
        p = self.params
        theta = math.remainder(sip.theta * p.angle_conv, math.tau)
        v = 0.5 * (sip.left_vel + sip.right_vel) * p.vel_conv / 1000.0
        if sip.rot_vel is not None:
            omega = math.radians(sip.rot_vel / 10.0)
        else:
            # diff_conv is per mm/s of half the difference, as the parameter files define it
            omega = 0.5 * (sip.right_vel - sip.left_vel) * p.vel_conv * p.diff_conv
        x, y = sx * p.dist_conv / 1000.0, sy * p.dist_conv / 1000.0
        if self.relative:
            if self._origin is None:
                self._origin = (x, y, theta)
            ox, oy, oth = self._origin
            c, s = math.cos(oth), math.sin(oth)
            x, y = c * (x - ox) + s * (y - oy), -s * (x - ox) + c * (y - oy)
            theta = math.remainder(theta - oth, math.tau)
        return OdometryState(x=x, y=y,
                             theta=theta, v=v, omega=omega, stalled=sip.stalled,
                             motors_enabled=sip.motors_enabled, battery=sip.battery / 10.0)
