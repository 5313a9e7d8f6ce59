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
recorded scan ages' quantiles. A cycled profile's server loop is fitted in
:mod:`sim.fit_cycle`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mdle.fit.cycle import (
    _ACC_V,
    _ACC_W,
    OMEGA_SCALE,
    V_SCALE,
    CycleFit,
    _columns,
    _replay_columns,
    fit_cycled,
    run_clock,
)
from mdle.fit.recording import Recording
from mdle.fit.scans import fit_half_rate, half_rate_stretches, scan_stamps
from mdle.sim.robot import RAMPS, HalfRate, Latency, RobotProfile, RunClock

# The scales and run_clock live in fit_cycle.py (both fits use them); tests read them here.
__all__ = ["OMEGA_SCALE", "V_SCALE", "AxisFit", "Fit", "fit_profile", "replay_axis", "run_clock"]

_LATENCIES = np.arange(0.0, 0.601, 0.02)
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
    scan_half_rate: HalfRate = HalfRate()
    """Stretches in which scans came at half rate (:mod:`sim.fit_scans`)."""

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
            changes.update(scan_period=self.scan_period, scan_latency=self.scan_latency,
                           scan_half_rate=self.scan_half_rate)
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
                      f"{(self.scan_age_model or 0.0) * 1e3:.0f} ms",
                      "  scans at half rate " + (self.scan_half_rate.describe()
                                                 if self.scan_half_rate.enabled else "never")]
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
    half = HalfRate()
    if ages.size >= 10:
        n = max(len(r) for r in recs)
        half = fit_half_rate(recs, scan_period)
        # the latency from the ticks at the full rate (the stretches' scans are older
        # because scans are missing, not because they came late)
        full = np.concatenate([_full_rate_ages(r, scan_period) for r in recs])
        scan_latency, model_mean = _fit_scan(full if full.size >= 10 else ages, tick, n,
                                             scan_period, seed)
        stats = (float(ages.min()), float(ages.max()), float(ages.mean()), float(ages.std()))
    return Fit(tuple(r.source for r in recs), tick, cycled.cycle if cycled else sip_cycle, lat,
               ramp, v, w, scan_period, scan_latency, stats, model_mean,
               cycled.cycle if cycled else 0.0, cycled.window if cycled else 0.0,
               cycled.clocks if cycled else (), cycled.slip if cycled else Latency(),
               cycled.slip_rate if cycled else 0.0, half)


def _full_rate_ages(rec: Recording, period: float) -> np.ndarray:
    """Return a recording's scan ages at the ticks outside its half-rate stretches."""
    stamps = scan_stamps(rec)
    ok = np.isfinite(stamps)
    inside = half_rate_stretches(rec, period).covers(stamps[ok])
    return rec.scan_age[ok][~inside]


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
