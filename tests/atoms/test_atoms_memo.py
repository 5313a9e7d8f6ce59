"""What is memoised from a sensor's fixed bearings is found by identity, and never goes stale."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from mdle.atoms.boundary import boundary_view
from mdle.atoms.estimators import scan_points, valid_points
from mdle.atoms.memo import ByIdentity
from mdle.core.backend import Scan

if TYPE_CHECKING:
    from tests.atoms.conftest import Raycast


def _counting() -> tuple[ByIdentity[float], list[int]]:
    calls: list[int] = []

    def fn(a: np.ndarray, k: int) -> float:
        calls.append(k)
        return float(np.sum(a)) * k

    return ByIdentity(fn, size=2), calls


def _fixed(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


def test_a_fixed_array_is_found_again_without_calling() -> None:
    memo, calls = _counting()
    b = _fixed(np.arange(4.0))
    assert [memo(b, 2), memo(b, 2), memo(b, 3)] == [12.0, 12.0, 18.0]
    assert calls == [2, 3]  # once per extra key
    assert memo(_fixed(np.arange(4.0)), 2) == 12.0 and calls == [2, 3, 2]  # another object


def test_arrays_that_may_change_are_computed_every_time() -> None:
    memo, calls = _counting()
    w = np.arange(4.0)
    base = np.arange(4.0)
    view = base[:]
    view.setflags(write=False)  # read-only, but its base is still writable
    for a in (w, view, [0.0, 1.0, 2.0, 3.0]):
        memo(a, 1)
        memo(a, 1)
    assert len(calls) == 6
    base[0] = 10.0
    assert memo(view, 1) == 16.0


def test_an_array_made_writable_again_is_not_trusted() -> None:
    memo, calls = _counting()
    b = np.arange(4.0)
    b.setflags(write=False)
    memo(b, 1)
    b.setflags(write=True)
    b[0] = 10.0
    assert memo(b, 1) == 16.0 and len(calls) == 2


def test_the_memo_is_bounded() -> None:
    memo, calls = _counting()
    arrays = [_fixed(np.full(3, float(i))) for i in range(5)]
    for a in arrays:
        memo(a, 1)
    assert len(memo._seen) <= 2
    assert memo(arrays[-1], 1) == 12.0 and len(calls) == 5  # the newest is still there


def test_boundary_view_follows_bearings_changed_in_place(raycast: Raycast) -> None:
    # a driver that reuses one writable bearing buffer: the view must read the new bearings
    wall = raycast.line((0.0, -0.5), (0.0, -1.0))
    shifted = raycast.line((0.0, -0.5), (0.0, -1.0), raycast.bearings + math.radians(2.0))
    b = raycast.bearings.copy()
    first = boundary_view(raycast.scan(wall, b), "right")
    b += math.radians(2.0)  # now no beam at -90 deg: no side ray
    second = boundary_view(raycast.scan(shifted, b), "right")
    assert first.side.hit and not second.side.hit
    fixed = _fixed(b)
    assert boundary_view(raycast.scan(shifted, fixed), "right") == second
    assert boundary_view(raycast.scan(shifted, fixed), "right") == second  # found again


def test_boundary_view_is_the_same_whichever_way_the_layout_is_found(raycast: Raycast) -> None:
    for case in raycast.catalogue.values():
        s = case.scan
        fixed = Scan(s.ranges, _fixed(s.bearings), s.valid, s.stamp, s.max_range)
        for side in ("right", "left"):
            assert boundary_view(fixed, side) == boundary_view(s, side)
            assert boundary_view(fixed, side) == boundary_view(s, side, windows=[7, 8, 9])


def test_valid_points_are_the_finite_rows_of_scan_points() -> None:
    b = _fixed(np.radians(np.arange(-90.0, 90.5, 1.0)))
    rng = np.random.default_rng(3)
    r = rng.uniform(0.1, 8.0, b.size)
    r[[0, 5, 90]] = [np.inf, -1.0, np.nan]
    valid = rng.random(b.size) > 0.2
    for v in (None, valid):
        p = scan_points(r, b, v)
        expect = p[np.isfinite(p[:, 0])]
        got = valid_points(r, b, v)
        assert got.shape == expect.shape and np.array_equal(got, expect)
        assert np.array_equal(valid_points(r, np.array(b), v), expect)  # writable bearings


def test_an_array_written_behind_its_flag_is_computed_again() -> None:
    # the owner may make a read-only array writable, write and make it read-only again:
    # the flag is the same before and after, the contents are not
    memo, calls = _counting()
    b = _fixed(np.arange(4.0))
    assert memo(b, 1) == 6.0
    b.setflags(write=True)
    b[0] = 10.0
    b.setflags(write=False)
    assert memo(b, 1) == 16.0 and len(calls) == 2
    assert memo(b, 1) == 16.0 and len(calls) == 2  # and remembered again as it is now


def test_an_array_reshaped_in_place_is_computed_again() -> None:
    memo = ByIdentity(lambda a: a.shape)
    b = _fixed(np.arange(4.0))
    assert memo(b) == (4,)
    b.shape = (2, 2)  # same bytes, same flag, another array to any function of it
    assert memo(b) == (2, 2)
