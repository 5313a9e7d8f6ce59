"""A Pioneer robot (ARCOS firmware, or MobileSim/AMRISim) as an mdle backend.

Over 500 lines: one backend class, whose handshake, reader thread, keep-alive, dead-man
switch and goodbye share one connection state under one lock (the codec is arcos.py).

:class:`PioneerBackend` implements :class:`mdle.core.backend.Backend` on the wall clock. The
connection is synchronised (SYNC0, SYNC1, SYNC2 with retries, per baud rate on serial
lines), opened, and the motors enabled; then a reader thread owns the incoming stream:
it decodes SIPs into odometry, reassembles the simulators' laser scans, sends a PULSE
whenever nothing else was sent for ``keepalive`` seconds (the firmware stops the motors
after 2 s of silence) and, as a dead-man switch, stops the robot itself if the runtime
has not commanded it for ``command_timeout`` seconds. The runtime's calls only read the
newest data and write commands, so none of them blocks for longer than a tick.

Safety: every way out stops the robot. :meth:`PioneerBackend.close` (idempotent, safe
from ``finally`` blocks and signal handlers) says a clean goodbye: STOP and zero
velocities, a wait until a SIP shows the wheels stopped or the link is gone (bounded by
the time the robot's deceleration takes from its last reported speeds, plus
``goodbye_timeout``), then CLOSE, and the stream is ended gracefully (every byte handed
over, the peer's last packets drained) before it is released. The SIGTERM handler and
the exit hook are in place before the first motor command, so a signal while connecting
also stops the robot; the handler is the driver's only when SIGTERM had none (under
mdle's command line its signal guard owns SIGTERM and ends runs cleanly). Stale data or
a lost connection raise :class:`~mdle.core.errors.BackendError` after a best-effort stop; the
runtime stops the robot at the end of every run.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Protocol

from mdle.core.backend import ClockMode, Command, Observation, RobotLimits, Scan
from mdle.core.errors import BackendError
from mdle.core.exit_hooks import ExitHooks, register_exit_hooks
from mdle.core.pose import Pose
from mdle.drivers import arcos, arcos_laser
from mdle.drivers.arcos import Cmd, OdometryState, PacketReader, RobotParams, SyncInfo
from mdle.drivers.limits import check_limits, check_robot_params
from mdle.drivers.transport import Transport, TransportClosed, read_or_fail

__all__ = ["PioneerBackend", "PioneerOptions", "ScanSource", "limits_from_params"]

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class PioneerOptions:
    """Timeouts and choices of a :class:`PioneerBackend` (seconds unless stated).

    The defaults suit a robot or simulator on a local link; tests shorten them.
    """

    sync_timeout: float = 0.5
    """How long to wait for each SYNC reply."""
    sync_retries: int = 4
    """Handshake attempts per baud rate before giving up."""
    first_sip_timeout: float = 2.0
    """How long after OPEN the first SIP may take."""
    sip_timeout: float = 0.5
    """The newest SIP may be this old (SIPs come every 0.1 s); beyond it the run ends."""
    first_scan_timeout: float = 3.0
    """How long the first laser scan may take after the connection is up."""
    max_scan_age: float = 0.5
    """The newest laser scan may be this old; beyond it the run ends."""
    keepalive: float = 0.4
    """Send a PULSE when nothing was sent for this long (the firmware watchdog is 2 s)."""
    command_timeout: float = 1.0
    """Dead-man switch: stop the robot when no command came for this long."""
    poll: float = 0.02
    """The reader thread's read timeout (bounds its reaction time)."""
    laser_mode: int = 1
    """Simulator laser packets: 1 for 0x60, 2 for the extended 0x61."""
    laser_max_range_mm: int = arcos_laser.NO_RETURN_MM
    """The simulator laser's no-return code (mm): AMRISim and MobileSim send 32767 for a
    beam without a return; readings at or above it are invalid."""
    laser_fov_deg: float = 180.0
    odometry_origin: str = "start"
    """``start``: the pose at connect is (0, 0, 0), as the simulators' odometry restarts
    each session; ``robot``: the robot's own odometry counters."""
    model: str | None = None
    """Use this model's parameters whatever SYNC2 reports."""
    param_overrides: tuple[tuple[str, float], ...] = ()
    """Conversion factors or limits to override (RobotParams field, value)."""
    bauds: tuple[int, ...] = ()
    """Serial rates to try in turn (empty: the transport's current rate)."""
    handle_sigterm: bool = False
    """Turn SIGTERM into SystemExit while connected, so ``finally`` blocks stop the robot,
    unless a handler is already installed (it stays the one owner: mdle's command line
    installs one that ends runs cleanly)."""
    goodbye_timeout: float = 0.5
    """On close, wait at most this long, plus the time the robot takes to stop from its
    last reported speeds at its deceleration limits, for a SIP showing the wheels
    stopped; and this long for the stream to end gracefully."""


class ScanSource(Protocol):
    """A laser delivering scans on its own (e.g.

    :class:`~mdle.drivers.lms200_driver. Lms200Driver`). Stamps are ``time.monotonic()``
    seconds.
    """

    def latest(self) -> Scan | None:
        """Return the newest complete scan, or None before the first."""
        ...

    def failure(self) -> str | None:
        """Why the laser stopped delivering (None while it works)."""
        ...

    def close(self) -> None:
        """Stop the laser and release its line (idempotent)."""
        ...


#: The command latency laws predict over on an ARCOS server when no robot profile says
#: otherwise (s): a command waits for the server's next read, acts at its next motion
#: step and shows in the next SIP, 1.5 cycles of 100 ms on average (``pioneer-p3dx``,
#: fitted on AMRISim, has 170 ms). With 0 the shipped corridor plan's law ran without
#: its lag prediction, and 11 of 44 doors took the robot below its 0.52 m side range.
SERVER_LOOP_LATENCY = 0.15


def limits_from_params(p: RobotParams) -> RobotLimits:
    """Return the :class:`RobotLimits` a model's parameters describe.

    The command latency is the server loop's (:data:`SERVER_LOOP_LATENCY`).
    """
    return RobotLimits(max_speed=p.max_speed, max_reverse_speed=p.max_reverse_speed,
                       max_turn_rate=p.max_turn_rate, max_accel=p.max_accel,
                       max_decel=p.max_decel, max_turn_accel=p.max_turn_accel,
                       radius=p.radius, command_latency=SERVER_LOOP_LATENCY)


_STOP_PACKETS = arcos.encode_command(Cmd.VEL, 0) + arcos.encode_command(Cmd.RVEL, 0)
_PULSE = arcos.encode_command(Cmd.PULSE)
#: Below these a SIP's speeds count as stopped (wheel speeds come in whole mm/s, the
#: turn rate in 0.1 deg/s).
_STOPPED_V = 0.002
_STOPPED_OMEGA = 0.005


@dataclass
class _Shared:
    """What the reader thread publishes; replaced whole under the lock."""

    odometry: OdometryState | None = None
    sip_stamp: float = -math.inf
    scan: Scan | None = None
    failure: str | None = None
    sips: int = 0
    scans: int = 0
    bad_packets: int = 0
    extra: dict[str, Any] = field(default_factory=dict)


class PioneerBackend:
    """A Pioneer over an ARCOS connection, as a wall-clock :class:`~mdle.core.backend.Backend`.

    Parameters
    ----------
    transport : Transport
        An open byte stream to the robot (TCP for the simulators, serial for a robot).
        The backend owns it from now on and closes it.
    laser : "sim", ScanSource or None
        ``"sim"``: the simulators' laser packets over this connection; a ScanSource: a
        laser on its own line (owned and closed by the backend); None: no laser.
    limits : RobotLimits or None
        Limits to clamp commands to; None takes them from the model's parameters.
    rate : float
        The control rate (Hz) the runtime will tick at; widens the dead-man and
        scan-age limits when ticks are long.
    options : PioneerOptions

    Raises
    ------
    BackendError
        Nothing answered the handshake, no SIP or no scan arrived: the message names
        the connection and what was missing. The transport is closed.

    Notes
    -----
    Units at the edge: SIP positions (model units) become metres, headings radians,
    wheel speeds m/s; commands go out as VEL (mm/s) and RVEL (whole deg/s).
    """

    clock: ClockMode = ClockMode.WALL

    def __init__(self, transport: Transport, *, laser: str | ScanSource | None = None,
                 limits: RobotLimits | None = None, rate: float = 10.0,
                 options: PioneerOptions | None = None) -> None:
        self._transport = transport
        self._opt = opt = options or PioneerOptions()
        problem = _check_arguments(laser, rate, opt)
        if problem is not None:
            transport.close()
            raise BackendError(problem)
        self.rate = rate
        #: The ladar's pose on the robot (x, y, theta: m, m, rad) and the (period,
        #: time_increment) of its scans (s), for recordings' frames and LaserScan
        #: timing: None (unknown) unless a robot profile says (``mdle run --robot``).
        self.laser_mount: tuple[float, float, float] | None = None
        self.laser_timing: tuple[float, float] | None = None
        self._command_timeout = max(opt.command_timeout, 3.0 / rate)
        self._max_scan_age = max(opt.max_scan_age, 2.0 / rate)
        self._sim_laser = laser == "sim"
        self._laser_source: ScanSource | None = None if isinstance(laser, str) or laser is None \
            else laser
        self._lock = threading.Lock()
        self._write_lock = threading.RLock()
        self._lost = threading.Event()
        self._halt = threading.Event()
        self._shared = _Shared()
        self._closed = False
        self._thread: threading.Thread | None = None
        self._last_write = -math.inf
        self._last_command = -math.inf
        self._moving = False
        self._sent = Command()  # the last speeds sent, as they went on the wire (SI)
        self._tick_start: float | None = None  # the current tick's place on the grid
        self._observed_at: float | None = None  # when observe() last ran (monotonic s)
        self._t0 = time.monotonic()
        self._assembler = arcos_laser.ScanAssembler(opt.laser_max_range_mm, opt.laser_fov_deg)
        self._exit_hooks: ExitHooks | None = None
        self.goodbye: str | None = None
        """How the last close went: ``stopped`` (a SIP showed the wheels stopped),
        ``link lost``, ``not confirmed`` (no such SIP within ``goodbye_timeout``) or
        ``not connected``; None while open."""
        self.deadman_stops = 0
        """How often the dead-man switch stopped the robot (runtime silent too long)."""
        try:
            self.info = self._handshake()
            model = opt.model or self.info.subtype
            if model.lower() not in arcos.ROBOT_PARAMS:
                _log.warning("unknown Pioneer model `%s`: using p3dx-sh parameters (override "
                             "with ?model=... or conversion factors in the URL)", model)
            try:
                self.params = arcos.robot_params(model, dict(opt.param_overrides))
            except ValueError as exc:
                raise BackendError(str(exc)) from None
            self.limits: RobotLimits = limits or limits_from_params(self.params)
            # never a negative, infinite or absurd speed on the wire, however they came
            problem = check_robot_params(self.params) or check_limits(self.limits)
            if problem is not None:
                raise BackendError(problem)
            self._odometer = arcos.Odometer(self.params,
                                            relative=opt.odometry_origin == "start")
            # from here on the motors may move: a signal or an exit must stop them
            self._exit_hooks = register_exit_hooks(self, self._opt.handle_sigterm)
            self._write(arcos.encode_command(Cmd.OPEN))
            self._write(_PULSE + arcos.encode_command(Cmd.ENABLE, 1))
            if self._sim_laser:
                self._write(arcos_laser.enable_command(opt.laser_mode, 0))
            self._thread = threading.Thread(target=self._run, name="mdle-pioneer-reader",
                                            daemon=True)
            self._thread.start()
            self._await_first_data()
        except BaseException:
            self._closed = True
            # Before OPEN (the exit hooks come just before it) no session exists and the
            # motors cannot run: nothing to stop, and no goodbye to wait for (a robot that
            # never answered would hold Ctrl-C for the stream's goodbye_timeout).
            self._shutdown(send=self._exit_hooks is not None and not self._lost.is_set())
            raise

    # ------------------------------------------------------------------ Backend API

    def observe(self) -> Observation:
        """Return the newest odometry and scan.

        Raises BackendError if the robot or laser is lost or their data are older than the
        limits (the robot is stopped first).
        """
        if self._closed:
            raise BackendError("the Pioneer connection is closed")
        now = time.monotonic()
        # a run's first tick starts its grid (advance); an observation outside a run (a
        # REPL's :pose, a report) must not, or the next run's first ticks come unpaced
        self._observed_at = now
        with self._lock:
            s = self._shared
            odo, sip_stamp, failure, scan = s.odometry, s.sip_stamp, s.failure, s.scan
        if failure is not None:
            self._abort(f"lost the robot on {self._transport.description}: {failure}")
        if odo is None or now - sip_stamp > self._opt.sip_timeout:
            self._abort(f"the robot sent no data for {now - sip_stamp:.2f} s (limit "
                        f"{self._opt.sip_timeout:.2f} s) on {self._transport.description}")
        assert odo is not None
        if self._laser_source is not None:
            why = self._laser_source.failure()
            if why is not None:
                self._abort(f"lost the laser: {why}")
            scan = self._laser_source.latest()
        if self._sim_laser or self._laser_source is not None:
            age = math.inf if scan is None else now - scan.stamp
            if age > self._max_scan_age:
                self._abort(f"the newest laser scan is {age:.2f} s old (limit "
                            f"{self._max_scan_age:.2f} s): the laser stopped sending")
        if scan is not None:
            scan = replace(scan, stamp=scan.stamp - self._t0)
        return Observation(time=now - self._t0, pose=Pose(odo.x, odo.y, odo.theta), v=odo.v,
                           omega=odo.omega, scan=scan, stalled=odo.stalled,
                           motors_enabled=odo.motors_enabled, battery=odo.battery)

    def command(self, cmd: Command) -> None:
        """Send VEL (mm/s) and RVEL (deg/s), clamped to :attr:`limits`."""
        if self._closed:
            raise BackendError("the Pioneer connection is closed")
        self._raise_if_lost()
        if not (math.isfinite(cmd.v) and math.isfinite(cmd.omega)):
            self._abort(f"refusing a non-finite command (v = {cmd.v}, omega = {cmd.omega})")
        lim = self.limits
        v = min(max(cmd.v, -lim.max_reverse_speed), lim.max_speed)
        w = min(max(cmd.omega, -lim.max_turn_rate), lim.max_turn_rate)
        mm = round(v * 1000.0)
        deg = round(math.degrees(w))
        packet = arcos.encode_command(Cmd.VEL, mm) + arcos.encode_command(Cmd.RVEL, deg)
        with self._write_lock:  # one decision at a time with the dead-man switch
            self._last_command = time.monotonic()
            self._moving = mm != 0 or deg != 0
            self._sent = Command(mm / 1000.0, math.radians(deg))
            self._send_or_abort(packet)

    def advance(self, dt: float) -> float:
        """Wait until this tick's wall-clock deadline (never longer); return the lateness.

        Ticks are laid on a fixed grid from the observation of a run's first tick (the
        first since :meth:`stop`), so the rate does not drift; after a tick later than a
        whole period the grid restarts from now. The wait ends early if the connection is
        lost (the next observe reports it).
        """
        now = time.monotonic()
        start = self._tick_start
        if start is None:  # the run's first tick: the grid starts at its observation
            start = self._observed_at if self._observed_at is not None else now
        deadline = start + dt
        if deadline > now:
            self._lost.wait(deadline - now)
            now = time.monotonic()
        lateness = max(0.0, now - deadline)
        self._tick_start = deadline if lateness < dt else now
        return lateness

    def stop(self) -> None:
        """Command zero velocity now (best effort: never raises)."""
        self._moving = False
        self._tick_start = None
        if self._closed or self._lost.is_set():
            return
        try:
            self._write(_STOP_PACKETS)
        except TransportClosed:
            pass

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` has run (the robot stopped and let go of)."""
        return self._closed

    def close(self) -> None:
        """Stop the robot, close the ARCOS session and release everything (idempotent)."""
        if self._closed:
            return
        self._closed = True
        self._shutdown(send=True)

    def __enter__(self) -> PioneerBackend:  # noqa: PYI034 (typing.Self needs Python 3.11)
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ introspection

    @property
    def failure(self) -> str | None:
        """Why the link to the robot was lost (None while it is up)."""
        with self._lock:
            return self._shared.failure

    @property
    def description(self) -> str:
        """Where the robot is: its connection (``tcp://host:port``, a serial device)."""
        return self._transport.description

    @property
    def stats(self) -> dict[str, int]:
        """Counters: SIPs and scans received, packets rejected, dead-man stops."""
        with self._lock:
            s = self._shared
            return {"sips": s.sips, "scans": s.scans, "bad_packets": s.bad_packets,
                    "rejected": int(s.extra.get("rejected", 0)),
                    "deadman_stops": self.deadman_stops}

    # ------------------------------------------------------------------ connection

    def _handshake(self) -> SyncInfo:
        opt = self._opt
        bauds: Sequence[int | None] = opt.bauds or (None,)
        attempts = 0
        last = "no reply to SYNC0"
        for baud in bauds:
            if baud is not None:
                self._transport.set_baud(baud)
            for _ in range(max(1, opt.sync_retries)):
                attempts += 1
                info, last = self._sync_once()
                if info is not None:
                    return info
        raise BackendError(
            f"no answer from a Pioneer on {self._transport.description} after {attempts} "
            f"handshake attempt(s) ({last}): check that the robot is switched on, the cable "
            f"and port (or the simulator's host and port) are right, and that no other "
            f"program holds the connection")

    def _sync_once(self) -> tuple[SyncInfo | None, str]:
        reader = PacketReader()
        for step in (Cmd.SYNC0, Cmd.SYNC1, Cmd.SYNC2):
            try:
                self._transport.write(arcos.encode_command(step))
            except TransportClosed as exc:
                raise BackendError(f"the connection to the robot on "
                                   f"{self._transport.description} failed during the "
                                   f"handshake: {exc}") from None
            deadline = time.monotonic() + self._opt.sync_timeout
            reply = None
            while reply is None:
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return None, f"no reply to SYNC{int(step)}"
                try:
                    data = self._transport.read(min(remaining, 0.05))
                except TransportClosed as exc:
                    raise BackendError(f"the robot on {self._transport.description} stopped "
                                       f"answering during the handshake: {exc}") from None
                for body in reader.feed(data):
                    if body[0] in arcos.SIP_IDS:
                        # a session left open: close it, let the SIPs in flight
                        # drain, and start again
                        self._transport.write(arcos.encode_command(Cmd.CLOSE))
                        self._drain(quiet=0.1, limit=self._opt.sync_timeout)
                        return None, "found an open session; closed it"
                    if body[0] == step:
                        reply = body
                        break
        assert reply is not None
        return arcos.parse_sync2(reply[1:]), ""

    def _drain(self, quiet: float, limit: float) -> None:
        """Discard input until the line has been quiet for ``quiet`` s (at most ``limit``)."""
        end = time.monotonic() + limit
        while time.monotonic() < end:
            try:
                if not self._transport.read(quiet):
                    return
            except TransportClosed as exc:
                raise BackendError(f"the robot on {self._transport.description} stopped "
                                   f"answering during the handshake: {exc}") from None

    def _await_first_data(self) -> None:
        opt = self._opt
        deadline = time.monotonic() + opt.first_sip_timeout
        while True:
            with self._lock:
                got, failure = self._shared.odometry is not None, self._shared.failure
            if failure is not None:
                raise BackendError(f"lost the robot on {self._transport.description} right "
                                   f"after connecting: {failure}")
            if got:
                break
            if time.monotonic() > deadline:
                raise BackendError(f"the robot on {self._transport.description} answered the "
                                   f"handshake but sent no SIP within {opt.first_sip_timeout} s")
            time.sleep(0.01)
        if not (self._sim_laser or self._laser_source is not None):
            return
        deadline = time.monotonic() + opt.first_scan_timeout
        while True:
            if self._sim_laser:
                with self._lock:
                    scan = self._shared.scan
            else:
                assert self._laser_source is not None
                why = self._laser_source.failure()
                if why is not None:
                    raise BackendError(f"the laser failed: {why}")
                scan = self._laser_source.latest()
            if scan is not None:
                return
            if time.monotonic() > deadline:
                where = ("the simulator sent no laser packets (does its robot model have a "
                         "laser?)" if self._sim_laser else "the laser delivered no scan")
                raise BackendError(f"no laser scan within {opt.first_scan_timeout} s: {where}")
            time.sleep(0.01)

    # ------------------------------------------------------------------ reader thread

    def _run(self) -> None:
        """Read, decode, publish; keep the link alive; never raises."""
        reader = PacketReader()
        opt = self._opt
        while not self._halt.is_set():
            data = read_or_fail(self._transport, opt.poll, self._fail)
            if data is None:
                return
            if data:
                now = time.monotonic()
                for body in reader.feed(data):
                    try:
                        self._handle(body, now)
                    except Exception:  # noqa: BLE001 - malformed content, valid checksum
                        _log.debug("dropped a malformed packet %s", body.hex(" "),
                                   exc_info=True)
                        with self._lock:
                            self._shared.bad_packets += 1
                with self._lock:
                    self._shared.extra["rejected"] = reader.rejected
            try:
                self._housekeeping(time.monotonic())
            except TransportClosed as exc:
                self._fail(str(exc))
                return

    def _handle(self, body: bytes, now: float) -> None:
        kind = body[0]
        if kind in arcos.SIP_IDS:
            state = self._odometer.update(arcos.decode_sip(body))
            with self._lock:
                self._shared.odometry = state
                self._shared.sip_stamp = now
                self._shared.sips += 1
        elif kind in arcos_laser.LASER_IDS and self._sim_laser:
            done = self._assembler.add(arcos_laser.decode_laser_packet(body), now)
            if done is not None:
                scan = Scan(done.ranges, done.bearings, done.valid, done.started,
                            done.max_range)
                with self._lock:
                    self._shared.scan = scan
                    self._shared.scans += 1

    def _housekeeping(self, now: float) -> None:
        with self._write_lock:
            if self._moving and now - self._last_command > self._command_timeout:
                # the runtime went quiet while the robot moves: stop it ourselves
                self._moving = False
                self.deadman_stops += 1
                _log.warning("no command for %.2f s: stopping the robot",
                             now - self._last_command)
                self._write(_STOP_PACKETS)
            elif now - self._last_write >= self._opt.keepalive:
                self._write(_PULSE)

    def _fail(self, why: str) -> None:
        with self._lock:
            if self._shared.failure is None:
                self._shared.failure = why
        self._lost.set()

    # ------------------------------------------------------------------ helpers

    def _write(self, data: bytes) -> None:
        with self._write_lock:
            self._transport.write(data)
            self._last_write = time.monotonic()

    def _send_or_abort(self, data: bytes) -> None:
        try:
            self._write(data)
        except TransportClosed as exc:
            self._fail(str(exc))
            self._abort(f"lost the robot on {self._transport.description}: {exc}")

    def _raise_if_lost(self) -> None:
        with self._lock:
            failure = self._shared.failure
        if failure is not None:
            self._abort(f"lost the robot on {self._transport.description}: {failure}")

    def _abort(self, message: str) -> None:
        self.stop()
        raise BackendError(message)

    def _shutdown(self, send: bool) -> None:
        """Say goodbye and release everything; swallows every I/O error.

        With ``send``: STOP and zero velocities, a wait until a SIP shows the wheels
        stopped (or the link is gone; at most :meth:`_stopping_bound`), the laser off, CLOSE.
        Then the reader thread ends and the stream is finished gracefully.
        """
        self.goodbye = "link lost"
        greet = send and not self._lost.is_set()
        try:
            if greet:
                with self._lock:
                    sips, odo = self._shared.sips, self._shared.odometry
                self._write(arcos.encode_command(Cmd.STOP) + _STOP_PACKETS)
                self._moving = False
                self.goodbye = self._await_stopped(sips, self._stopping_bound(odo))
        except (TransportClosed, OSError):
            greet = False
        finally:
            # a second Ctrl-C during the wait lands here too: the session still ends
            self._release(greet)

    def _release(self, greet: bool) -> None:
        """Send CLOSE (with ``greet``), end the reader, finish the stream, free the rest."""
        opt = self._opt
        try:
            if greet:
                if self._sim_laser:
                    self._write(arcos_laser.enable_command(0, 0))
                self._write(arcos.encode_command(Cmd.CLOSE))
        except (TransportClosed, OSError):
            greet = False
            self.goodbye = "link lost"
        finally:
            if self.goodbye == "not confirmed":
                _log.warning("no SIP showed the robot's wheels stopped in time after the "
                             "final stop")
            self._halt.set()
            thread = self._thread
            if thread is not None and thread is not threading.current_thread():
                thread.join(timeout=1.0)
            try:
                if greet:
                    self._transport.finish(opt.goodbye_timeout)
                else:
                    self._transport.close()
            except Exception:  # noqa: BLE001 - closing must go on whatever the stream says
                _log.debug("closing the robot's stream failed", exc_info=True)
            if self._laser_source is not None:
                try:
                    self._laser_source.close()
                except Exception:  # noqa: BLE001
                    _log.debug("closing the laser failed", exc_info=True)
            if self._exit_hooks is not None:
                self._exit_hooks.release()

    def _stopping_bound(self, odo: OdometryState | None) -> float:
        """Return how long the goodbye waits at most for the wheels to stop, seconds.

        ``goodbye_timeout`` (the stop's way to the firmware and a report showing it) plus
        the time the robot's deceleration limits take from the larger of the newest SIP's
        speeds and the last ones sent (the wheels may still be ramping up to them): a fixed
        wait shorter than the ramp down would send CLOSE with the wheels still turning
        (0.3 m/s at 0.3 m/s^2 takes 1 s).
        """
        bound = self._opt.goodbye_timeout
        if odo is None:  # no SIP yet: the motors never ran in this session
            return bound
        lim = self.limits
        v = max(abs(odo.v), abs(self._sent.v))
        omega = max(abs(odo.omega), abs(self._sent.omega))
        ramps = [speed / rate for speed, rate in ((v, lim.max_decel), (omega, lim.max_turn_accel))
                 if math.isfinite(speed) and 0.0 < rate < math.inf]
        return bound + max(ramps, default=0.0)

    def _await_stopped(self, sips_before: int, timeout: float) -> str:
        """Wait until a SIP newer than ``sips_before`` shows the wheels stopped.

        Returns ``stopped``, ``link lost`` or ``not confirmed`` (none within ``timeout``;
        also when the reader thread never ran).
        """
        thread = self._thread
        if thread is None or not thread.is_alive():
            return "not confirmed" if thread is not None else "not connected"
        deadline = time.monotonic() + timeout
        while True:
            with self._lock:
                odo, sips = self._shared.odometry, self._shared.sips
            if self._lost.is_set():
                return "link lost"
            if (odo is not None and sips > sips_before and abs(odo.v) < _STOPPED_V
                    and abs(odo.omega) < _STOPPED_OMEGA):
                return "stopped"
            left = deadline - time.monotonic()
            if left <= 0:
                return "not confirmed"
            self._lost.wait(min(left, 0.01))


def _check_arguments(laser: object, rate: float, opt: PioneerOptions) -> str | None:
    """Return what is wrong with the constructor's arguments, or None."""
    if not rate > 0:
        return f"the control rate must be positive, got {rate} Hz"
    if isinstance(laser, str) and laser != "sim":
        return f"unknown laser `{laser}` (use `sim` or a laser driver)"
    if opt.odometry_origin not in ("start", "robot"):
        return f"odometry origin must be `start` or `robot`, got `{opt.odometry_origin}`"
    if opt.model is not None and opt.model.lower() not in arcos.ROBOT_PARAMS:
        return (f"unknown Pioneer model `{opt.model}`; known: "
                f"{', '.join(sorted(arcos.ROBOT_PARAMS))}")
    if opt.laser_mode not in (1, 2):
        return f"simulator laser mode must be 1 (0x60) or 2 (0x61), got {opt.laser_mode}"
    return None
