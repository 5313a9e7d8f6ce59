"""The whole-scan model's per-tick searches over the scan points (:mod:`atoms.closest`).

Three searches run every tick: the nearest point on the followed side
(:func:`nearest_right`, over the squared ranges of :func:`squared_ranges`), the points
around it (:func:`within`) and the next face's nearest point (:func:`next_face`). In
numpy they take some thirty calls on arrays of a few dozen to a few hundred points, and
numpy's fixed cost per call is most of it; where the install
built ``atoms/_searches.c`` (an optional build, like the simulator's loops) each runs as
one compiled call instead. Each has its numpy path beside it, ``*_numpy``: the reference,
and what runs without the build or whenever the compiled search cannot be sure of numpy's
answer (:data:`AMBIGUOUS`). The answers are the same either way, so a seeded run gives the
same numbers on any install (``tests/atoms/test_atoms_searches.py``).

The compiled searches only compare numbers that numpy computes the same way (differences
of two doubles, the squared ranges given). A distance compared with a limit is numpy's
modulus (its own vectorised algorithm, within an ulp or so of the exact value) there and a
squared distance here: when the squared distance lies within 1e-12 of the squared limit,
or a NaN appears, or an array comes in another form (strided, another dtype), the compiled
search answers :data:`AMBIGUOUS` and numpy decides.

Points are complex ``x + iy`` in the law's frame (:mod:`atoms.closest`).

>>> import numpy as np
>>> z = np.array([1.0 - 0.5j, 0.5 - 0.5j, 0.6 + 0.1j])
>>> d2 = (z * z.conjugate()).real
>>> nearest_right(z, d2), within(z, 0.5 - 0.5j, 0.6).tolist()
(1, [True, True, False])
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np

__all__ = ["squared_ranges", "nearest_right", "within", "next_face", "squared_ranges_numpy",
           "nearest_right_numpy", "within_numpy", "next_face_numpy", "AMBIGUOUS", "COMPILED"]

#: What a compiled search answers when numpy's comparison could go the other way (or for an
#: array in another form than it reads): the numpy path decides.
AMBIGUOUS = -2


def _compiled_searches() -> Any:
    """Return the compiled searches (atoms/_searches.c), or None where they were not built."""
    try:
        import mdle.atoms._searches as compiled
    except ImportError:
        return None
    return compiled


#: The compiled searches (None: the numpy paths only).
_COMPILED = _compiled_searches()
#: Whether this install runs the compiled searches.
COMPILED = _COMPILED is not None


def squared_ranges(z: "np.ndarray") -> "np.ndarray":
    """Return the points' squared ranges ``x x + y y`` (float, (M,)).

    Each a rounded product plus a rounded product, rounded: the same numbers as
    :func:`squared_ranges_numpy`, in one call instead of five.
    """
    if _COMPILED is not None:
        import numpy as np

        d2 = np.empty(z.shape[0])
        if _COMPILED.squared_ranges(z, d2) != AMBIGUOUS:
            return d2
    return squared_ranges_numpy(z)


def squared_ranges_numpy(z: "np.ndarray") -> "np.ndarray":
    """Return :func:`squared_ranges` with numpy (the reference of the compiled loop)."""
    x, y = z.real, z.imag
    d2: np.ndarray = x * x  # full-length operations (a reduction over a short axis is slow)
    d2 += y * y
    return d2


def nearest_right(z: "np.ndarray", d2: "np.ndarray") -> int:
    """Return the index of the nearest point with ``y < 0`` (the followed side); -1 for none.

    ``d2``: the points' squared ranges. The first of equals, as ``argmin`` gives it.
    """
    if _COMPILED is not None:
        k: int = _COMPILED.nearest_right(z, d2)
        if k != AMBIGUOUS:
            return k
    return nearest_right_numpy(z, d2)


def nearest_right_numpy(z: "np.ndarray", d2: "np.ndarray") -> int:
    """Return :func:`nearest_right` with numpy (the reference of the compiled search)."""
    import numpy as np

    right = np.where(z.imag < 0.0, d2, math.inf)
    k = int(right.argmin())
    return k if float(right[k]) < math.inf else -1


def within(z: "np.ndarray", q: complex, radius: float) -> "np.ndarray":
    """Return the mask of the points less than ``radius`` from ``q``: ``abs(z - q) < radius``."""
    if _COMPILED is not None:
        import numpy as np

        sel = np.empty(z.shape[0], dtype=bool)
        if _COMPILED.within(z, q, radius, sel) != AMBIGUOUS:
            return sel
    return within_numpy(z, q, radius)


def within_numpy(z: "np.ndarray", q: complex, radius: float) -> "np.ndarray":
    """Return :func:`within` with numpy (the reference of the compiled search)."""
    mask: np.ndarray = abs(z - q) < radius
    return mask


def next_face(z: "np.ndarray", d2: "np.ndarray", fitted: "np.ndarray", window: int,
              jump: float) -> int:
    """Return the index of the next face's nearest point; -1 for none.

    :func:`atoms.closest.next_nearest` says what that point is; :func:`next_face_numpy`
    computes it in numpy.
    """
    if _COMPILED is not None:
        k: int = _COMPILED.next_face(z, d2, fitted, window, jump)
        if k != AMBIGUOUS:
            return k
    return next_face_numpy(z, d2, fitted, window, jump)


def next_face_numpy(z: "np.ndarray", d2: "np.ndarray", fitted: "np.ndarray", window: int,
                    jump: float) -> int:
    """Return :func:`next_face` with numpy (the reference of the compiled search).

    A point qualifies when its squared range ``d2`` is the least of the ``window`` points
    on either side of it, or when it lies on another surface than the first ``fitted``
    point (surfaces: runs of points less than ``jump`` apart); and it is not ``fitted`` and
    lies less than 45 deg left of the heading. The nearest that qualifies (the first of
    equals) counts if its squared range is positive and finite.
    """
    import numpy as np

    m = z.shape[0]
    w = int(window)
    if m == 0:
        return -1
    pad = np.full(m + 2 * w, math.inf)
    pad[w:w + m] = d2
    # the least of 2 w + 1 neighbours by doubling (w = 10: windows of 2, 4, 8, 16, then 21)
    low, span = pad, 1
    while 2 * span <= 2 * w + 1:
        low = np.minimum(low[:-span], low[span:])
        span *= 2
    rest = 2 * w + 1 - span
    if rest:
        low = np.minimum(low[:-rest], low[rest:])
    ok = d2 <= low
    # points of other surfaces (beyond a depth jump) count too: in the list of valid points
    # a surface's neighbours across a gap in the scan can hide its local minimum. The
    # surface of the face followed runs between the jumps on either side of its first
    # fitted point (found in the jumps' bytes: a cumulative sum of them costs more)
    f = int(fitted.argmax())
    cut = (abs(z[1:] - z[:-1]) > jump).tobytes()  # cut[i]: a jump between points i, i + 1
    hi = cut.find(1, f)
    ok[:cut.rfind(1, 0, f) + 1] = True
    if hi >= 0:
        ok[hi + 1:] = True
    ok &= z.imag < z.real  # less than 45 deg left of the heading
    ok = np.greater(ok, fitted)  # and not the face followed (ok and not fitted)
    k = int(np.where(ok, d2, math.inf).argmin())
    r2 = float(d2[k])
    return k if ok[k] and 0.0 < r2 < math.inf else -1
