"""Fit a cycled profile's server loop to recorded runs: its cycle, clock and ramp rates.

A cycled profile (``control_cycle``): the robot's server steps its speeds once a cycle,
reports on its own clock and reads commands between the two (sim.backend's
SimBackend._advance_cycled). Replayed here vectorised over columns, each column its own
clock phase (and cycle, input window) or its own ramp rates.
:func:`sim.fit.fit_profile` calls :func:`fit_cycled` after fitting the continuous model.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mdle.fit.recording import Recording
from mdle.sim.robot import Latency, RobotProfile, RunClock

__all__ = ["OMEGA_SCALE", "V_SCALE", "CycleFit", "fit_cycled", "report_times", "run_clock"]

#: Errors are weighed against these (the accuracy a fitted profile should reach).
V_SCALE = 0.03       # m/s
OMEGA_SCALE = 0.05   # rad/s
#: The acceleration grids both fits search, m/s^2 and rad/s^2.
_ACC_V = np.geomspace(0.05, 5.0, 25)
_ACC_W = np.geomspace(0.1, 10.0, 25)
_CYCLE_STRETCH = np.arange(-2, 11) * 1e-3   # the server's cycle against the controller's
_WINDOWS = np.array([0.0, 0.01, 0.02, 0.03, 0.04])
# up to 0.12 s: on the 2026-11-28 AMRISim session commands showed a tick later than on
# the 2026-11-24 one (the earlier 0.06 s ceiling left its fit at the edge)
_CYCLE_LATENCIES = np.arange(0.0, 0.1201, 0.02)
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
