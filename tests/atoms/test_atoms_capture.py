"""Capture and recapture: the followed side wins in the safety layer, a lost boundary is
searched for (never abandoned), and ``lost`` tells a plan how long it has been lost."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdle.atoms import safety
from mdle.atoms import steering as S
from mdle.atoms.follow import FollowState, lost
from mdle.atoms.registry import Context
from mdle.core.backend import Observation
from mdle.core.pose import Pose
from mdle.lang import load_text
from mdle.runtime import run
from mdle.runtime.events import Cause
from mdle.runtime.scripted import ScriptedBackend
from tests.atoms.conftest import cast_line, make_scan

G = S.Gains()


def _z(points: np.ndarray) -> np.ndarray:
    """Robot-frame points (M, 2) as complex numbers (M,), as the safety layer reads them."""
    return points[:, 0] + 1j * points[:, 1]


def _nearest_side(points: np.ndarray, v: float, u: float, horizon: float) -> float:
    """Return the cross product sign of the arc's heading with its nearest point (+: left)."""
    t = np.linspace(1e-3, horizon, 400)
    th = u * t
    if abs(u) < 1e-9:
        path = np.stack((v * t, 0 * t), axis=1)
    else:
        path = np.stack((v * np.sin(th) / u, v * (1 - np.cos(th)) / u), axis=1)
    d = np.hypot(path[:, None, 0] - points[None, :, 0], path[:, None, 1] - points[None, :, 1])
    i, j = np.unravel_index(np.argmin(d), d.shape)
    rel = points[j] - path[i]
    return float(math.cos(th[i]) * rel[1] - math.sin(th[i]) * rel[0])


@pytest.mark.parametrize("side", [-1, 1])
def test_safety_layer_passes_a_post_on_the_followed_side(side: int) -> None:
    # a thin post just off the heading on the *blind* side: the nearest escape would pass it
    # there; the followed side wins and the robot swings round it the other way
    post = np.array([[0.35, -0.02 * side]])
    v, u, own = safety.filter_complex(_z(post), 1.0, 0.0, 3.0, 0.0, 0.05, 0.5, side=side)
    assert own < 0.05
    assert u * side < 0  # right-hand following turns left, and the other way round
    assert _nearest_side(post, v, u, 0.5) * side > 0


def test_safety_layer_never_slides_along_a_face_with_the_obstacle_on_the_blind_side() -> None:
    # a face ahead at 60 deg to the heading, the obstacle beyond it on the left: putting it on
    # the right needs more than a 90 deg left turn. Going straight (or right) slides along the
    # face with the obstacle on the left; the layer must turn left, slower if need be.
    s = np.linspace(-3.0, 3.0, 300)[:, None]
    direction = np.array([[math.cos(math.radians(60)), math.sin(math.radians(60))]])
    face = np.array([[0.6, 0.0]]) + s * direction
    face = face[np.hypot(face[:, 0], face[:, 1]) < 8.0]
    v, u, _ = safety.filter_complex(_z(face), 1.0, 3.0, 3.0, 0.0, 0.15, 0.8, side=-1)
    assert u > 0
    if v > 0:
        assert _nearest_side(face, v, u, 0.8) < 0


def test_safety_layer_turns_on_the_spot_towards_the_followed_side() -> None:
    # walls all round: no arc is admissible at any speed
    a = np.linspace(0.0, 2 * math.pi, 200, endpoint=False)
    ring = 0.3 * np.stack((np.cos(a), np.sin(a)), axis=1)
    z = _z(ring)
    assert safety.filter_complex(z, 1.0, -1.0, 3.0, 0.0, 0.15, 0.8, side=-1)[:2] == (0.0, 3.0)
    assert safety.filter_complex(z, 1.0, 1.0, 3.0, 0.0, 0.15, 0.8, side=1)[:2] == (0.0, -3.0)


def test_a_robot_that_never_saw_the_boundary_drives_straight_on() -> None:
    mem = S.Memory()
    for k in range(50):
        u = S.step(S.MISS, S.MISS, (0.02 * k, 0.0, 0.0), 0.02 * k, 0.02, mem, 1.0, 0.5, G)
        assert u == 0.0 and mem.mode == S.FOLLOW
    assert mem.lost_for(1.0) == 0.0


def test_a_face_lost_beyond_corner_reach_is_searched_for() -> None:
    # late capture: the side ray saw a face 1.5 m away (beyond corner reach, 2 rc = 1 m), then
    # the face ended. The robot circles the point it saw, obstacle on the right.
    mem = S.Memory()
    S.step(S.MISS, S.Ray(True, 1.5, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0, 0.02, mem, 1.0, 0.5, G)
    assert mem.seen == pytest.approx((0.0, -1.5))
    u = S.step(S.MISS, S.MISS, (0.02, 0.0, 0.0), 0.02, 0.02, mem, 1.0, 0.5, G)
    assert mem.mode == S.SEARCH and mem.corner == pytest.approx((0.0, -1.5))
    assert u < 0  # towards the point on the right
    assert mem.lost_for(0.52) == pytest.approx(0.52)  # seen last at t = 0
    # a ray finds the boundary again: back to following
    S.step(S.MISS, S.Ray(True, 0.7, 0.1, 0.0), (0.3, -0.2, -0.5), 0.6, 0.02, mem, 1.0, 0.5, G)
    assert mem.mode == S.FOLLOW and mem.lost_for(0.6) == 0.0


def test_a_search_closes_in_on_the_point_seen_last() -> None:
    # integrate the search: from 3 m away the robot ends up circling the point at about rc
    mem = S.Memory()
    S.step(S.Ray(True, 1.4, 1.0, 0.0), S.MISS, (0.0, 0.0, 0.0), 0.0, 0.02, mem, 1.0, 0.5, G)
    x, y, th = -1.6, 0.0, math.pi / 2  # moved away, now heading north
    dt = 0.02
    dists = []
    for k in range(1, 1500):
        u = S.step(S.MISS, S.MISS, (x, y, th), k * dt, dt, mem, 1.0, 0.5, G)
        assert mem.mode == S.SEARCH
        x += math.cos(th + 0.5 * u * dt) * dt
        y += math.sin(th + 0.5 * u * dt) * dt
        th += u * dt
        dists.append(math.hypot(x - 1.4, y))
    assert max(abs(d - 0.5) for d in dists[-300:]) < 0.05


def test_corner_mode_that_gives_up_keeps_searching() -> None:
    mem = S.Memory()
    S.step(S.MISS, S.Ray(True, 0.5, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0, 0.02, mem, 1.0, 0.5, G)
    S.step(S.MISS, S.MISS, (0.02, 0.0, 0.0), 0.02, 0.02, mem, 1.0, 0.5, G)
    assert mem.mode == S.CORNER
    mem.turned = G.corner_max_turn + 0.1
    u = S.step(S.MISS, S.MISS, (0.04, 0.0, 0.0), 0.04, 0.02, mem, 1.0, 0.5, G)
    assert mem.mode == S.SEARCH and u != 0.0


def test_lost_sensor_reads_the_running_follow_atom() -> None:
    mem = S.Memory(seen=(1.0, 0.0), seen_at=2.0)
    state = FollowState(side=None, gains=G, memory=mem, t0=10.0)  # type: ignore[arg-type]
    ctx = Context(Observation(15.0, Pose()), 0.0, 0.1, None, atom=state)  # type: ignore[arg-type]
    assert lost({}, ctx) == pytest.approx(3.0)
    ctx.atom = None
    assert lost({}, ctx) == 0.0


def test_a_plan_ends_a_search_with_lost() -> None:
    # a wall on the right for the first second, then nothing: the atom searches, and the
    # plan's `lost > 0.5 s` ends it about 0.5 s after the wall vanished
    wall = make_scan(cast_line((0.0, -0.5), (0.0, 1.0)))
    empty = make_scan(np.full(wall.ranges.shape, np.inf))
    program = load_text(
        "atom f = (follow_boundary(side = right, rc = 0.5 m, v = 0.5 m/s), lost > 0.5 s, 10 s)\n"
        "run f\n")
    backend = ScriptedBackend(lambda t, k: {"scan": wall if t < 1.0 else empty})
    result = run(program.elements["f"], backend, rate=20)
    t = result.termination
    assert t.cause is Cause.INTERRUPT
    assert 1.4 <= t.time <= 1.6
    # while it searched, the robot turned towards where the wall was (right)
    late = [c.omega for time, c in backend.commands if 1.0 <= time < t.time - 1e-6]
    assert late and all(w < 0 for w in late), late
