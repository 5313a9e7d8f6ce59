"""A ladar's noise, quantum and clipping in C (sim/_kernels.c, ``settle``) give numpy's numbers.

Side by side with the numpy reference (``_Settling.settle_numpy``) on every noise model
and on awkward ranges (signed zeros, quanta's halfway points, NaN, infinities, beyond
the range), for one scan and a team's block of rows.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdle.sim import ladar
from mdle.sim.ladar import LMS200, _Settling

needs_settle = pytest.mark.skipif(ladar._SETTLE is None,
                                  reason="this install has no compiled settling")


def _ranges(rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
    r = rng.uniform(-1.0, 12.0, shape)
    flat = r.reshape(-1)
    odd = [0.0, -0.0, math.nan, math.inf, -math.inf, 8.0, 8.0005, 0.0005, 2.0015, 1e-300,
           1e300, 7.9995]
    flat[::7] = np.round(flat[::7], 3) + 0.0005          # halfway to a quantum
    at = rng.choice(flat.shape[0], min(flat.shape[0], len(odd)), replace=False)
    flat[at] = rng.choice(odd, at.shape[0], replace=False)
    return r


@needs_settle
@pytest.mark.parametrize("noise, sigma, resolution", [
    ("relative", 0.008, 0.001), ("absolute", 0.03, 0.01), ("relative", 0.01, 0.0),
    ("none", 0.0, 0.001), ("none", 0.0, 0.0), ("absolute", 1e300, 0.5)])
@pytest.mark.parametrize("shape", [(181,), (1,), (7, 361)])
def test_compiled_and_numpy_settling_are_equal_bit_for_bit(
        noise: str, sigma: float, resolution: float, shape: tuple[int, ...]) -> None:
    how = _Settling.of(LMS200.with_overrides(noise=noise, sigma=sigma, resolution=resolution))
    rng = np.random.default_rng(len(shape) + int(sigma * 1000))
    for _ in range(60):
        ranges = _ranges(rng, shape)
        valid = rng.random(shape) < 0.7
        draws = rng.standard_normal(shape) if how.noisy else None
        r1, v1 = ranges.copy(), valid.copy()
        r2, v2 = ranges.copy(), valid.copy()
        n1 = None if draws is None else draws.copy()
        n2 = None if draws is None else draws.copy()
        how.settle(r1, v1, n1)
        with np.errstate(invalid="ignore", over="ignore"):     # inf - inf, 1e300 squared
            how.settle_numpy(r2, v2, n2)
        assert r1.tobytes() == r2.tobytes()
        assert n1 is None or n2 is None or n1.tobytes() == n2.tobytes()
        assert not (r1.flags.writeable or v1.flags.writeable)
        assert np.array_equal(v1, valid)


@needs_settle
def test_the_settling_kernel_refuses_arrays_that_do_not_fit() -> None:
    settle = ladar._SETTLE
    assert settle is not None
    r, v, n = np.full(5, 3.0), np.ones(5, bool), np.zeros(5)
    settle(r, v, n, 0.01, True, 0.001, 8.0)
    for args, match in [((r, v[:4], n), "valid"), ((r, v.astype(np.int8), n), "valid"),
                        ((r, v, n[:3]), "noise"), ((r.astype(np.float32), v, n), "ranges")]:
        with pytest.raises(ValueError, match=match):
            settle(*args, 0.01, True, 0.001, 8.0)
    frozen = r.copy()
    frozen.flags.writeable = False
    with pytest.raises((ValueError, BufferError)):
        settle(frozen, v, n, 0.01, True, 0.001, 8.0)
    with pytest.raises(TypeError, match="7 arguments"):
        settle(r, v, n, 0.01, True, 0.001)
