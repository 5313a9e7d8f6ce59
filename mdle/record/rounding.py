"""Numbers as a trace's reader gets them: rounded to 9 significant digits, for a whole batch.

The trace writes a sample's numbers with ``%.9g``; the live recording publishes them as
a reader of that line would parse them, ``float("%.9g" % x)``, so that a recording and
the export of the run's trace hold the same messages. Formatting and parsing each
number costs two decimal conversions; :func:`round9` gets the same doubles for an array
at once with binary arithmetic, and formats and parses only the numbers where that
arithmetic could be off (a last-place error that could tip a rounding).

Why it is exact: with ``e = floor(log10(|x|))`` and ``k = 8 - e`` (|k| <= 22, so
``10**|k|`` is an exact double), ``y = x * 10**k`` (or ``x / 10**-k``) is the 9-digit
mantissa, off by at most half a unit in its last place (under 1e-7 for ``|y| < 1e9``).
Unless ``y`` lies within 1e-6 of a half-integer, rounding it gives the integer ``n`` of
the correctly rounded 9-digit decimal, and ``n / 10**k`` (or ``n * 10**-k``), one
correctly rounded operation on exact operands, is the double nearest that decimal: what
parsing it gives. A computed ``y`` in [1e8, 1e9) whose exact value is just outside
(``log10`` off near a power of ten) is within that error of the power of ten, where both
choices of ``e`` round to the same number. Where ``y`` is outside [1e8, 1e9), near a
half-integer, or ``|k| > 22``, the number is formatted and parsed.
"""

from __future__ import annotations

import numpy as np

__all__ = ["round9"]

_K = np.arange(-22, 23)
# y = x * _MUL[k] / _DIV[k]: one of the two is 1, the other 10**|k| (an exact double)
_MUL = np.where(_K >= 0, 10.0 ** np.abs(_K), 1.0)
_DIV = np.where(_K < 0, 10.0 ** np.abs(_K), 1.0)


def round9(values: np.ndarray) -> np.ndarray:
    """Return ``float("%.9g" % x)`` of each element (a non-finite one: NaN), as float64."""
    v = np.asarray(values, dtype=np.float64)
    x = v.ravel()
    with np.errstate(all="ignore"):  # 0, inf and NaN give inf and NaN on the way
        k = 8.0 - np.floor(np.log10(np.abs(x)))
        usable = np.abs(k) <= 22.0
        at = np.where(usable, k, 0.0).astype(np.int64) + 22
        mul, div = _MUL[at], _DIV[at]
        y = x * mul / div
        n = np.rint(y)
        out = n / mul * div
        ay = np.abs(y)
        usable &= (ay >= 1e8) & (ay < 1e9) & (np.abs(y - n) < 0.5 - 1e-6)
    finite = np.isfinite(x)
    out[~finite] = np.nan
    zero = x == 0.0
    out[zero] = x[zero]  # 0 and -0 as they are
    for i in np.flatnonzero(~usable & finite & ~zero).tolist():
        out[i] = float("%.9g" % x[i])
    return out.reshape(v.shape)
