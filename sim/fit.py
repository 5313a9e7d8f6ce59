"""Fit a robot profile's timing to recorded runs by replaying their commands.

The recorded command sequence is replayed, tick by tick at the recording's median tick,
through the simulator's motion model (:class:`sim.backend.SimBackend` with a timed
profile): each command takes effect ``command_latency`` after it was sent, the firmware
ramps speed and turn rate at the profile's accelerations (decelerations when slowing
down), and each tick reads the last report of the robot's ``sip_cycle``. The two axes
are independent given the latency, so for each latency on a grid the accelerations of
each axis are found by grid search (vectorised over the candidates), and the latency
that minimises the summed, tolerance-weighted squared RMS errors of ``v`` and ``omega``
is kept, then refined. The scan latency distribution (uniform, min-max) is fitted so that
scans taken every ``scan_period`` at an unknown phase and read at the ticks have the
recorded scan ages' quantiles.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mdle.sim.recording import Recording
from mdle.sim.robot import RAMPS, Latency, RobotProfile, RunClock

__all__ = ["OMEGA_SCALE", "V_SCALE", "AxisFit", "CycleFit", "Fit", "fit_cycled", "fit_profile",
           "replay_axis", "report_times", "run_clock"]

#: Errors are weighed against these (the accuracy a fitted profile should reach).
V_SCALE = 0.03       # m/s
OMEGA_SCALE = 0.05   # rad/s
_LATENCIES = np.arange(0.0, 0.601, 0.02)
_ACC_V = np.geomspace(0.05, 5.0, 25)       # m/s^2
_ACC_W = np.geomspace(0.1, 10.0, 25)       # rad/s^2
_AGE_QUANTILES = np.linspace(0.05, 0.95, 19)
_PHASES = 16


def _events(n: int, tick: float, latency: float, cycle: float
            ) -> list[tuple[float, int, int]]:
    """Return (time, kind, index) sorted: 0 a command takes effect, 1 a report, 2 a tick."""
    ev = [(round(i * tick + latency, 9), 0, i) for i in range(n)]
    ev += [(round(i * tick, 9), 2, i) for i in range(n)]
    if cycle > 0:
        ev += [(round(j * cycle, 9), 1, j) for j in range(1, int(n * tick / cycle) + 1)]
    ev.sort()
    return ev


def replay_axis(cmd: np.ndarray, tick: float, latency: float, accel: np.ndarray,
                decel: np.ndarray, cycle: float, ramp: str = "firmware") -> np.ndarray:
    """Replay one axis's commands for many (accel, decel) candidates at once.

    Parameters
    ----------
    cmd : (n,) array
        The command sent at each tick ``i * tick``.
    accel, decel : (G,) arrays
        Candidate ramp rates (ramping away from zero, towards zero).
    cycle : float
        Report cycle (0: ticks read the current value).

    Returns
    -------
    (n, G) array
        The value each tick observes, before its command is sent. The ramp is the
        simulator's (:func:`sim.robot.ramp_rate`): one rate per change, ``decel`` while
        the change points towards zero; with ``ramp="stage"`` a positive value commanded
        negative jumps to the command.
    """
    jump = ramp == "stage"
    accel = np.asarray(accel, dtype=float)
    decel = np.asarray(decel, dtype=float)
    cur = np.zeros(accel.shape)
    rep = cur
    out = np.empty((len(cmd), accel.size))
    target = 0.0
    t_prev = 0.0
    for time, kind, i in _events(len(cmd), tick, latency, cycle):
        h = time - t_prev
        if h > 0:
            diff = target - cur
            step = np.where(cur * diff < 0, decel, accel) * h
            if jump and target < 0:
                step = np.where(cur > 0, np.inf, step)
            cur = cur + np.clip(diff, -step, step)
            t_prev = time
        if kind == 0:
            target = float(cmd[i])
        elif kind == 1:
            rep = cur
        else:
            out[i] = rep if cycle > 0 else cur
    return out


@dataclass(frozen=True)
class AxisFit:
    """Fitted ramp rates of one axis and the RMS error per recording and overall."""

    accel: float
    decel: float
    rms: float
    rms_each: tuple[float, ...]


@dataclass(frozen=True)
class Fit:
    """A fitted timing model and how well it reproduces the recordings.

    Units: seconds, m/s^2 and rad/s^2, m/s and rad/s for the RMS errors.
    """

    sources: tuple[str, ...]
    tick: float
    sip_cycle: float
    command_latency: float
    ramp: str
    v: AxisFit
    omega: AxisFit
    scan_period: float
    scan_latency: Latency | None
    scan_age: tuple[float, float, float, float] | None
    """Recorded scan age: min, max, mean, std (None: the recordings have none)."""
    scan_age_model: float | None
    """Mean scan age the fitted scan model gives at the ticks."""
    control_cycle: float = 0.0
    """The server loop's cycle (0: the continuous model fitted better)."""
    input_window: float = 0.0
    clocks: tuple[RunClock, ...] = ()
    """Each recording's clock (motion-cycle phase, report instants) for a cycled fit."""
    report_slip: Latency = Latency()
    report_slip_rate: float = 0.0

    def profile(self, base: RobotProfile, name: str, description: str = "",
                source: str = "") -> RobotProfile:
        """Return ``base`` with the fitted timing (the ladar delay only if one was fitted)."""
        changes: dict[str, object] = {
            "name": name, "command_latency": self.command_latency,
            "sip_cycle": self.sip_cycle, "ramp": self.ramp,
            "control_cycle": self.control_cycle, "input_window": self.input_window,
            "report_slip": self.report_slip, "report_slip_rate": self.report_slip_rate,
            "max_accel": self.v.accel,
            "max_decel": self.v.decel, "max_turn_accel": self.omega.accel,
            "max_turn_decel": self.omega.decel, "description": description or base.description,
            "source": source or base.source}
        if self.scan_latency is not None:
            changes.update(scan_period=self.scan_period, scan_latency=self.scan_latency)
        return base.with_overrides(**changes)

    def report(self) -> str:
        """Return the fit in words, one figure a line."""
        lines = [f"fitted to {len(self.sources)} recording(s), replayed at a {self.tick:g} s "
                 f"tick with a {self.sip_cycle:g} s report cycle:",
                 f"  command latency    {self.command_latency:.3f} s",
                 (f"  server loop        motion and reports every {self.control_cycle:.4f} s, "
                  f"commands read unless an instant is due within {self.input_window:.3f} s; "
                  "clock phases: " + ", ".join(f"{c.control_phase or 0.0:.3f} s"
                                               for c in self.clocks)
                  if self.control_cycle > 0 else
                  "  server loop        none (continuous ramps fit better)"),
                 *([f"  report slips       {self.report_slip_rate * 100:.1f} % of reports, "
                    f"late by {self.report_slip.describe()}"]
                   if self.report_slip_rate > 0 else []),
                 f"  ramp model         {self.ramp}",
                 f"  speed ramp         accel {self.v.accel:.3f} m/s^2, "
                 f"decel {self.v.decel:.3f} m/s^2",
                 f"  turn-rate ramp     accel {math.degrees(self.omega.accel):.1f} deg/s^2, "
                 f"decel {math.degrees(self.omega.decel):.1f} deg/s^2",
                 f"  RMS error v        {self.v.rms:.4f} m/s  (" +
                 ", ".join(f"{r:.4f}" for r in self.v.rms_each) + ")",
                 f"  RMS error omega    {self.omega.rms:.4f} rad/s  (" +
                 ", ".join(f"{r:.4f}" for r in self.omega.rms_each) + ")"]
        if self.scan_latency is not None and self.scan_age is not None:
            lo, hi, mean, std = self.scan_age
            lines += [f"  scan latency       {self.scan_latency.describe()} "
                      f"(scans every {self.scan_period:g} s)",
                      f"  scan age           recorded {lo * 1e3:.0f}-{hi * 1e3:.0f} ms, mean "
                      f"{mean * 1e3:.0f} ms, std {std * 1e3:.0f} ms; model mean "
                      f"{(self.scan_age_model or 0.0) * 1e3:.0f} ms"]
        else:
            lines.append("  scan latency       not fitted (no scan ages recorded)")
        return "\n".join(lines)


def _axis_cost(recs: Sequence[Recording], field: str, latency: float, tick: float,
               cycle: float, accel: np.ndarray, decel: np.ndarray, ramp: str
               ) -> tuple[np.ndarray, list[np.ndarray]]:
    """Return pooled squared error sums per candidate, and each recording's mean square."""
    total = np.zeros(accel.size)
    each = []
    for rec in recs:
        pred = replay_axis(getattr(rec, "cmd_" + field), tick, latency, accel, decel, cycle,
                           ramp)
        err = ((pred - getattr(rec, field)[:, None]) ** 2)
        total += err.sum(axis=0)
        each.append(err.mean(axis=0))
    return total, each


def _best_axis(recs: Sequence[Recording], field: str, latency: float, tick: float,
               cycle: float, grid: np.ndarray, ramp: str) -> tuple[float, float, float]:
    """Return (accel, decel, pooled mean square) minimising one axis's error."""
    n = sum(len(r) for r in recs)
    a, d = np.meshgrid(grid, grid, indexing="ij")
    cost, _ = _axis_cost(recs, field, latency, tick, cycle, a.ravel(), d.ravel(), ramp)
    k = int(np.argmin(cost))
    return float(a.ravel()[k]), float(d.ravel()[k]), float(cost[k] / n)


def _refine_axis(recs: Sequence[Recording], field: str, latency: float, tick: float,
                 cycle: float, accel: float, decel: float, ramp: str) -> AxisFit:
    """Search a fine grid around (accel, decel) and return the best with its errors."""
    fa = accel * np.linspace(0.8, 1.2, 21)
    fd = decel * np.linspace(0.8, 1.2, 21)
    a, d = np.meshgrid(fa, fd, indexing="ij")
    cost, each = _axis_cost(recs, field, latency, tick, cycle, a.ravel(), d.ravel(), ramp)
    k = int(np.argmin(cost))
    n = sum(len(r) for r in recs)
    return AxisFit(round(float(a.ravel()[k]), 4), round(float(d.ravel()[k]), 4),
                   math.sqrt(cost[k] / n), tuple(math.sqrt(float(e[k])) for e in each))


def _latency_cost(recs: Sequence[Recording], latency: float, tick: float, cycle: float,
                  ramp: str) -> tuple[float, tuple[float, float], tuple[float, float]]:
    av, dv, msv = _best_axis(recs, "v", latency, tick, cycle, _ACC_V, ramp)
    aw, dw, msw = _best_axis(recs, "omega", latency, tick, cycle, _ACC_W, ramp)
    return msv / V_SCALE ** 2 + msw / OMEGA_SCALE ** 2, (av, dv), (aw, dw)


def scan_ages(tick: float, n: int, period: float, phase: float, delays: np.ndarray
              ) -> np.ndarray:
    """Return the age of the newest readable scan at ticks ``1..n-1`` (``tick`` apart).

    Scans are taken at ``phase + k * period`` and readable ``delays[k]`` later.
    """
    taken = phase + period * np.arange(delays.size)
    due = taken + delays
    order = np.argsort(due, kind="stable")
    newest = np.maximum.accumulate(taken[order])
    t = tick * np.arange(1, n)
    idx = np.searchsorted(due[order], t + 1e-9, side="right") - 1
    ok = idx >= 0
    return t[ok] - newest[idx[ok]]


def _fit_scan(ages: np.ndarray, tick: float, n: int, period: float, seed: int
              ) -> tuple[Latency, float]:
    """Fit a uniform scan latency to recorded ages by quantiles; return it and the model mean."""
    rng = np.random.default_rng(seed)
    u = rng.random(int(n * tick / period) + 8)
    target = np.quantile(ages, _AGE_QUANTILES)
    phases = (np.arange(_PHASES) + 0.5) / _PHASES * period
    steps = np.arange(0.0, 0.2001, 0.005)
    best = (math.inf, 0.0, 0.0)
    for lo in steps:
        for hi in steps[steps >= lo]:
            sim = np.concatenate([scan_ages(tick, n, period, ph, lo + (hi - lo) * u)
                                  for ph in phases])
            cost = float(np.mean((np.quantile(sim, _AGE_QUANTILES) - target) ** 2))
            if cost < best[0]:
                best = (cost, float(lo), float(hi))
    _, lo, hi = best
    sim = np.concatenate([scan_ages(tick, n, period, ph, lo + (hi - lo) * u) for ph in phases])
    return Latency("uniform", round(lo, 3), round(hi, 3)), float(np.mean(sim))


def fit_profile(recs: Sequence[Recording], *, sip_cycle: float = 0.1,
                scan_period: float = 0.1, ramps: Sequence[str] = RAMPS, seed: int = 0,
                cycles: bool = True) -> Fit:
    """Fit command latency, ramp rates and scan latency to one or more recordings.

    Parameters
    ----------
    recs : recordings of the same robot
    sip_cycle : float, s
        The robot's report cycle assumed in the replay (a Pioneer's is 0.1 s).
    scan_period : float, s
        Time between scans assumed for the scan-latency fit.
    ramps : ramp models to try (:data:`sim.robot.RAMPS`); the one that fits better is kept.
    cycles : bool
        Also fit the server loop (:func:`fit_cycled`: a motion cycle, its own report
        clock, commands read between them) and keep it when it fits better than
        continuous ramps.
    seed : int
        Seed of the scan-latency fit's random draws.
    """
    if not recs:
        raise ValueError("fit_profile needs at least one recording")
    tick = round(float(np.median(np.concatenate([np.diff(r.t) for r in recs]))), 4)
    best: tuple[float, float, str, tuple[float, float], tuple[float, float]] | None = None
    for ramp in ramps:
        coarse = [(_latency_cost(recs, float(la), tick, sip_cycle, ramp), float(la))
                  for la in _LATENCIES]
        lat0 = min(coarse, key=lambda c: c[0][0])[1]
        for la in np.arange(lat0 - 0.02, lat0 + 0.0201, 0.005):
            if la < 0:
                continue
            cost, vd, wd = _latency_cost(recs, float(la), tick, sip_cycle, ramp)
            if best is None or cost < best[0]:
                best = (cost, round(float(la), 3), ramp, vd, wd)
    assert best is not None
    cost0, lat, ramp, (av, dv), (aw, dw) = best
    v = _refine_axis(recs, "v", lat, tick, sip_cycle, av, dv, ramp)
    w = _refine_axis(recs, "omega", lat, tick, sip_cycle, aw, dw, ramp)
    cycled = None
    if cycles:
        # reports as the scan ages show them (scans over the robot's link), or on a clock
        for from_ages in (True, False):
            c = fit_cycled(recs, tick, sip_cycle, ramp, (v.accel, v.decel, w.accel, w.decel),
                           from_ages)
            if cycled is None or c.cost < cycled.cost:
                cycled = c
        # the continuous model's cost on the same scale (mean over ticks)
        cost0 = (v.rms / V_SCALE) ** 2 + (w.rms / OMEGA_SCALE) ** 2
        assert cycled is not None
        if cycled.cost < cost0:
            lat, ramp = cycled.latency, cycled.ramp
            v, w = _cycled_errors(recs, tick, cycled)
        else:
            cycled = None
    ages = np.concatenate([r.scan_age[np.isfinite(r.scan_age)] for r in recs])
    scan_latency: Latency | None = None
    stats = model_mean = None
    if ages.size >= 10:
        n = max(len(r) for r in recs)
        scan_latency, model_mean = _fit_scan(ages, tick, n, scan_period, seed)
        stats = (float(ages.min()), float(ages.max()), float(ages.mean()), float(ages.std()))
    return Fit(tuple(r.source for r in recs), tick, cycled.cycle if cycled else sip_cycle, lat,
               ramp, v, w, scan_period, scan_latency, stats, model_mean,
               cycled.cycle if cycled else 0.0, cycled.window if cycled else 0.0,
               cycled.clocks if cycled else (), cycled.slip if cycled else Latency(),
               cycled.slip_rate if cycled else 0.0)


def _cycled_errors(recs: Sequence[Recording], tick: float, c: CycleFit
                   ) -> tuple[AxisFit, AxisFit]:
    """Return the RMS errors of a fitted server loop, per recording and pooled."""
    errs: dict[str, list[np.ndarray]] = {"v": [], "omega": []}
    for rec, clock in zip(recs, c.clocks, strict=True):
        col = _columns(rec, tick, [(c.latency, c.cycle, c.window, clock.control_phase or 0.0)],
                       clock.report_times)
        for field, (a, d) in (("v", c.rates[:2]), ("omega", c.rates[2:])):
            pred = _replay_columns(getattr(rec, "cmd_" + field), col.targets, col.seen,
                                   col.cycles, np.array([a]), np.array([d]), c.ramp)
            errs[field].append((pred[:, 0] - getattr(rec, field)) ** 2)
    out = []
    for field, (a, d) in (("v", c.rates[:2]), ("omega", c.rates[2:])):
        e = errs[field]
        out.append(AxisFit(a, d, math.sqrt(float(np.mean(np.concatenate(e)))),
                           tuple(math.sqrt(float(np.mean(x))) for x in e)))
    return out[0], out[1]


# ---------------------------------------------------------------------- the server loop
# A cycled profile (``control_cycle``): the robot's server steps its speeds once a cycle,
# reports on its own clock and reads commands between the two (sim.backend's
# SimBackend._advance_cycled). Replayed here vectorised over columns, each column its own
# clock phase (and cycle, input window) or its own ramp rates.

_CYCLE_STRETCH = np.arange(-2, 11) * 1e-3   # the server's cycle against the controller's
_WINDOWS = np.array([0.0, 0.01, 0.02, 0.03, 0.04])
_CYCLE_LATENCIES = np.array([0.0, 0.02, 0.04, 0.06])
_CLOCK_PHASES = 20
_EPS_FIT = 1e-9   # s: instants closer than this are the same instant (as in SimBackend)


def report_times(rec: Recording, cycle: float) -> tuple[float, ...] | None:
    """Return a recording's report instants in replay time (tick ``i`` at ``i * tick``).

    Read from the scan ages, for robots whose scans come over the robot's link with its
    reports (ARCOS's laser packets, as AMRISim sends them): tick ``i`` holds the report
    that arrived ``scan_age`` before it. Repeated arrivals are one report; a gap of
    more than 1.5 cycles had reports the ticks missed, filled in every ``cycle``.
    None when the recording has too few scan ages.
    """
    ages = rec.scan_age
    if np.count_nonzero(np.isfinite(ages)) < 0.9 * len(rec):
        return None
    out: list[float] = []
    for a in rec.tick * np.arange(len(rec)) - ages:
        if not math.isfinite(a) or (out and a <= out[-1] + 0.25 * cycle):
            continue
        while out and a - out[-1] > 1.5 * cycle:
            out.append(out[-1] + cycle)
        out.append(float(a))
    return tuple(x for x in out if x > 0)


def _schedule(n: int, tick: float, latency: float, cycle: float, window: float, phase: float,
              reports: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the command index each motion instant steps towards, and each tick's instant.

    Per motion instant, the last command read before it (-1: none); per tick, the
    motion instant whose speeds the last report before the tick holds (-1: none yet).
    """
    end = n * tick + 2 * cycle
    controls = phase + cycle * np.arange(int((end - phase) / cycle) + 1)
    events = np.concatenate([controls, reports])
    order = np.argsort(events, kind="stable")
    ev = events[order]
    nxt = np.append(ev[1:], math.inf)
    slots = ev[nxt - ev > window]                     # read right after these instants
    sent = tick * np.arange(n) + latency
    # the read before each motion instant, and the commands arrived by then
    k = np.searchsorted(slots, controls - _EPS_FIT, side="left") - 1
    read = np.where(k >= 0, slots[np.maximum(k, 0)], -math.inf)
    target = np.searchsorted(sent, read + _EPS_FIT, side="right") - 1
    # a tick sees the last report before it, which holds the last motion step before that
    t = tick * np.arange(n)
    j = np.searchsorted(reports, t - _EPS_FIT, side="left") - 1
    rep = np.where(j >= 0, reports[np.maximum(j, 0)], -math.inf)
    seen = np.searchsorted(controls, rep + _EPS_FIT, side="right") - 1
    return target, seen


def _replay_columns(cmd: np.ndarray, targets: np.ndarray, seen: np.ndarray, cycles: np.ndarray,
                    accel: np.ndarray, decel: np.ndarray, ramp: str) -> np.ndarray:
    """Step every column's speeds through its motion instants; return (n, G) as ticks see it.

    ``targets`` (K, G): command index per instant (-1: zero); ``seen`` (n, G).
    """
    cmd0 = np.append(cmd, 0.0)                 # index -1 -> 0
    goal = cmd0[targets]
    cur = np.zeros(goal.shape[1])
    vals = np.empty((goal.shape[0] + 1, goal.shape[1]))
    vals[-1] = 0.0                             # row -1: before the first instant
    jump = ramp == "stage"
    for k in range(goal.shape[0]):
        g = goal[k]
        diff = g - cur
        step = np.where(cur * diff < 0, decel, accel) * cycles
        if jump:
            step = np.where((cur > 0) & (g < 0), np.inf, step)
        cur = np.where(step >= np.abs(diff), g, cur + np.sign(diff) * step)
        vals[k] = cur
    return np.take_along_axis(vals, seen, axis=0)


@dataclass(frozen=True)
class _Columns:
    """Schedules of many clock settings for one recording, stacked as columns."""

    targets: np.ndarray
    seen: np.ndarray
    cycles: np.ndarray


def _columns(rec: Recording, tick: float, settings: Sequence[tuple[float, float, float, float]],
             reports: tuple[float, ...] | None) -> _Columns:
    """Return the schedules of (latency, cycle, window, phase) settings as columns.

    Without report instants, reports come every cycle, half a cycle after the motion steps.
    """
    n = len(rec)
    tg, sn = [], []
    for latency, cycle, window, phase in settings:
        rep = (np.asarray(reports) if reports is not None
               else (phase + 0.5 * cycle) % cycle + cycle * np.arange(int(n * tick / cycle) + 2))
        a, b = _schedule(n, tick, latency, cycle, window, phase, rep)
        tg.append(a)
        sn.append(b)
    k = max(len(a) for a in tg)
    tg = [np.pad(a, (0, k - len(a)), mode="edge") for a in tg]
    return _Columns(np.stack(tg, axis=1), np.stack(sn, axis=1),
                    np.array([s[1] for s in settings]))


def _cost_columns(recs: Sequence[Recording], cols: Sequence[_Columns], av: np.ndarray,
                  dv: np.ndarray, aw: np.ndarray, dw: np.ndarray, ramp: str) -> list[np.ndarray]:
    """Per recording, the tolerance-weighted mean square error of each column."""
    out = []
    for rec, c in zip(recs, cols, strict=True):
        pv = _replay_columns(rec.cmd_v, c.targets, c.seen, c.cycles, av, dv, ramp)
        pw = _replay_columns(rec.cmd_omega, c.targets, c.seen, c.cycles, aw, dw, ramp)
        out.append(np.mean((pv - rec.v[:, None]) ** 2, axis=0) / V_SCALE ** 2
                   + np.mean((pw - rec.omega[:, None]) ** 2, axis=0) / OMEGA_SCALE ** 2)
    return out


def _axis_rates(recs: Sequence[Recording], cols: Sequence[_Columns], field: str,
                grid: np.ndarray, ramp: str) -> tuple[float, float, float]:
    """Return the best (accel, decel) of one axis on a grid, and its mean square error.

    Each recording is replayed at its one column (clock).
    """
    a, d = np.meshgrid(grid, grid, indexing="ij")
    a, d = a.ravel(), d.ravel()
    total = np.zeros(a.size)
    for rec, c in zip(recs, cols, strict=True):
        rep = np.repeat
        pred = _replay_columns(getattr(rec, "cmd_" + field), rep(c.targets, a.size, axis=1),
                               rep(c.seen, a.size, axis=1), rep(c.cycles, a.size), a, d, ramp)
        total += np.sum((pred - getattr(rec, field)[:, None]) ** 2, axis=0)
    k = int(np.argmin(total))
    return float(a[k]), float(d[k]), float(total[k] / sum(len(r) for r in recs))


def _phases(cycle: float) -> np.ndarray:
    return (np.arange(_CLOCK_PHASES) + 0.5) / _CLOCK_PHASES * cycle


def _best_phases(recs: Sequence[Recording], tick: float,
                 reports: Sequence[tuple[float, ...] | None],
                 latency: float, cycle: float, window: float, rates: tuple[float, ...],
                 ramp: str) -> tuple[float, list[float]]:
    """Return the pooled cost and each recording's best motion-cycle phase for a setting."""
    av, dv, aw, dw = (np.full(_CLOCK_PHASES, r) for r in rates)
    total, best = 0.0, []
    for rec, rep in zip(recs, reports, strict=True):
        settings = [(latency, cycle, window, float(ph)) for ph in _phases(cycle)]
        cost = _cost_columns([rec], [_columns(rec, tick, settings, rep)], av, dv, aw, dw,
                             ramp)[0]
        k = int(np.argmin(cost))
        total += float(cost[k]) * len(rec)
        best.append(settings[k][3])
    return total / sum(len(r) for r in recs), best


@dataclass(frozen=True)
class CycleFit:
    """The server loop fitted to recordings.

    Its cycle, input window, command latency, ramp, rates (accel and decel of v, then of
    omega, SI), each recording's clock, the cost, and how reports slipped.
    """

    cycle: float
    window: float
    latency: float
    ramp: str
    rates: tuple[float, float, float, float]
    clocks: tuple[RunClock, ...]
    cost: float
    slip: Latency = Latency()
    slip_rate: float = 0.0


def _report_slips(reports: Sequence[tuple[float, ...] | None], cycle: float
                  ) -> tuple[Latency, float]:
    """How often recorded reports came late (more than a fifth of a cycle), and by how much."""
    gaps = np.concatenate([np.diff(r) for r in reports if r is not None and len(r) > 1]
                          or [np.zeros(0)])
    late = gaps[gaps > 1.2 * cycle] - cycle
    if gaps.size == 0 or late.size == 0:
        return Latency(), 0.0
    return (Latency("uniform", round(float(late.min()), 3), round(float(late.max()), 3)),
            round(late.size / gaps.size, 4))


def fit_cycled(recs: Sequence[Recording], tick: float, sip_cycle: float, ramp: str,
               rates: tuple[float, float, float, float], ages: bool = True) -> CycleFit:
    """Fit the server loop: cycle, input window, latency, then the ramp rates, then phases.

    ``rates`` start the search (the continuous model's fit). With ``ages``, recordings
    with scan ages give their report instants (:func:`report_times`); the others (and
    all without ``ages``) report every cycle.
    """
    def reports_at(cycle: float) -> list[tuple[float, ...] | None]:
        return [report_times(r, cycle) if ages else None for r in recs]

    best: tuple[float, float, float, float, list[float]] | None = None
    for stretch in _CYCLE_STRETCH:
        cycle = round(sip_cycle * (1 + stretch), 6)
        reports = reports_at(cycle)
        for window in _WINDOWS:
            cost, phases = _best_phases(recs, tick, reports, 0.0, cycle, float(window), rates,
                                        ramp)
            if best is None or cost < best[0]:
                best = (cost, cycle, float(window), 0.0, phases)
    assert best is not None
    _, cycle, window, _, phases = best
    reports = reports_at(cycle)
    for latency in _CYCLE_LATENCIES[1:]:
        cost, ph = _best_phases(recs, tick, reports, float(latency), cycle, window, rates, ramp)
        if cost < best[0]:
            best = (cost, cycle, window, float(latency), ph)
    _, cycle, window, latency, phases = best
    for _ in range(2):     # the rates at these clocks, then the clocks at those rates
        cols = [_columns(r, tick, [(latency, cycle, window, ph)], rep)
                for r, rep, ph in zip(recs, reports, phases, strict=True)]
        av, dv, _ = _axis_rates(recs, cols, "v", _ACC_V, ramp)
        aw, dw, _ = _axis_rates(recs, cols, "omega", _ACC_W, ramp)
        fine = np.linspace(0.9, 1.1, 11)
        av, dv, _ = _axis_rates(recs, cols, "v", np.unique(np.r_[av * fine, dv * fine]), ramp)
        aw, dw, _ = _axis_rates(recs, cols, "omega", np.unique(np.r_[aw * fine, dw * fine]),
                                ramp)
        rates = (round(av, 4), round(dv, 4), round(aw, 4), round(dw, 4))
        cost, phases = _best_phases(recs, tick, reports, latency, cycle, window, rates, ramp)
    clocks = tuple(RunClock(round(ph, 4), rep) for ph, rep in zip(phases, reports, strict=True))
    return CycleFit(cycle, window, latency, ramp, rates, clocks, cost,
                    *_report_slips(reports, cycle))


def run_clock(rec: Recording, profile: RobotProfile, phases: int = 50) -> RunClock:
    """Return a recorded run's clock for a cycled profile.

    Its report instants (from the scan ages, :func:`report_times`) and the motion-cycle
    phase that replays it best, searched on a grid of ``phases``.
    """
    cycle = profile.control_cycle
    if cycle <= 0:
        raise ValueError(f"profile {profile.name} has no control_cycle")
    rep = report_times(rec, profile.sip_cycle or cycle)
    grid = (np.arange(phases) + 0.5) / phases * cycle
    settings = [(profile.command_latency, cycle, profile.input_window, float(p)) for p in grid]
    rates = (profile.max_accel, profile.max_decel, profile.max_turn_accel, profile.max_turn_decel)
    av, dv, aw, dw = (np.full(phases, r) for r in rates)
    cost = _cost_columns([rec], [_columns(rec, rec.tick, settings, rep)], av, dv, aw, dw,
                         profile.ramp)[0]
    return RunClock(round(float(grid[int(np.argmin(cost))]), 5), rep)
