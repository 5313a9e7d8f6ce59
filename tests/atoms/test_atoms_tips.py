"""A tip seen from one flank is a point (atoms/tips.py, ``ends_at_nearest``).

A circle fitted to the one flank of a sharp tip that the robot sees carries on past the tip:
its nearest point lies on the flank's extension, a straight face where the boundary is a
point to turn round. These tests pin the rule that takes the tip itself then, and what it is
for: a spike star whose tips are closer than ``2 rc``, followed at 1 m/s.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdle import sim
from mdle.atoms import closest as C
from mdle.atoms import tips as T
from mdle.core.pose import Pose
from mdle.sim.profiles import robot_profile
from mdle.sim.shapes import Polygon
from tests.atoms.conftest import BEARINGS, Shape, World2D, follow_run


def _points(shape: Shape) -> np.ndarray:
    """Scan ``shape`` from the origin, heading +x, with 1-degree beams: the points hit."""
    r, _, _ = shape.cast(0.0, 0.0, 0.0, BEARINGS)
    hit = np.isfinite(r)
    return np.asarray(r[hit] * np.exp(1j * BEARINGS[hit]))


def _spike(tip: complex, axis_deg: float, half_deg: float = 15.0, length: float = 1.0
           ) -> list[tuple[float, float]]:
    """A thin isosceles spike (counter-clockwise) whose tip points along ``axis_deg``."""
    a, h = math.radians(axis_deg), math.radians(half_deg)
    ends = [tip - length * complex(math.cos(a - h), math.sin(a - h)),
            tip - length * complex(math.cos(a + h), math.sin(a + h))]
    return [(p.real, p.imag) for p in (tip, *ends)]


def test_a_tip_seen_from_one_flank_is_its_point(world2d: World2D) -> None:
    # the tip 0.58 m off at -59 deg, pointing ahead-left: the robot sees its right flank only,
    # and a line fitted to that flank runs on past the tip to a foot 5 cm nearer the robot
    tip = complex(0.3, -0.5)
    z = _points(world2d.Shape("poly", vertices=_spike(tip, 70.0)))
    ray = C.nearest_point(z, 0.25)
    assert ray.kappa == C.POINT_KAPPA  # a point, not the flank's straight line
    assert ray.r == pytest.approx(abs(tip), abs=0.01)
    # the tangent is perpendicular to the line of sight
    assert ray.beta == pytest.approx(math.atan2(tip.real, -tip.imag), abs=0.02)


def test_the_flank_beside_the_robot_is_still_a_face(world2d: World2D) -> None:
    # the same spike, the robot beside its flank (the flank's nearest point among its points)
    tip = complex(0.6, -0.45)
    z = _points(world2d.Shape("poly", vertices=_spike(tip, 10.0)))
    ray = C.nearest_point(z, 0.25)
    assert ray.kappa == pytest.approx(0.0, abs=1e-6)
    assert ray.r < abs(tip) - 0.05


def test_a_pole_beyond_the_field_of_view_is_still_carried_on_along_its_circle() -> None:
    # a pole of radius 10 cm whose nearest point lies 5 deg behind the ladar's -90 deg beam:
    # only the arc in view is seen, and its fit carries on to the unseen nearest point
    centre, rho = complex(-0.05, -0.6), 0.1
    arc = centre + rho * np.exp(1j * np.linspace(0.0, math.pi, 181))
    z = arc[np.abs(np.angle(arc)) <= math.pi / 2]
    ray = C.nearest_point(z, 0.25)
    assert ray.r == pytest.approx(abs(centre) - rho, abs=1e-6)
    assert ray.kappa == pytest.approx(-1.0 / rho, rel=1e-6)


@pytest.mark.parametrize(("s", "expected"), [
    (0.1, True),     # 10 cm past the last point on that side, in view: the tip ends there
    (0.02, False),   # within three beams of the last point: at it
    (-0.05, False),  # among the points fitted
])
def test_a_foot_past_the_end_of_the_points_in_view_means_the_boundary_ends(
        s: float, expected: bool) -> None:
    flank = np.linspace(0.0, -0.2, 11) + 0.0j  # the points, all on one side of q
    assert T.ends_at_nearest(flank, complex(s, 0.0), complex(0.3, -0.45), 0.6) is expected
    # the same foot at the edge of the field of view: unseen there, not ended
    assert T.ends_at_nearest(flank, complex(s, 0.0), complex(-0.01, -0.6), 0.6) is False


def _star(n: int, outer: float, tip_deg: float) -> Polygon:
    """A star polygon of ``n`` spikes whose tips are ``tip_deg`` sharp."""
    tan = math.tan(math.radians(tip_deg) / 2.0)
    inner = outer * tan / (math.sin(math.pi / n) + tan * math.cos(math.pi / n))
    angles = np.pi * np.arange(2 * n) / n
    radii = np.where(np.arange(2 * n) % 2 == 0, outer, inner)
    return Polygon(tuple(zip((radii * np.cos(angles)).tolist(),
                             (radii * np.sin(angles)).tolist(), strict=True)), name="star")


def test_a_star_whose_tips_are_closer_than_2rc_is_followed_round_its_tips_at_rc() -> None:
    # 9 tips of 30 deg, 0.74 m apart (0.74 x 2 rc): the rc level set is a chain of arcs round
    # the tips with concave kinks of about 100 deg between them. Before the tips counted as
    # points, the robot circled each one about 0.1 m outside rc (late mean error 0.10-0.16 m)
    star = _star(9, 1.08, 30.0)
    world = sim.World("star", obstacles=(star,), start_pose=Pose(-4.0, 0.3, 0.0),
                      robot=robot_profile("ideal"))
    t, _, d = follow_run(world, 40.0)
    assert d.min() > 0.3
    late = t > 20.0
    assert np.abs(d[late] - 0.5).mean() < 0.06
