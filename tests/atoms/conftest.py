"""Catalogue of canonical scans for the atoms tests (analytic ray casts, no simulator).

Every scan is an LMS-200-like sweep: 181 beams from -90 to +90 degrees (index 0 on the
robot's right), maximum range 10 m, beams with no return at max range and ``valid=False``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pytest

from mdle.backend import Scan

MAX_RANGE = 10.0
BEARINGS = np.radians(np.arange(-90.0, 90.5, 1.0))


def cast_circle(center: tuple[float, float], radius: float,
                bearings: np.ndarray = BEARINGS) -> np.ndarray:
    """Range to a circle from the origin along each bearing (inf where the ray misses)."""
    d = np.stack((np.cos(bearings), np.sin(bearings)), axis=1)
    c = np.asarray(center, dtype=float)
    b = d @ c
    disc = b * b - (c @ c - radius * radius)
    r = b - np.sqrt(np.where(disc >= 0, disc, np.nan))
    return np.where((disc >= 0) & (r > 0), r, np.inf)


def cast_line(point: tuple[float, float], normal: tuple[float, float],
              bearings: np.ndarray = BEARINGS) -> np.ndarray:
    """Range to the infinite line through ``point`` with ``normal`` (inf where parallel/behind)."""
    n = np.asarray(normal, dtype=float)
    d = np.stack((np.cos(bearings), np.sin(bearings)), axis=1)
    den = d @ n
    with np.errstate(divide="ignore"):
        r = (np.asarray(point, dtype=float) @ n) / den
    return np.where((den != 0) & (r > 0), r, np.inf)


def make_scan(ranges: np.ndarray, bearings: np.ndarray = BEARINGS,
              max_range: float = MAX_RANGE) -> Scan:
    """A Scan from ranges (inf/NaN or beyond max range: no return)."""
    r = np.asarray(ranges, dtype=float)
    valid = np.isfinite(r) & (r < max_range)
    return Scan(np.where(valid, r, max_range), np.asarray(bearings, dtype=float), valid, 0.0,
                max_range)


@dataclass(frozen=True)
class Case:
    """A catalogue entry: the scan and what the truth is where the estimate is defined."""

    name: str
    scan: Scan
    curvature: Callable[[np.ndarray], np.ndarray] | None  # truth per beam index, None: no beam valid
    min_valid: int  # beams at least this many must be valid for a 1-beam window


def _catalogue() -> dict[str, Case]:
    empty = Scan(np.zeros(0), np.zeros(0), np.zeros(0, bool), 0.0, MAX_RANGE)
    invalid = Scan(np.full(181, np.nan), BEARINGS, np.zeros(181, bool), 0.0, MAX_RANGE)
    at_max = make_scan(np.full(181, MAX_RANGE))
    wall = make_scan(cast_line((0.0, -0.5), (0.0, -1.0)))          # wall on the right, y = -0.5
    circle = make_scan(cast_circle((2.0, 0.0), 1.0))                # R = 1 m, 1 m ahead
    corner_r = np.minimum(cast_line((1.5, 0.0), (1.0, 0.0)), cast_line((0.0, -0.8), (0.0, -1.0)))
    corner = make_scan(corner_r)                                     # concave right-angle corner
    zero = lambda idx: np.zeros(idx.shape)  # noqa: E731
    return {
        "empty": Case("empty", empty, None, 0),
        "all_invalid": Case("all_invalid", invalid, None, 0),
        "all_max_range": Case("all_max_range", at_max, None, 0),
        "straight_wall": Case("straight_wall", wall, zero, 80),
        "circle_R1": Case("circle_R1", circle, lambda idx: np.full(idx.shape, -1.0), 50),
        "right_angle_corner": Case("right_angle_corner", corner, zero, 150),
    }


CATALOGUE = _catalogue()


@pytest.fixture(params=sorted(CATALOGUE))
def case(request: pytest.FixtureRequest) -> Case:
    """Each catalogue scan in turn."""
    return CATALOGUE[request.param]


@pytest.fixture
def raycast() -> object:
    """The analytic ray-cast helpers, for tests that build their own scans."""
    import types

    return types.SimpleNamespace(circle=cast_circle, line=cast_line, scan=make_scan,
                                 bearings=BEARINGS, max_range=MAX_RANGE, catalogue=CATALOGUE)
