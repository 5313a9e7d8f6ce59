"""Which turn-rate ramp the recorded ARCOS server has: the evidence behind ``ramp: stage``.

The pioneer-p3dx profile says ``ramp: stage``: a positive turn rate commanded negative takes
the command at once, every other change ramps (:func:`mdle.sim.robot.ramp_rate`). These tests
read the measured turn rate of the 2026-11-28 ARCOS session (13 runs, one report per 0.1 s
tick) and check that asymmetry in the data themselves, not through a fit: the reports where
the measured rate crosses zero downwards change it by more than the fitted ramp can move in
one cycle far more often than the crossings upwards or the changes that cross nothing.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from mdle.fit.recording import read_recording
from mdle.sim.profiles import robot_profile

SESSION = Path(__file__).resolve().parents[1] / "data" / "recordings" / "amrisim-2026-11-28"


def _steps() -> dict[str, np.ndarray]:
    """Per-report changes of the measured turn rate (deg/s), by kind of change."""
    down, up, other = [], [], []
    for path in sorted(SESSION.glob("*.jsonl")):
        w = np.degrees(read_recording(path).omega)
        a, b = w[:-1], w[1:]
        moved = np.abs(b - a) > 0.5  # reports come in whole degrees per second
        down.append(np.abs(b - a)[(a > 0.5) & (b < -0.5)])
        up.append(np.abs(b - a)[(a < -0.5) & (b > 0.5)])
        other.append(np.abs(b - a)[moved & ~((a > 0.5) & (b < -0.5)) & ~((a < -0.5) & (b > 0.5))])
    return {"down": np.concatenate(down), "up": np.concatenate(up),
            "other": np.concatenate(other)}


def test_the_recorded_server_jumps_only_from_positive_to_negative_turn_rates() -> None:
    steps = _steps()
    p3 = robot_profile("pioneer-p3dx")
    assert p3.ramp == "stage"
    # what the fitted ramp moves the rate in one report cycle, with 20 % to spare
    reach = 1.2 * math.degrees(max(p3.max_turn_accel, p3.max_turn_decel)) * p3.sip_cycle
    share = {kind: float(np.mean(s > reach)) for kind, s in steps.items()}
    assert min(len(s) for s in steps.values()) > 200   # enough of each kind to compare
    assert share["down"] > 0.3                          # 43 % in this session
    assert share["up"] < 0.05 and share["other"] < 0.01  # 3.5 % and 0.04 %
    # and the largest jumps downwards are several cycles of ramp at once
    assert float(steps["down"].max()) > 5 * reach
