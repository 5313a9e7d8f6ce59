"""The two rays' estimates from a few of a scan's points: the side ray's fit, the front ray's.

:func:`side_ray` fits a quadratic to the first surface's points from -90 deg on;
:func:`front_ray` averages the geometric estimate over a few windows at the 0 deg beam. Both
read points as complex ``x + iy`` in the law's frame (see :mod:`atoms.boundary`, which picks
the beams) and return a :class:`atoms.steering.Ray`. numpy is imported on first use.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from mdle.atoms.steering import MISS, Ray

if TYPE_CHECKING:
    import numpy as np

__all__ = ["side_ray", "front_ray"]

def side_ray(z: "np.ndarray", r0: float) -> "Ray":
    """Fit the side ray to the first surface's beams 0..n (beam 0 at -90 deg), all valid.

    ``z`` holds their points as complex ``x + iy`` in the law frame.

    A quadratic ``h = a + b s + c s^2`` is fitted by least squares in the frame of the
    total-least-squares line through the points (centred), and its slope and curvature are
    taken at the hit point, beam 0. Windows of three points (the paper's one-sided
    ``(P0, Pw, P2w)``) are far noisier at the side ray: at 0.5 m with 0.8 % range noise they
    give a curvature std of about 1.3 1/m and a tangent std of 6 deg; the fit over
    ``span = 30`` beams (about 0.27 m of wall) gives 0.22 1/m and 1.9 deg.

    Both fits are closed-form moments (no SVD), about ten numpy calls: the line's direction
    is half the angle of ``sum(q^2)`` (``q`` the centred points as complex numbers,
    ``sum(q^2) = sxx - syy + 2i sxy``). In that frame ``sum s = sum h = sum s h = 0`` (centred,
    principal axes), so the quadratic's normal equations need only ``sum s^2`` (from
    ``sum |q|^2`` and ``|sum q^2|``), ``sum s^3 + i sum s^2 h`` (one dot product of ``s^2``
    with the complex ``s + i h``) and ``sum s^4``; Cramer's rule on them is two lines. When
    they are singular (fewer than three distinct abscissae) the minimum-norm solution of
    :func:`_side_fit_lstsq`.
    """
    import numpy as np

    m = z.size
    if m < 5:
        return MISS
    total = complex(np.add.reduce(z))
    inv = 1.0 / m  # the mean as numpy's complex division by m computes it
    q = z - complex(total.real * inv, total.imag * inv)
    sq = complex(np.dot(q, q))  # unconjugated: sxx - syy + 2i sxy
    if not (math.isfinite(sq.real) and math.isfinite(sq.imag)):
        return MISS
    ang = 0.5 * math.atan2(sq.imag, sq.real)
    w = q * complex(math.cos(ang), -math.sin(ang))  # s + i h in the line's frame
    first, last = w[::m - 1].tolist()
    s = w.real
    t = s * s  # (a product: pow is many times slower per element)
    s3b2 = complex(np.dot(t, w))  # sum s^3 + i sum s^2 h
    s4 = float(np.dot(t, t))
    s2 = 0.5 * (float(np.vdot(q, q).real) + abs(sq))  # sum s^2 (sum s^2 - sum h^2 = |sq|)
    s0, s3, b2 = first.real, s3b2.real, s3b2.imag
    if last.real < s0:  # orient the line first -> last point: s and h change sign
        ang += math.pi
        s0, s3, b2 = -s0, -s3, -b2
    ang = math.atan2(math.sin(ang), math.cos(ang))
    if not s2 > 0:
        return MISS
    # Cramer's rule on [[m 0 s2] [0 s2 s3] [s2 s3 s4]] (a b c) = (0 0 b2)
    det = m * (s2 * s4 - s3 * s3) - s2 * s2 * s2
    if abs(det) > 1e-12 * m * s2 * s4:
        c2 = m * s2 * b2 / det
        slope = 2.0 * c2 * s0 - m * s3 * b2 / det
        kappa = 2.0 * c2 / (1.0 + slope * slope) ** 1.5
    else:
        slope, kappa = _side_fit_lstsq(q, ang)
    return Ray(True, r0, ang + math.atan(slope), float(kappa))


def _side_fit_lstsq(q: "np.ndarray", ang: float) -> tuple[float, float]:
    """Return the side fit's slope and curvature at ``q[0]`` from ``lstsq`` (singular case).

    The quadratic in the line's frame (direction ``ang``) over abscissae scaled by their
    span: with fewer than three distinct abscissae the minimum-norm solution in that basis.
    """
    import numpy as np

    w = q * complex(math.cos(ang), -math.sin(ang))
    s, h = w.real, w.imag
    scale = float(np.maximum.reduce(np.abs(s)))
    x = np.empty((3, q.size))
    x[0] = 1.0
    np.divide(s, scale, out=x[1])
    np.multiply(x[1], x[1], out=x[2])
    coef = np.linalg.lstsq(x.T, h, rcond=None)[0]
    c1, c2 = float(coef[1]), float(coef[2])
    slope = (c1 + 2.0 * c2 * float(x[1, 0])) / scale
    return slope, 2.0 * c2 / scale ** 2 / (1.0 + slope * slope) ** 1.5


def front_ray(z: "np.ndarray", c: int, right: int, left: int, r0: float,
               windows: tuple[int, ...], exact: bool = False) -> "Ray | None":
    """Compute the front ray at beam ``c`` of the points ``z`` (complex, law frame).

    Its surface extends ``right`` beams before and ``left`` beams after it.

    The averaged geometric estimate over the windows that fit (curvature of each window's
    circle and its tangent at the middle point, as :func:`atoms.estimators.geometric_curvature`
    computes them for the whole scan).
    ``right`` and ``left`` may be capped at ``max(windows)`` (all the estimate reads) unless
    ``exact``; None when no window gives an estimate and the one-sided chord needs the
    surface's true extent on both sides (only for degenerate, coincident points).
    """
    import numpy as np

    reach = min(right, left)
    ws = [w for w in windows if w <= reach] or ([reach] if reach >= 1 else [])
    if ws:
        # at most a few windows at one beam: Python float arithmetic (which the interpreter
        # runs fastest), where numpy's per-call overhead on 3-element arrays would cost
        # several times more; the same operations as complex numbers, in the same order
        mid = max(ws)
        f = z[c - mid: c + mid + 1].view(np.float64).tolist()  # x0, y0, x1, y1, ...
        px, py = f[2 * mid], f[2 * mid + 1]
        tx = ty = k_sum = 0.0
        count = 0
        for w in ws:
            i, j = 2 * (mid - w), 2 * (mid + w)
            ux, uy = px - f[i], py - f[i + 1]  # u = p - P[c-w]
            vx, vy = f[j] - px, f[j + 1] - py  # v = P[c+w] - p
            cx, cy = ux + vx, uy + vy  # the chord u + v
            av_c = math.hypot(vx, vy) * math.hypot(cx, cy)
            den = math.hypot(ux, uy) * av_c
            if not den > 0:  # coincident points: no circle
                continue
            cross = ux * vy - uy * vx
            dot = abs(cx * vx + cy * vy)
            # the circle's tangent at p: u turned by half the arc it spans (see estimators)
            tx += (ux * dot - uy * cross) / av_c
            ty += (ux * cross + uy * dot) / av_c
            k_sum += 2.0 * cross / den
            count += 1
        if count:
            return Ray(True, r0, math.atan2(ty, tx), k_sum / count)
    m = min(max(right, left), max(windows))
    if m >= 1:
        if not exact and min(left, right) >= max(windows):
            return None  # both capped: the side with the longer surface is not known here
        chord = complex(z[c + m] - z[c] if left >= right else z[c] - z[c - m])
        return Ray(True, r0, math.atan2(chord.imag, chord.real), 0.0)
    return Ray(True, r0, math.pi / 2.0, 0.0)  # an isolated return: a surface facing the robot
