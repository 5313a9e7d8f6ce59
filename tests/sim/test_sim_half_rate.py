"""Scans at half rate in stretches (issue 24): AMRISim's laser, read over ARCOS, sends a
scan with every report for a while, then with every other one for seconds at a time.
The profile key, the simulator's stretches, and their fit from recorded scan ages."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mdle.core.backend import Command
from mdle.core.errors import WorldError
from mdle.fit.recording import Recording, read_recording
from mdle.fit.scans import MIN_GAPS, fit_half_rate, half_rate_stretches
from mdle.sim.backend import SimBackend
from mdle.sim.profiles import parse_robot, robot_profile
from mdle.sim.robot import HalfRate, Latency
from mdle.sim.robot_yaml import dump_robot
from mdle.sim.world import World

SESSION = Path(__file__).resolve().parents[1] / "data" / "recordings" / "amrisim-2026-11-28"


def _record(half: HalfRate, seconds: float, seed: int = 0, **changes: object) -> Recording:
    """Stand the robot still for ``seconds`` at 10 Hz; record each tick's scan age."""
    profile = robot_profile("pioneer-p3dx").with_overrides(scan_half_rate=half, **changes)
    sim = SimBackend(World("empty", robot=profile), seed=seed)
    n = int(seconds * 10)
    t, age = np.zeros(n), np.zeros(n)
    for i in range(n):
        obs = sim.observe()
        assert obs.scan is not None
        t[i], age[i] = obs.time, obs.time - obs.scan.stamp
        sim.command(Command())
        sim.advance(0.1)
    zero = np.zeros(n)
    return Recording(f"seed {seed}", t, zero, zero, zero, zero, age)


def test_the_key_reads_and_round_trips() -> None:
    p = parse_robot("profile: pioneer2dx\nscan_half_rate: {share: 0.25, length: 4}\n")
    assert p.scan_half_rate == HalfRate(0.25, 4.0) and p.timed
    assert parse_robot(dump_robot(p)).scan_half_rate == p.scan_half_rate
    assert p.scan_half_rate.full_length == pytest.approx(12.0)
    # the mean scan age laws see: a scan period twice as long a quarter of the time
    assert p.limits_with(0.1).scan_latency == pytest.approx(0.5 * 0.1 * 1.25)


@pytest.mark.parametrize(("text", "message"), [
    ("scan_half_rate: {share: 1, length: 4}",
     "r.yaml:2:25: error: scan_half_rate.share: must be a share of the time in [0, 1), got 1"),
    ("scan_half_rate: {share: 0.3}",
     "r.yaml:2:17: error: scan_half_rate: needs both `share`"),
    ("scan_half_rate: {share: 0.3, length: 0}",
     "r.yaml:2:38: error: scan_half_rate.length: must be"),
    ("scan_half_rate: 0.3", "r.yaml:2:17: error: scan_half_rate: expected"),
])
def test_bad_values_are_located(text: str, message: str) -> None:
    with pytest.raises(WorldError) as info:
        parse_robot(f"profile: pioneer2dx\n{text}\n", file="r.yaml")
    assert str(info.value).startswith(message), str(info.value)


def test_the_simulator_loses_every_other_scan_in_stretches_seeded() -> None:
    half = HalfRate(0.3, 4.0)
    recs = [_record(half, 800.0, seed) for seed in range(4)]  # some 240 stretches
    rec = recs[0]
    stamps = np.unique(np.round(rec.t - rec.scan_age, 6))
    gaps = np.round(np.diff(stamps) / 0.1)
    # a stretch loses every other scan, never two in a row (a third period can go by when
    # the latency's jitter lets a tick read past a scan, as at the full rate)
    assert set(gaps) <= {1.0, 2.0, 3.0} and np.mean(gaps == 3.0) < 0.01
    # what the fit reads back from the ages is what the profile says
    fitted = fit_half_rate(recs, 0.1)
    assert fitted.share == pytest.approx(half.share, abs=0.07)
    assert fitted.length == pytest.approx(half.length, rel=0.35)
    again = _record(half, 60.0)
    assert np.array_equal(again.scan_age, _record(half, 60.0).scan_age)
    assert not np.array_equal(again.scan_age, _record(half, 60.0, seed=1).scan_age)
    # without the key, and a latency without jitter, every scan comes
    steady = _record(HalfRate(), 120.0, scan_latency=Latency("uniform", 0.015, 0.015))
    assert set(np.round(np.diff(np.unique(np.round(steady.t - steady.scan_age, 6))) / 0.1)) \
        == {1.0}


def test_the_recorded_session_has_the_stretches_the_shipped_profile_has() -> None:
    recs = [read_recording(p) for p in sorted(SESSION.glob("*.jsonl"))]
    assert len(recs) == 13
    # corridor-uncompensated-5: stretches of three doubled gaps (0.6 s) and more
    five = half_rate_stretches(read_recording(SESSION / "corridor-uncompensated-5.jsonl"), 0.1)
    assert five.lengths.size >= 3 and np.all(five.lengths > 0.2 * MIN_GAPS - 0.1)
    assert fit_half_rate(recs, 0.1) == robot_profile("pioneer-p3dx").scan_half_rate
    assert robot_profile("pioneer-p3dx").scan_half_rate.share == pytest.approx(0.34, abs=0.02)
