"""Turn-away shaping (issue 23): a firmware that jumps to turns away is held to its ramp.

The Pioneer 3-DX profile's ``ramp: stage`` takes a positive turn rate commanded negative at
once. Following on the left, a negative turn rate is a turn away from the boundary, so a
one-tick spike of the law (the front floor's full turn rate) spun the robot off for seconds,
and one spike star of the lab suite was never engaged from any start on the left.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdle.atoms.latency import Predictor
from mdle.atoms.turn_shaping import UNWIND, TurnShaper, limit_turn_away
from mdle.sim.robot import ramp_step
from tests.atoms.conftest import p3dx_lab_run

ACCEL = math.radians(100.0)  # rad/s^2
DT = 0.1


def test_a_turn_away_is_capped_at_one_tick_of_the_ramp_and_a_turn_towards_is_not() -> None:
    assert limit_turn_away(8.7, 0.2, ACCEL, DT) == pytest.approx(0.2 + ACCEL * DT)
    assert limit_turn_away(0.25, 0.2, ACCEL, DT) == 0.25  # within reach: as asked
    assert limit_turn_away(-8.7, 0.2, ACCEL, DT) == -8.7  # towards the boundary: as asked
    assert limit_turn_away(8.7, 0.2, math.inf, DT) == 8.7  # no acceleration limit
    assert limit_turn_away(8.7, 0.2, ACCEL, 0.0) == 8.7


def test_a_jump_away_is_told_from_a_ramp_seen_through_late_reports() -> None:
    s = TurnShaper()
    t, rate = 0.0, -0.5
    s.observe(t, rate, ACCEL)
    for step in (1, 1, 2, 1):  # the ramp's rise per cycle; a slipped report shows two at once
        t, rate = t + DT, rate + step * ACCEL * DT
        s.observe(t, rate, ACCEL)
        s.observe(t + 0.5 * DT, rate, ACCEL)  # the same report read again, later
    assert not s.jumps
    # not seen to jump: only a spin is capped
    assert s.limit(8.7, rate, ACCEL, DT) == pytest.approx(rate + ACCEL * UNWIND)
    assert s.limit(rate + 0.5, rate, ACCEL, DT) == rate + 0.5
    s.observe(t + DT, rate + 0.8, ACCEL)  # 0.8 rad/s in one tick: the firmware jumped
    assert s.jumps
    assert s.limit(8.7, rate + 0.8, ACCEL, DT) == pytest.approx(rate + 0.8 + ACCEL * DT)
    ideal = TurnShaper()
    for k, r in enumerate((0.0, 5.0, -5.0, 5.0)):
        ideal.observe(k * DT, r, math.inf)
    assert not ideal.jumps


def _actuate(commands: list[float], ramp: str, shaped: bool, left: bool = False
             ) -> list[float]:
    """Return the turn rates (law frame) a ramping firmware reaches under ``commands``.

    One command (law frame: positive away from the boundary) per tick, acting at once for
    the tick. The robot's rate ramps towards it at ``ACCEL`` as ``sim.robot`` ramps it
    (``stage``: a positive robot rate commanded negative jumps); following on the ``left``
    the robot's frame is the law's mirror image.
    """
    sgn = -1.0 if left else 1.0
    rate, rates = 0.0, []
    for u in commands:
        if shaped:
            u = limit_turn_away(u, rate, ACCEL, DT)
        rate = sgn * ramp_step(sgn * rate, sgn * u, ACCEL, ACCEL, ramp, DT)
        rates.append(rate)
    return rates


def test_a_firmware_that_ramps_turns_exactly_as_without_shaping() -> None:
    rng = np.random.default_rng(23)
    commands = list(rng.uniform(-8.7, 8.7, 400) * (rng.random(400) < 0.3))  # spikes and zeros
    for left in (False, True):
        assert _actuate(commands, "firmware", True, left) == pytest.approx(
            _actuate(commands, "firmware", False, left), abs=1e-12)


def test_a_firmware_that_jumps_is_held_to_its_ramp_away_from_the_boundary() -> None:
    # on the left a stage firmware's jump (a positive robot rate commanded negative) is a
    # jump from a turn towards the boundary to one away from it
    commands = [-0.5] * 5 + [8.7] + [-0.5] * 60  # rounding a tip, one floor spike away
    free = _actuate(commands, "stage", shaped=False, left=True)
    assert max(free) == pytest.approx(8.7)  # the spike is taken at once ...
    assert sum(r > 1.0 for r in free) * DT > 4.0  # ... and takes over 4 s to unwind
    shaped = _actuate(commands, "stage", shaped=True, left=True)
    assert np.diff([0.0, *shaped]).max() <= ACCEL * DT + 1e-12  # never faster away than a ramp
    assert max(shaped) < 0.0  # it never even turned away
    # on the right the same firmware ramps every turn away: shaping changes nothing
    assert _actuate(commands, "stage", True) == pytest.approx(_actuate(commands, "stage", False))


def test_the_rate_when_a_command_acts_ramps_through_the_commands_in_flight() -> None:
    p = Predictor()
    p.record_command(-0.1, 0.3, 1.0)  # sent 0.1 s ago; latency 0.2 s: acts from 0.1 s on

    def rate_when_acting(omega: float, latency: float, turn_accel: float) -> float:
        return p.predict(0.0, 0.0, (0.0, 0.0, 0.0), 0.3, omega, latency, math.inf,
                         turn_accel).omega

    assert rate_when_acting(0.0, 0.2, 2.0) == pytest.approx(0.2)  # 0.1 s at 2 rad/s^2
    assert rate_when_acting(0.4, 0.0, 2.0) == 0.4  # no latency: the rate measured
    assert rate_when_acting(0.0, 0.2, math.inf) == pytest.approx(1.0)


def test_the_p3dx_follows_the_spike_star_it_never_engaged_on_the_left() -> None:
    """Lab suite, seed 0, shape 8 (a spike star): before the shaping no start engaged it on
    the left (the robot spun at up to 8.6 rad/s after each floor spike); on the right all did."""
    spec, omega, engaged, err = p3dx_lab_run("left", 8, 0)
    assert spec.family == "spike-star"
    assert engaged and err <= 0.10, err
    # turns away (negative on the left) never spin up (8.6 rad/s before the shaping); the
    # unwind look-ahead (atoms/unwind.py) lets the safety layer ramp one to 2.3 rad/s here
    assert omega.min() > -2.5
