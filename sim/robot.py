"""Robot profiles and unicycle kinematics integrated exactly, with acceleration limits.

A step of length ``dt`` under a held command is split into at most three *phases*
where the speed ``v`` and the turn rate ``omega`` each either ramp linearly (at the
profile's acceleration) or hold. A phase with both held is an exact circular arc; a
phase with a ramp is integrated by Gauss-Legendre quadrature on sub-pieces of at most
0.25 rad of turning, accurate to machine precision for any tick length.

>>> p = Phase(duration=math.pi, v0=1.0, a_v=0.0, w0=1.0, a_w=0.0)
>>> x, y, th = integrate(0.0, 0.0, 0.0, p, math.pi)   # half a unit circle
>>> round(x, 12) + 0.0, round(y, 12), round(th, 12)
(0.0, 2.0, 3.14159265359)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, NamedTuple

from mdle.core.backend import RobotLimits

if TYPE_CHECKING:
    import numpy as np

__all__ = [
    "HalfRate",
    "Latency",
    "RunClock",
    "OdometryNoise",
    "Phase",
    "RAMPS",
    "RobotProfile",
    "integrate",
    "plan_phases",
    "ramp_rate",
    "ramp_step",
]



#: The 8 Gauss-Legendre nodes and weights on [-1, 1] (numpy's ``leggauss(8)``, written out
#: so that reading a profile, as ``mdle check`` does, needs no numpy; a test compares them).
GAUSS_LEGENDRE_8: tuple[tuple[float, float], ...] = (
    (-0.9602898564975362, 0.10122853629037706), (-0.7966664774136267, 0.22238103445337443),
    (-0.525532409916329, 0.3137066458778869), (-0.18343464249564978, 0.36268378337836166),
    (0.18343464249564978, 0.36268378337836166), (0.525532409916329, 0.3137066458778869),
    (0.7966664774136267, 0.22238103445337443), (0.9602898564975362, 0.10122853629037706))


_MAX_TURN_PER_PIECE = 0.25  # rad: keeps the quadrature error far below 1e-12


@dataclass(frozen=True)
class OdometryNoise:
    """Seeded odometry error, drawn per step and accumulated (all zero: perfect odometry).

    Standard deviations grow with the square root of the motion: ``distance`` (m per
    sqrt(m) travelled), ``turn`` (rad per sqrt(rad) turned) and ``drift`` (heading error,
    rad per sqrt(m) travelled).
    """

    distance: float = 0.0
    turn: float = 0.0
    drift: float = 0.0

    @property
    def enabled(self) -> bool:
        """True when any error term is non-zero."""
        return self.distance > 0 or self.turn > 0 or self.drift > 0


@dataclass(frozen=True)
class Latency:
    """A seeded delay distribution, seconds: uniform on [low, high], or normal (mean, std).

    ``kind`` is ``"uniform"`` (``a`` = low, ``b`` = high) or ``"normal"`` (``a`` = mean,
    ``b`` = standard deviation; draws below 0 are taken as 0). All zero: no delay.
    """

    kind: str = "uniform"
    a: float = 0.0
    b: float = 0.0

    @property
    def mean(self) -> float:
        """Return the mean delay (of the untruncated normal for ``normal``)."""
        return 0.5 * (self.a + self.b) if self.kind == "uniform" else self.a

    @property
    def enabled(self) -> bool:
        """True when the delay is not always zero."""
        return self.a > 0 or self.b > 0

    def draw(self, rng: np.random.Generator) -> float:
        """Draw one delay (seconds, >= 0)."""
        if self.kind == "uniform":
            # rng.uniform(a, b)'s own arithmetic (a + (b - a) * a double in [0, 1)), the
            # same number, without its argument checks: a timed run draws once a tick.
            return self.a if self.b <= self.a else self.a + (self.b - self.a) * rng.random()
        return max(0.0, float(rng.normal(self.a, self.b)))

    def describe(self) -> str:
        """Return the distribution in words, milliseconds."""
        if self.kind == "uniform":
            return f"uniform {self.a * 1e3:.0f}-{self.b * 1e3:.0f} ms"
        return f"normal, mean {self.a * 1e3:.0f} ms, std {self.b * 1e3:.0f} ms"


@dataclass(frozen=True)
class HalfRate:
    """Stretches of time in which the ladar's scans come at half their rate.

    AMRISim's laser, read over ARCOS, sends a scan with every report for a while, then
    only with every other one for a while (5 Hz instead of 10 Hz), and back. The
    stretches at half rate make up ``share`` of the time and last ``length`` seconds on
    average; both kinds of stretch have exponential lengths (so a run may begin in
    either). While one lasts, every other scan is lost. ``share`` 0: never.
    """

    share: float = 0.0
    length: float = 0.0

    @property
    def enabled(self) -> bool:
        """True when scans are ever lost."""
        return self.share > 0 and self.length > 0

    @property
    def full_length(self) -> float:
        """Return the mean length of a stretch at the full rate, seconds."""
        return self.length * (1.0 - self.share) / self.share

    def describe(self) -> str:
        """Return the stretches in words."""
        return (f"{self.share * 100:.0f} % of the time, in stretches of {self.length:.1f} s "
                f"on average")


@dataclass(frozen=True)
class RunClock:
    """Where a run's robot-side clocks stand, for a cycled profile (seconds of sim time).

    Normally drawn from the run's seed; a replay of a recorded run sets them from the
    recording (:func:`sim.fit.run_clock`).

    ``control_phase``: the first motion-cycle instant, in ``[0, control_cycle)``
    (None: seeded). ``report_times``: the report instants, increasing (None: every
    ``sip_cycle`` from a seeded phase); after the last one, reports go on every
    ``sip_cycle``.
    """

    control_phase: float | None = None
    report_times: tuple[float, ...] | None = None


@dataclass(frozen=True)
class RobotProfile:
    """A robot's body, limits, timing, ladar mount and odometry model (SI units).

    Attributes
    ----------
    name : str
    radius : float, metres
        Radius of the disc taken as the body, centred on the rotation centre.
    max_speed, max_reverse_speed : float, m/s
    max_turn_rate : float, rad/s
    max_accel, max_decel : float, m/s^2 (``inf``: reaches any speed at once)
        Rates at which the firmware ramps the speed up (away from zero) and down.
    max_turn_accel, max_turn_decel : float, rad/s^2
        The same for the turn rate.
    ramp : {"firmware", "stage"}
        How speeds ramp (:func:`ramp_rate`): as a Pioneer's firmware, or as the
        Stage-based simulators (a positive speed commanded negative changes at once).
    command_latency : float, s
        From a command being sent until the firmware starts ramping towards it.
    sip_cycle : float, s
        The robot reports pose, speed and turn rate every ``sip_cycle`` seconds (a
        Pioneer's server information packet); observations hold the last report, as old
        as it is. 0: every observation is current.
    control_cycle : float, s
        The robot's motion cycle (0: continuous). When set, the robot's server takes
        commands and changes its speeds only at its own instants, one ramp step of
        ``accel * control_cycle`` per cycle, and reports come on their own clock; both
        clocks start at a seeded phase (see ``docs/robots.md``, "The server loop").
    input_window : float, s
        With ``control_cycle``: the server reads arrived commands right after a motion
        step or a report, but only when neither is due within ``input_window``.
    report_slip : Latency
        With ``control_cycle``: how late a report that slips comes (its clock goes on
        from there, as a server's timer restarted late does), drawn per slip.
    report_slip_rate : float
        The chance that a report slips (0: never).
    scan_period : float or None, s
        Time between ladar scans (None: the ladar profile's rate).
    scan_latency : Latency
        From a scan being taken until the controller can read it.
    scan_half_rate : HalfRate
        Stretches of time in which every other scan is lost.
    ladar_mount : (x, y, theta)
        Ladar origin in the robot frame (m, m, rad).
    odometry : OdometryNoise
    description, source : str
        What the robot is; where the numbers come from.
    """

    name: str
    radius: float
    max_speed: float
    max_reverse_speed: float
    max_turn_rate: float
    max_accel: float = math.inf
    max_decel: float = math.inf
    max_turn_accel: float = math.inf
    max_turn_decel: float = math.inf
    ramp: str = "firmware"
    command_latency: float = 0.0
    sip_cycle: float = 0.0
    control_cycle: float = 0.0
    input_window: float = 0.0
    report_slip: Latency = field(default_factory=Latency)
    report_slip_rate: float = 0.0
    scan_period: float | None = None
    scan_latency: Latency = field(default_factory=Latency)
    scan_half_rate: HalfRate = field(default_factory=HalfRate)
    ladar_mount: tuple[float, float, float] = (0.0, 0.0, 0.0)
    odometry: OdometryNoise = field(default_factory=OdometryNoise)
    description: str = ""
    source: str = ""

    @property
    def timed(self) -> bool:
        """True when the profile delays commands, reports at a cycle or delays scans."""
        return (self.command_latency > 0 or self.sip_cycle > 0 or self.control_cycle > 0
                or self.scan_latency.enabled or self.scan_period is not None
                or self.scan_half_rate.enabled)

    @property
    def effective_latency(self) -> float:
        """Return the mean time from a command being sent until it shows, seconds.

        ``command_latency``; with a server loop (``control_cycle``) one and a half cycles
        more: on average half a cycle until the server reads the command, half a cycle
        until its next motion step, and half a cycle until a report shows the new speed.
        """
        return self.command_latency + 1.5 * self.control_cycle

    def expected_scan_age(self, scan_period: float) -> float:
        """Return the mean age of the newest scan at an unsynchronised tick, seconds.

        The scan latency's mean plus half the time between scans (the mean wait for the
        next one): the scan period, twice as long in the stretches at half rate.
        """
        if not self.timed:
            return 0.0
        half = self.scan_half_rate.share if self.scan_half_rate.enabled else 0.0
        return self.scan_latency.mean + 0.5 * scan_period * (1.0 + half)

    @property
    def limits(self) -> RobotLimits:
        """The backend-facing limits (the scan age with the profile's own scan period)."""
        return self.limits_with(self.scan_period or 0.0)

    def limits_with(self, scan_period: float) -> RobotLimits:
        """Return the backend-facing limits for a ladar scanning every ``scan_period`` s."""
        return RobotLimits(max_speed=self.max_speed, max_reverse_speed=self.max_reverse_speed,
                           max_turn_rate=self.max_turn_rate, max_accel=self.max_accel,
                           max_decel=self.max_decel, max_turn_accel=self.max_turn_accel,
                           radius=self.radius, command_latency=self.effective_latency,
                           scan_latency=self.expected_scan_age(scan_period))

    def with_overrides(self, **changes: Any) -> RobotProfile:
        """Return a copy with some fields replaced (values already in SI)."""
        return replace(self, **changes)


class Phase(NamedTuple):
    """A stretch of motion with linear speed and turn-rate profiles.

    ``v(t) = v0 + a_v t`` (m/s), ``omega(t) = w0 + a_w t`` (rad/s), ``0 <= t <= duration``.
    (A named tuple, not a dataclass: a tick makes a few, and a tuple is made far faster.)
    """

    duration: float
    v0: float
    a_v: float
    w0: float
    a_w: float

    def v_at(self, t: float) -> float:
        """Return the speed at time ``t`` into the phase."""
        return self.v0 + self.a_v * t

    def w_at(self, t: float) -> float:
        """Return the turn rate at time ``t`` into the phase."""
        return self.w0 + self.a_w * t

    @property
    def max_abs_v(self) -> float:
        """Largest |v| over the phase (v is linear, so at an end)."""
        return max(abs(self.v0), abs(self.v0 + self.a_v * self.duration))


#: How the firmware ramps towards a command (the profile's ``ramp``).
RAMPS = ("firmware", "stage")


def ramp_rate(cur: float, target: float, accel: float, decel: float, ramp: str = "firmware"
              ) -> float:
    """Return the ramp rate from ``cur`` towards ``target`` (> 0, ``inf``: at once).

    Slowing down (the change points towards zero from a moving start) uses ``decel``,
    anything else ``accel``; one rate holds for the whole change, through zero, as a
    Pioneer ramps. ``ramp="stage"`` is the ramp of the Stage-based Pioneer simulators
    (AMRISim, MobileSim): the same, except that a positive value commanded negative
    takes the command at once.
    """
    if ramp == "stage" and cur > 0 > target:
        return math.inf
    return decel if cur * (target - cur) < 0 else accel


def ramp_step(cur: float, target: float, accel: float, decel: float, ramp: str, dt: float
              ) -> float:
    """Return the value one discrete ramp step of ``dt`` seconds moves ``cur`` to.

    The step a cycled firmware takes (:attr:`RobotProfile.control_cycle`): at most
    ``rate * dt`` towards ``target``, the rate as :func:`ramp_rate` chooses it.
    """
    if cur == target:       # at the command already (what the rest would return)
        return target
    rate = ramp_rate(cur, target, accel, decel, ramp)
    diff = target - cur
    step = rate * dt
    if not step < abs(diff):
        return target
    return cur + math.copysign(step, diff)


def _ramp(cur: float, target: float, accel: float, decel: float, ramp: str
          ) -> tuple[float, float, float]:
    """Return (start, signed rate, time to reach) for one axis, as :func:`ramp_rate` ramps.

    An infinite rate jumps: the start is then the target (rate and time 0).
    """
    diff = target - cur
    if diff == 0.0:
        return cur, 0.0, 0.0
    rate = ramp_rate(cur, target, accel, decel, ramp)
    if math.isfinite(rate):
        return cur, math.copysign(rate, diff), abs(diff) / rate
    return target, 0.0, 0.0


def plan_phases(v: float, w: float, v_cmd: float, w_cmd: float, dt: float,
                profile: RobotProfile) -> tuple[list[Phase], float, float]:
    """Split ``dt`` seconds under command ``(v_cmd, w_cmd)`` into phases.

    Returns the phases and the speed and turn rate at the end.
    Infinite accelerations jump to the command at the start.
    """
    v, av, tv = _ramp(v, v_cmd, profile.max_accel, profile.max_decel, profile.ramp)
    w, aw, tw = _ramp(w, w_cmd, profile.max_turn_accel, profile.max_turn_decel, profile.ramp)
    # The cuts 0 < ... < dt: where each ramp ends inside the step (once if both end together).
    cuts = [0.0]
    inside_v, inside_w = 0.0 < tv < dt, 0.0 < tw < dt
    if inside_v and inside_w and tv != tw:
        cuts += (tv, tw) if tv < tw else (tw, tv)
    elif inside_v:
        cuts.append(tv)
    elif inside_w:
        cuts.append(tw)
    if dt != 0.0:
        cuts.append(dt)
    phases = []
    t0 = 0.0
    for t1 in cuts[1:]:
        a_v = av if t0 < tv else 0.0
        a_w = aw if t0 < tw else 0.0
        v0 = v_cmd if t0 >= tv > 0 else v + av * t0
        w0 = w_cmd if t0 >= tw > 0 else w + aw * t0
        phases.append(Phase(t1 - t0, v0, a_v, w0, a_w))
        t0 = t1
    v_end = v_cmd if tv <= dt else v + av * dt
    w_end = w_cmd if tw <= dt else w + aw * dt
    return phases, v_end, w_end


def integrate(x: float, y: float, th: float, phase: Phase, tau: float
              ) -> tuple[float, float, float]:
    """Return the pose after ``tau`` seconds of ``phase`` from ``(x, y, th)`` (exact)."""
    if tau <= 0.0:
        return x, y, th
    _, v0, av, w0, aw = phase
    cos, sin = math.cos, math.sin
    if av == 0.0 and aw == 0.0:
        dth = w0 * tau
        half_turn = dth / 2.0
        # The chord of the arc: v tau sinc(dth / 2), sinc by its series near 0.
        sinc = (1.0 - half_turn * half_turn / 6.0 if abs(half_turn) < 1e-4
                else sin(half_turn) / half_turn)
        chord = v0 * tau * sinc
        mid = th + half_turn
        return x + chord * cos(mid), y + chord * sin(mid), th + dth
    # Ramp: theta(t) is quadratic; integrate v cos(theta), v sin(theta) piecewise with
    # Gauss-Legendre nodes (plain floats: a tick has one or two pieces, numpy would cost more).
    turn = abs(w0) * tau + 0.5 * abs(aw) * tau * tau
    pieces = max(1, math.ceil(turn / _MAX_TURN_PER_PIECE))
    h = tau / pieces
    half = h / 2.0
    haw = 0.5 * aw                  # (0.5 * aw) * t * t: the same rounding as written out
    dx = dy = 0.0
    if av == 0.0:
        # Constant speed: (v0 + 0 t) wg is v0 wg.
        for i in range(pieces):
            mid = i * h + half
            for xg, wg in GAUSS_LEGENDRE_8:
                t = mid + half * xg
                a = th + w0 * t + haw * t * t
                vw = v0 * wg
                dx += vw * cos(a)
                dy += vw * sin(a)
    else:
        for i in range(pieces):
            mid = i * h + half
            for xg, wg in GAUSS_LEGENDRE_8:
                t = mid + half * xg
                a = th + w0 * t + haw * t * t
                vw = (v0 + av * t) * wg
                dx += vw * cos(a)
                dy += vw * sin(a)
    dx *= half
    dy *= half
    return x + dx, y + dy, th + w0 * tau + haw * tau * tau
