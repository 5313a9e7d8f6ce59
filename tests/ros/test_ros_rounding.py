"""round9 gives exactly what parsing the trace's ``%.9g`` digits gives, for any double."""

from __future__ import annotations

import math

import numpy as np

from mdle.record.rounding import round9


def _parsed(x: np.ndarray) -> np.ndarray:
    return np.array([float("%.9g" % v) if math.isfinite(v) else math.nan for v in x])


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    both_nan = np.isnan(a) & np.isnan(b)
    return bool(np.all(((a == b) & (np.signbit(a) == np.signbit(b))) | both_nan))


def test_random_doubles_of_every_magnitude() -> None:
    rng = np.random.default_rng(7)
    for x in (rng.uniform(-10, 10, 50_000),
              rng.standard_normal(50_000) * 10.0 ** rng.integers(-30, 30, 50_000),
              np.frombuffer(rng.bytes(8 * 50_000), np.float64),  # any bit pattern
              rng.uniform(-1, 1, 20_000).round(3)):
        assert _same(round9(x), _parsed(x))


def test_hard_cases() -> None:
    """Powers of ten and their neighbours (log10 off by one), exact and near ties, zeros
    with their sign, subnormals, the largest doubles, non-finite numbers."""
    p = 10.0 ** np.arange(-25, 25)
    rng = np.random.default_rng(8)
    ties = (rng.integers(100_000_000, 999_999_999, 5_000) + 0.5) * 10.0 ** rng.integers(
        -12, 12, 5_000)
    x = np.concatenate([p, np.nextafter(p, 0), np.nextafter(p, np.inf), -p, 0.5 * p, ties,
                        np.nextafter(ties, 0), np.nextafter(ties, np.inf),
                        [0.0, -0.0, 123456788.5, 0.5, 2.5, 5e-324, -1.7e308, np.inf,
                         -np.inf, np.nan, 999_999_999.6, 9.9999999996]])
    assert _same(round9(x), _parsed(x))


def test_shape_is_kept() -> None:
    x = np.arange(12.0).reshape(3, 4) / 7
    assert round9(x).shape == (3, 4)
    assert _same(round9(x).ravel(), _parsed(x.ravel()))
