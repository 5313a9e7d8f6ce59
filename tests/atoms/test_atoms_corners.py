"""Concave corners of the rc level set: when the whole-scan model weighs in the next face.

Two things closer than ``2 rc`` make one level set with a concave corner between them (a
table's legs, a pole row's pillars, a star's tips): the robot must turn before it. Farther
apart, each has its own closed level set, and the robot circles the one it follows. A face
that runs on along the chord (the far face of a convex corner, seen edge on) makes no
corner at all.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdle import sim
from mdle.atoms import closest as C
from mdle.atoms import corners
from mdle.atoms import steering as S
from mdle.atoms.ramped_arcs import Ramp
from mdle.core.pose import Pose
from mdle.lang import load_text
from mdle.runtime import Recorder, run
from mdle.sim.profiles import robot_profile
from mdle.sim.shapes import Circle, Polygon
from tests.atoms.conftest import follow_run

IDEAL = robot_profile("ideal")
FAN = np.exp(1j * np.radians(np.arange(-90.0, 90.5, 1.0)))  # the LMS-200's 181 beams


def _discs(discs: list[tuple[complex, float]]) -> np.ndarray:
    """Cast the fan from the origin at discs (centre, radius): the points hit, beam order."""
    r = np.full(FAN.size, np.inf)
    for c, rho in discs:
        b = (FAN.conjugate() * c).real
        disc = b * b - abs(c) ** 2 + rho * rho
        hit = np.where(disc >= 0, b - np.sqrt(np.maximum(disc, 0.0)), np.inf)
        r = np.minimum(r, np.where(hit > 0, hit, np.inf))
    ok = np.isfinite(r)
    return r[ok] * FAN[ok]


def _segments(points: list[complex]) -> np.ndarray:
    """Cast the fan at the polyline through ``points``: the points hit, beam order."""
    r = np.full(FAN.size, np.inf)
    for a, b in zip(points[:-1], points[1:], strict=True):
        e = b - a
        den = (FAN.conjugate() * 1j * e).real  # beam . normal
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (a.conjugate() * 1j * e).real / den  # range along the beam
            hit = FAN * t
            s = ((hit - a) * e.conjugate()).real / abs(e) ** 2  # place along the segment
        ok = (t > 0) & (s >= 0) & (s <= 1)
        r = np.minimum(r, np.where(ok, t, np.inf))
    ok = np.isfinite(r)
    return r[ok] * FAN[ok]


def test_a_gap_between_two_poles_is_recessed() -> None:
    q, p = complex(0.0, -0.45), complex(0.9, -0.45)  # their near sides, 0.9 m apart
    z = _discs([(q - 0.02j, 0.02), (p - 0.02j, 0.02)])
    assert corners.recessed(z, q, p, 0.5)


def test_a_wall_between_two_points_is_not_recessed() -> None:
    q, p = complex(0.0, -0.5), complex(0.8, -0.5)
    z = _segments([complex(-3.0, -0.5), complex(3.0, -0.5)])
    assert not corners.recessed(z, q, p, 0.5)


def test_a_notch_between_two_tips_is_recessed() -> None:
    # two tips 0.8 m apart and a notch 0.6 m deep between them
    q, p = complex(0.0, -0.5), complex(0.8, -0.5)
    z = _segments([complex(-0.3, -1.2), q, complex(0.4, -1.1), p, complex(1.1, -1.2)])
    assert corners.recessed(z, q, p, 0.5)


def test_the_far_face_of_a_convex_corner_seen_edge_on_is_not_recessed() -> None:
    # the robot has just passed a square's vertex (behind it, out of the ladar's view); the
    # next face runs away from it along the beams at -90 deg: neighbouring beams sample it
    # 0.2-0.4 m apart, but no beam between them is missing
    q = complex(-0.1, -0.47)
    z = _segments([q, q + 5.0 * complex(0.15, -0.51)])
    p = complex(z[np.argmin(np.abs(z - complex(0.05, -0.98)))])
    assert abs(p - q) < 1.0 and np.abs(np.diff(z)).max() > C.JUMP  # split by depth jumps
    assert not corners.recessed(z, q, p, 0.5)


def _ray(point: complex) -> S.Ray:
    """The nearest-point ray standing for ``point`` (bearing ``beta - pi/2``)."""
    return S.Ray(True, abs(point), math.atan2(point.real, -point.imag), C.POINT_KAPPA)


def test_a_pole_farther_than_2rc_from_the_one_followed_has_no_weight() -> None:
    # circling a pole at rc: the next pole is 1.2 m on, its level set a circle of its own
    a, b = complex(0.0, -0.5), complex(0.97, -0.1)
    assert abs(b - a) > 1.0
    z = _discs([(a - 0.03j, 0.03), (b - 0.03j, 0.03)])
    near, ahead = _ray(a), _ray(b)
    assert (near.r + 0.5 - ahead.r) / 0.5 > 0.0  # the plain weight would blend it in
    assert corners.next_face_weight(z, a, b, near.r, ahead.r, 1.0, 0.5, 3.0) == 0.0


def test_the_next_leg_of_a_table_is_weighed_in_while_a_full_turn_still_clears_it() -> None:
    # the next leg 0.65 m off and 25 deg right of the heading: a full left turn (radius
    # v / umax = 0.33 m) from here passes it at 0.51 m, just outside rc, so its law has
    # nearly the whole weight already, where the plain weight gives it 0.7
    a = complex(0.0, -0.5)
    b = 0.65 * complex(math.cos(math.radians(-25.0)), math.sin(math.radians(-25.0)))
    z = _discs([(a - 0.012j, 0.012), (b * (1 + 0.012 / 0.65), 0.012)])
    near, ahead = _ray(a), _ray(b)
    assert abs(b - a) < 1.0
    assert (near.r + 0.5 - ahead.r) / 0.5 == pytest.approx(0.7)
    assert corners.next_face_weight(z, a, b, near.r, ahead.r, 1.0, 0.5, 3.0) > 0.95


def test_a_table_is_followed_at_rc_at_one_metre_a_second() -> None:
    # four 2.4 cm legs 0.88 m and 1.06 m apart (gaps narrower than 2 rc): one level set with
    # four concave corners; the nearest point jumps to each next leg when it is already at rc
    legs = tuple(Circle((x, y), 0.012) for x in (-0.44, 0.44) for y in (-0.53, 0.53))
    world = sim.World("table", obstacles=legs, start_pose=Pose(-4.0, 0.2, 0.0), robot=IDEAL)
    t, _, d = follow_run(world, 40.0)
    late = t > 20.0
    assert d.min() > 0.3
    assert np.abs(d[late] - 0.5).mean() < 0.06


def test_poles_farther_apart_than_2rc_are_circled_not_blended() -> None:
    # a gap of 1.1 x 2 rc: each pole has a level set of its own, and the next one's law is
    # not blended in while the robot circles the one it follows (which drew it off by 0.066 m
    # on average: the weight, near 1 each time it passed the other pole, pulled it outwards)
    poles = (Circle((0.0, 0.0), 0.035), Circle((1.17, 0.0), 0.035))
    world = sim.World("pair", obstacles=poles, start_pose=Pose(-4.0, 0.3, 0.0), robot=IDEAL)
    t, _, d = follow_run(world, 40.0)
    late = t > 20.0
    assert np.abs(d[late] - 0.5).mean() < 0.045


@pytest.mark.parametrize("side", ["right", "left"])
def test_the_noisy_square_is_not_changed_by_the_corner_rules(side: str) -> None:
    # a square has no concave corner: the rules above must leave its run as it was, which a
    # zero weight or a floor where none belongs would change from the first tick
    square = Polygon(((-2.0, -2.0), (2.0, -2.0), (2.0, 2.0), (-2.0, 2.0)))
    y0 = 0.3 if side == "right" else -0.3
    program = load_text(f"atom f = (follow_boundary(side = {side}, rc = 0.5 m, v = 1 m/s),"
                        " never, 30 s)\nrun f\n")
    traces = []
    for rule in (corners.next_face_weight, _plain_weight):
        rec = Recorder()
        world = sim.World("square", obstacles=(square,), start_pose=Pose(-6.0, y0, 0.0),
                          robot=IDEAL)
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(corners, "next_face_weight", rule)
            run(program.elements["f"], sim.SimBackend(world, seed=2, sensing="scan"),
                rate=50.0, observers=[rec])
        traces.append(np.array([(s.true_x, s.true_y) for s in rec.samples]))
    assert np.array_equal(traces[0], traces[1])


def _plain_weight(z: np.ndarray, q: complex, p: complex, r: float, r_next: float, v: float,
                  rc: float, umax: float, ramp: Ramp | None = None) -> float:
    """The next face's weight without the corner rules: ``(r + rc - r_next) / rc``.

    ``ramp`` (a ramping robot's turn, which the corner floor reads) changes nothing here.
    """
    return (r + rc - r_next) / rc
