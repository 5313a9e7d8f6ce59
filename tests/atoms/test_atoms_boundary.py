"""The boundary view and the boundary sensor functions: conventions, mirroring, oracle, cache."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import pytest

from mdle.atoms import default_registry
from mdle.atoms.boundary import Side, boundary_view, cached_beams, cached_view, parse_side
from mdle.atoms.estimators import valid_points
from mdle.atoms.follow import scan_points_cached, scan_points_complex
from mdle.atoms.registry import Context
from mdle.core.backend import Observation, RobotLimits, Scan
from mdle.core.pose import Pose

if TYPE_CHECKING:
    from tests.atoms.conftest import Case, Raycast, World2D

LIMITS = RobotLimits(1.0, 1.0, 3.0)
SENSORS = ("boundary_range", "boundary_curvature", "boundary_tangent")


def _ctx(scan: Scan | None) -> Context:
    return Context(Observation(0.0, Pose(), scan=scan), 0.0, 0.1, LIMITS)


def _mirror(scan: Scan) -> Scan:
    """The same scene reflected left-right (y -> -y)."""
    return Scan(scan.ranges[::-1].copy(), -scan.bearings[::-1], scan.valid[::-1].copy(),
                scan.stamp, scan.max_range)


@pytest.mark.parametrize("name", SENSORS)
@pytest.mark.parametrize("side", ["right", "left"])
def test_sensor_functions_over_the_catalogue(case: Case, name: str, side: str) -> None:
    fn = default_registry().sensors[name].fn
    value = fn({"side": side}, _ctx(case.scan))
    assert isinstance(value, float) and math.isfinite(value)
    if case.curvature is None:  # nothing seen: max range, and the virtual boundary's 0s
        assert value == (case.scan.max_range if name == "boundary_range" else 0.0)


def test_no_scan_yet_is_a_miss_not_an_error() -> None:
    reg = default_registry()
    assert reg.sensors["boundary_range"].fn({"side": "right"}, _ctx(None)) == math.inf
    assert reg.sensors["boundary_curvature"].fn({"side": "left"}, _ctx(None)) == 0.0


def test_wall_on_the_right(raycast: Raycast) -> None:
    view = boundary_view(raycast.catalogue["straight_wall"].scan, "right")
    assert view.side.hit and view.side.r == pytest.approx(0.5)
    assert view.side.beta == pytest.approx(0.0, abs=1e-9)
    assert view.side.kappa == pytest.approx(0.0, abs=1e-9)
    assert not view.front.hit  # a wall parallel to the heading never meets the front ray
    assert not boundary_view(raycast.catalogue["straight_wall"].scan, "left").side.hit


@pytest.mark.parametrize("radius", [1.0, 2.0])
def test_circle_on_the_right_is_convex_negative(raycast: Raycast, radius: float) -> None:
    # the circle's top at 0.5 m to the right: its tangent there is the heading
    scan = raycast.scan(raycast.circle((0.0, -0.5 - radius), radius))
    view = boundary_view(scan, "right")
    assert view.side.kappa == pytest.approx(-1.0 / radius, rel=0.05)
    assert view.side.beta == pytest.approx(0.0, abs=0.01)
    ctx = _ctx(scan)
    reg = default_registry()
    assert reg.sensors["boundary_curvature"].fn({"side": "right"}, ctx) == view.side.kappa


def test_left_is_the_mirror_of_right(raycast: Raycast) -> None:
    scan = raycast.scan(raycast.circle((1.0, -1.0), 1.2))
    right = boundary_view(scan, "right")
    assert right.side.hit and right.front.hit
    left = boundary_view(_mirror(scan), "left")
    for a, b in ((right.front, left.front), (right.side, left.side)):
        assert a.hit == b.hit
        assert a.r == pytest.approx(b.r, nan_ok=True)
        assert a.beta == pytest.approx(b.beta, abs=1e-9)
        assert a.kappa == pytest.approx(b.kappa, abs=1e-9)
    # the sensor functions answer in the side's own orientation: convex positive on the left
    reg = default_registry()
    k_left = reg.sensors["boundary_curvature"].fn({"side": "left"}, _ctx(_mirror(scan)))
    assert k_left == pytest.approx(-right.side.kappa) and k_left > 0


def test_front_ray_on_a_facing_wall(raycast: Raycast) -> None:
    scan = raycast.scan(raycast.line((2.0, 0.0), (1.0, 0.0)))
    view = boundary_view(scan, "right")
    assert view.front.hit and view.front.r == pytest.approx(2.0)
    # oriented obstacle-on-right: the wall is crossed going left, beta = +90 deg
    assert view.front.beta == pytest.approx(math.pi / 2, abs=1e-9)
    assert boundary_view(scan, "left").front.beta == pytest.approx(math.pi / 2, abs=1e-9)


def test_oracle_scan_values_are_used_as_given(world2d: World2D) -> None:
    shape = world2d.Shape("circle", center=(0.0, -1.5), radius=1.0)
    scan = world2d.scan(shape, 0.0, 0.0, 0.0)
    view = boundary_view(scan, "right")
    assert view.exact
    # on a smooth boundary the exact curvature stands (no vertex ahead adds turning)
    assert view.side.kappa == pytest.approx(-1.0, abs=1e-4)
    assert view.side.beta == pytest.approx(0.0, abs=1e-12)
    left = boundary_view(world2d.scan(world2d.Shape("circle", center=(0.0, 1.5), radius=1.0),
                                      0.0, 0.0, 0.0), "left")
    assert left.side.kappa == pytest.approx(-1.0, abs=1e-4)
    assert left.side.beta == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("side", ["right", "left"])
def test_exact_side_curvature_anticipates_a_convex_vertex_ahead(world2d: World2D,
                                                                side: str) -> None:
    # a face 0.5 m to the side with a 45-degree convex corner 0.2 m ahead: the exact
    # curvature is 0 on the face, but the turning at the corner within the side window shows
    sgn = -1.0 if side == "right" else 1.0
    sq = [(-3.0, sgn * 0.5), (0.2, sgn * 0.5), (3.7, sgn * 4.0), (-3.0, sgn * 4.0)]
    view = boundary_view(world2d.scan(world2d.Shape("polygon", vertices=sq), 0.0, 0.0, 0.0),
                         side)
    assert view.exact and view.side.hit
    assert view.side.kappa < -0.5
    # the corner far ahead, beyond the window: nothing to anticipate
    far = [(-3.0, sgn * 0.5), (3.0, sgn * 0.5), (3.0, sgn * 4.0), (-3.0, sgn * 4.0)]
    view = boundary_view(world2d.scan(world2d.Shape("polygon", vertices=far), 0.0, 0.0, 0.0),
                         side)
    assert view.side.kappa == pytest.approx(0.0, abs=1e-9)


def test_exact_side_curvature_ignores_a_concave_corner_ahead(world2d: World2D) -> None:
    # a wall on the right meeting a wall ahead (inside an L): the front ray's business
    room = [(-3.0, -0.5), (1.0, -0.5), (1.0, 3.0), (5.0, 3.0), (5.0, -4.0), (-3.0, -4.0)]
    view = boundary_view(world2d.scan(world2d.Shape("polygon", vertices=room), 0.0, 0.0, 0.0),
                         "right")
    assert view.side.kappa == pytest.approx(0.0, abs=1e-9)


def test_depth_jump_at_the_side_ray_is_not_smoothed_over(raycast: Raycast) -> None:
    # a short near post at -90..-85 deg in front of a far wall: too few beams for a surface
    r = raycast.line((0.0, -3.0), (0.0, -1.0))
    r = np.where(raycast.bearings < np.radians(-86.5), 0.5, r)
    view = boundary_view(raycast.scan(r), "right")
    assert not view.side.hit


def test_view_is_computed_once_per_tick(raycast: Raycast) -> None:
    ctx = _ctx(raycast.catalogue["circle_R1"].scan)
    assert cached_view(ctx, "right") is cached_view(ctx, Side.RIGHT)


def test_parse_side_lists_the_options() -> None:
    assert parse_side("right") is Side.RIGHT
    with pytest.raises(ValueError, match="right, left"):
        parse_side("up")


def test_view_and_scan_points_share_the_ticks_masked_points(raycast: Raycast) -> None:
    # a wall on the right, a gap of invalid and non-positive beams, a cylinder ahead
    r = np.minimum(raycast.line((0.0, -0.6), (0.0, -1.0)), raycast.circle((1.5, 0.0), 0.5))
    valid = np.ones(r.size, dtype=bool)
    valid[40:45] = False
    r[50] = 0.0
    r[60] = np.inf
    scan = Scan(r, raycast.bearings, valid, 0.0, 10.0)
    ctx = _ctx(scan)
    for side in ("right", "left"):
        assert cached_view(ctx, side) == boundary_view(scan, side)  # the cached path agrees
    beams = cached_beams(ctx)
    assert beams is not None and beams is ctx.cache["beams"]  # one computation per tick
    z, seen, masked = beams
    assert seen.tolist() == (valid & np.isfinite(r) & (r > 0)).tolist()
    assert np.isnan(masked[~seen]).all() and np.array_equal(masked[seen], r[seen])
    points = scan_points_cached(ctx)
    assert np.array_equal(points, valid_points(r, raycast.bearings, valid))
    assert points.shape == (int(seen.sum()), 2) and np.isfinite(points).all()
    z_points = scan_points_complex(ctx)
    assert np.array_equal(np.stack((z_points.real, z_points.imag), 1), points)
    assert scan_points_complex(_ctx(None)).shape == (0,)


def test_no_surface_at_either_rays_beam_gives_two_misses(raycast: Raycast) -> None:
    # everything is seen except the -90 and 0 degree beams themselves
    r = np.full(raycast.bearings.size, 1.0)
    valid = np.ones(r.size, dtype=bool)
    valid[[0, 90]] = False
    view = boundary_view(Scan(r, raycast.bearings, valid, 0.0, 10.0), "right")
    assert not view.side.hit and not view.front.hit
    assert cached_beams(_ctx(None)) is None
