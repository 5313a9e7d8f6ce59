"""Gaps near 2 rc: the robot goes on round what it circles where turning costs more.

Two legs or poles a little less than ``2 rc`` apart join their ``rc`` level sets at a kink of
nearly 180 deg; a little more, and they are two closed curves. The measured gap flips
between the two from tick to tick, and a turn onto the next thing started late took the
robot in among a table's legs (``atoms/pinch.py``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdle import sim
from mdle.atoms import fillet, pinch
from mdle.core.pose import Pose
from mdle.sim.profiles import robot_profile
from mdle.sim.shapes import Circle
from tests.atoms.conftest import follow_run

IDEAL = robot_profile("ideal")
RC = 0.5
TURN = 1.0 / 3.0  # v / umax at 1 m/s and 3 rad/s


def _circled(radius: float = 0.1) -> tuple[complex, float]:
    """A pole of ``radius`` abeam on the right at rc, circled: its nearest point, curvature."""
    return complex(0.0, -RC), -1.0 / radius


def _next_pole(gap: float, bearing_deg: float, radius: float = 0.1) -> complex:
    """The nearest point of a pole ``gap`` from the circled one's surface, round its centre.

    ``bearing_deg``: where its centre lies, seen from the circled pole's centre (0: ahead).
    """
    centre = complex(0.0, -RC - radius)
    u = complex(math.cos(math.radians(bearing_deg)), math.sin(math.radians(bearing_deg)))
    other = centre + u * (gap + 2.0 * radius)
    return other - other / abs(other) * radius  # its point nearest the robot (roughly)


def test_the_circle_followed_passes_a_point_by_its_own_centre_and_radius() -> None:
    q, kappa = _circled()
    # a point 1.1 m from the centre (0, -0.6) of a circle of radius 0.6: 0.5 outside it
    p = complex(0.0, -0.6) + 1.1 * complex(math.cos(0.3), math.sin(0.3))
    assert pinch.circle_clearance(p, q, RC, 0.0, kappa, RC) == pytest.approx(0.0)
    # not circling: a wall (no curvature), a long face (radius of curvature beyond rc),
    # capturing (far off rc, or heading across the circle)
    assert pinch.circle_clearance(p, q, RC, 0.0, 0.0, RC) is None
    assert pinch.circle_clearance(p, q, RC, 0.0, -1.0, RC) is None
    assert pinch.circle_clearance(p, 0.6 * q, 0.6 * RC, 0.0, kappa, RC) is None
    assert pinch.circle_clearance(p, q, RC, math.radians(50.0), kappa, RC) is None


@pytest.mark.parametrize("gap", [0.97, 0.99, 1.0, 1.01])
def test_a_next_pole_near_2rc_is_passed_round_the_pole_circled(gap: float) -> None:
    # at every bearing the circle dips at most 2 rc - gap into its rc band, less than the
    # swing out of a full-rate turn onto it (about 0.1 m) or a late turn's miss
    q, kappa = _circled()
    for bearing in range(-80, 10, 5):
        p = _next_pole(gap, bearing)
        assert pinch.circle_on(p, q, RC, 0.0, kappa, RC, TURN), bearing


def test_a_next_leg_well_inside_2rc_is_turned_onto() -> None:
    # a table's next leg 0.75 m off: the circle would pass 0.25 m inside its rc band, where
    # the fillet swings out by 0.07 m; a late turn is still better while it misses by less
    q, kappa = _circled()
    p = _next_pole(0.75, -40.0)
    assert fillet.turn_margin(p, RC, TURN) > 0.0
    assert not pinch.circle_on(p, q, RC, 0.0, kappa, RC, TURN)


def test_the_fillet_swings_out_more_as_the_kink_sharpens() -> None:
    swings = [pinch.fillet_swing(g, RC, TURN) for g in np.linspace(0.0, 1.0, 11)]
    assert swings[0] == pytest.approx(0.0, abs=1e-12)
    assert all(b > a for a, b in zip(swings[:-1], swings[1:], strict=True))
    assert swings[-1] == pytest.approx(math.hypot(0.5, math.sqrt(TURN * (TURN + 1.0)) - TURN)
                                       - 0.5)
    assert pinch.fillet_swing(1.5, RC, TURN) == swings[-1]  # beyond 2 rc: as at 2 rc
    assert pinch.fillet_swing(0.9, RC, 0.0) == pytest.approx(0.0, abs=1e-12)  # on the spot


def test_a_pole_ahead_that_the_circle_clears_is_no_wall() -> None:
    q, kappa = _circled()
    # the next pole's near side 1.3 m straight ahead: the circle (radius 0.6 round (0, -0.6))
    # passes it 0.83 m off; at 0.75 m ahead, 0.36 m off: the front ray must act
    assert pinch.clear_ahead(1.3, q, RC, 0.0, kappa, RC)
    assert not pinch.clear_ahead(0.75, q, RC, 0.0, kappa, RC)
    # following a wall, whatever lies ahead is met: the front ray decides
    assert not pinch.clear_ahead(1.3, q, RC, 0.0, 0.0, RC)


def _legs(gaps: tuple[float, float], radius: float = 0.03) -> tuple[Circle, ...]:
    """Four legs of ``radius`` whose surfaces are ``gaps`` (x, y) apart."""
    hx, hy = gaps[0] / 2.0 + radius, gaps[1] / 2.0 + radius
    return tuple(Circle((x, y), radius) for x in (-hx, hx) for y in (-hy, hy))


@pytest.mark.parametrize("gaps", [(0.83, 0.995), (0.995, 0.83), (0.83, 1.005)])
def test_a_table_whose_gap_is_within_a_centimetre_of_2rc_is_followed_at_rc(
        gaps: tuple[float, float]) -> None:
    # one pair of sides 2 rc to within 5 mm: the robot goes round the legs without turning
    # in among them (before atoms/pinch.py: 0.15-0.35 m from a leg, each time round)
    world = sim.World("table", obstacles=_legs(gaps), start_pose=Pose(-4.0, 0.2, 0.0),
                      robot=IDEAL)
    t, _, d = follow_run(world, 40.0)
    late = t > 20.0
    assert d[late].min() > 0.38
    assert np.abs(d[late] - RC).mean() < 0.04


def test_a_pole_circled_out_of_view_and_the_next_2rc_away_are_two_things() -> None:
    # the pole circled has gone behind the robot (remembered, at -115 deg); the next pole is
    # 1.1 m from it: no face runs between them, or it would be in view, nearer
    behind = 0.5 * complex(math.cos(math.radians(-115.0)), math.sin(math.radians(-115.0)))
    nxt = complex(0.85, 0.1)
    assert abs(nxt - behind) > 1.0
    assert pinch.apart_behind(behind, nxt, 0.5, RC)
    # in view, the scan decides (atoms/corners.py); nearer than 2 rc, a kink; the robot
    # still 2 rc or more from the one: approaching both
    assert not pinch.apart_behind(complex(0.1, -0.5), nxt, 0.51, RC)
    assert not pinch.apart_behind(behind, complex(0.3, -0.5), 0.5, RC)
    assert not pinch.apart_behind(2.2 * behind, nxt + 1.0, 1.1, RC)


def test_a_point_circled_out_of_view_beats_one_on_the_other_side_on_a_quick_robot() -> None:
    # the nearest point on the other side (tangent past a right angle): no margin at all
    assert pinch.bridge_margin(0.6 * math.pi, True, 0.05, quick=True) == 0.0
    # on the followed side: a point by 5 mm, a fitted face by the bridge margin
    assert pinch.bridge_margin(0.2, True, 0.05, quick=True) == 0.005
    assert pinch.bridge_margin(0.2, False, 0.05, quick=True) == 0.05
    # a robot that ramps keeps the margins wherever the point is
    assert pinch.bridge_margin(0.6 * math.pi, False, 0.05, quick=False) == 0.05
