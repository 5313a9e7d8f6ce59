"""A scan's points in C (atoms/_points.c, for ``estimators.beam_points``) are numpy's, bit for bit.

Side by side with the numpy reference (``estimators._points_numpy``) on random scans and on
awkward ranges, with and without a valid mask; the arrays the compiled loop does not
read go to numpy; the import-time check tells the two roundings of a complex product
apart.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdle.atoms import estimators
from mdle.atoms.estimators import beam_points

needs_points = pytest.mark.skipif(estimators._POINTS is None,
                                  reason="this install has no compiled scan points")

_ODD = [0.0, -0.0, 5e-324, 1e-320, 2.2e-308, 1e-300, math.nan, math.inf, -math.inf, -1.0,
        1.0, 3.7, 9.999, 10.0, 1e300]


def _bits(out: tuple[np.ndarray, ...]) -> tuple[bytes, ...]:
    return tuple(a.tobytes() for a in out)


def test_an_install_built_with_a_c_compiler_has_the_compiled_points() -> None:
    from importlib.util import find_spec

    # the build is optional; where it happened, the import-time check must accept it
    if find_spec("mdle.atoms._points") is not None:
        assert estimators._POINTS is not None


@needs_points
@pytest.mark.parametrize("beams, fov", [(181, math.pi), (361, math.pi), (1, 0.0),
                                        (720, 2 * math.pi - 0.01), (7, 1.0)])
def test_compiled_and_numpy_points_are_equal_bit_for_bit(beams: int, fov: float) -> None:
    rng = np.random.default_rng(beams)
    bearings = np.linspace(-fov / 2, fov / 2, beams)
    for k in range(200):
        ranges = rng.uniform(-0.5, 10.5, beams)
        ranges[rng.random(beams) < 0.2] = 10.0
        at = rng.random(beams) < 0.1
        ranges[at] = rng.choice(_ODD, int(at.sum()))
        valid = rng.random(beams) < 0.8 if k % 2 else None
        got = beam_points(ranges, bearings, valid)
        want = estimators._points_numpy(ranges, bearings, valid)
        assert _bits(got) == _bits(want)


@needs_points
def test_arrays_the_compiled_loop_does_not_read_go_to_numpy() -> None:
    bearings = np.linspace(-1.0, 1.0, 11)
    ranges = np.linspace(0.5, 5.0, 22)[::2]                   # strided
    want = estimators._points_numpy(np.ascontiguousarray(ranges), bearings, None)
    assert _bits(beam_points(ranges, bearings)) == _bits(want)
    assert _bits(beam_points(ranges.tolist(), bearings)) == _bits(want)   # not an array
    mask = np.arange(11) % 2                                  # ints, not bools
    assert _bits(beam_points(ranges, bearings, mask)) == _bits(
        estimators._points_numpy(np.ascontiguousarray(ranges), bearings, mask.astype(bool)))
    with pytest.raises(ValueError):                           # numpy says what does not fit
        beam_points(np.ones(5), bearings)


@needs_points
def test_the_import_check_tells_the_roundings_apart() -> None:
    compiled = estimators._POINTS
    assert compiled is not None
    ranges, bearings, _ = estimators._probe_scan()
    unit = estimators._terms_of(bearings, estimators.DEFAULT_GAP_FACTOR)[0]
    want = estimators._points_numpy(ranges, bearings, None)
    ours = estimators._points_compiled(compiled.kernel, compiled.fused, ranges, unit, None)
    other = estimators._points_compiled(compiled.kernel, not compiled.fused, ranges, unit,
                                        None)
    assert _bits(ours) == _bits(want) and _bits(other) != _bits(want)


@needs_points
def test_the_points_kernel_refuses_arrays_that_do_not_fit() -> None:
    compiled = estimators._POINTS
    assert compiled is not None
    kernel = compiled.kernel
    n = 5
    r, unit = np.ones(n), np.ones(n, dtype=complex)
    outs = [np.empty(n, dtype=complex), np.empty(n, dtype=bool), np.empty(n)]
    kernel(r, unit, None, *outs, True)
    assert outs[1].all() and (outs[0] == 1.0).all()
    for i, bad, match in [(1, np.ones(n), "unit"), (2, np.ones(4, dtype=bool), "valid"),
                          (3, np.empty(n), "z"), (5, np.empty(n - 1), "r")]:
        args = [r, unit, None, *outs]
        args[i] = bad
        with pytest.raises(ValueError, match=match):
            kernel(*args, True)
    with pytest.raises(TypeError, match="7 arguments"):
        kernel(r, unit, None, *outs)
