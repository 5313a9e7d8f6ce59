"""Engagement metrics of a boundary-following run, from the simulator's ground truth.

Given the true pose at every tick and the nearest obstacle boundary point to it, a run is
**engaged** once, for :data:`ENGAGE_PATH` (4 m) of path without a break, the true distance
``d`` from the robot's centre to the nearest boundary stays within :data:`ENGAGE_BAND`
(0.2 m) of ``rc`` *and* that nearest point lies on the followed side (negative robot-frame
``y`` for right-hand following, positive for left). The engagement instant is the first tick
of the first such stretch.

The accuracy of an engaged run is measured over the **second half of the time after
engagement**: the ticks with ``t >= t_e + (T - t_e) / 2``, ``t_e`` the engagement instant and
``T`` the last tick. There ``mean_err`` and ``max_err`` are the mean and max of
``|d - rc|``. A run that never engaged has NaN there.

>>> import numpy as np
>>> t = np.arange(0.0, 10.01, 0.1)                    # along a wall y = 0 at 1 m/s, 0.5 m above
>>> m = follow_metrics(t, t, np.full_like(t, 0.5), np.zeros_like(t), np.full_like(t, 0.5),
...                    np.column_stack([t, np.zeros_like(t)]), np.full_like(t, 0.5),
...                    collided=False, side="right", rc=0.5)
>>> m.engaged, round(m.t_engage, 3), round(m.mean_err, 3), round(m.window_start, 3)
(True, 0.0, 0.0, 5.0)
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["ENGAGE_BAND", "ENGAGE_PATH", "FollowMetrics", "follow_metrics"]

#: Largest |d - rc| that counts as following, metres.
ENGAGE_BAND = 0.2
#: Path length that must be followed without a break to count as engaged, metres.
ENGAGE_PATH = 4.0


@dataclass(frozen=True)
class FollowMetrics:
    """What one run did (metres, seconds).

    Attributes
    ----------
    collided : bool
        The body touched an obstacle.
    min_clearance : float
        Smallest true body clearance over the run.
    engaged : bool
        See the module docstring.
    t_engage, s_engage : float
        Time and path length from the start to the engagement instant (NaN if never).
    mean_err, max_err : float
        Mean and max of ``|d - rc|`` over the second half of the time after engagement.
    window_start : float
        Where that window starts, seconds (NaN if never engaged).
    path_length : float
        Total path of the run.
    min_d, final_d : float
        Smallest and last true centre-to-boundary distance.
    blind_path : float
        Path driven with the nearest boundary on the non-followed side within ``3 rc``:
        sliding along a face with the obstacle on the wrong side.
    """

    collided: bool
    min_clearance: float
    engaged: bool
    t_engage: float
    s_engage: float
    mean_err: float
    max_err: float
    window_start: float
    path_length: float
    min_d: float
    final_d: float
    blind_path: float

    def as_dict(self) -> dict[str, float | bool]:
        """Return the fields as a plain dict."""
        return asdict(self)


def follow_metrics(t: np.ndarray, x: np.ndarray, y: np.ndarray, theta: np.ndarray,
                   d: np.ndarray, nearest: np.ndarray, clearance: np.ndarray, *,
                   collided: bool, side: str, rc: float, band: float = ENGAGE_BAND,
                   path: float = ENGAGE_PATH) -> FollowMetrics:
    """Measure one run from its true trace.

    Parameters
    ----------
    t, x, y, theta : (N,) arrays
        Tick times (s) and true poses (m, rad).
    d : (N,) array
        True distance from the robot's centre to the nearest obstacle boundary (m).
    nearest : (N, 2) array
        That nearest boundary point (world frame, m).
    clearance : (N,) array
        True body clearance (m).
    collided : bool
        Whether the body touched an obstacle.
    side : {"right", "left"}
        The followed side.
    rc : float
        The following distance (m).
    band, path : float
        Engagement band (m) and the path (m) it must hold for.

    Returns
    -------
    FollowMetrics
    """
    if side not in ("right", "left"):
        raise ValueError(f"side must be `right` or `left`, got `{side}`")
    t, x, y, theta, d = (np.asarray(a, dtype=float) for a in (t, x, y, theta, d))
    nearest = np.asarray(nearest, dtype=float).reshape(-1, 2)
    # Robot-frame y of the nearest boundary point: negative means on the robot's right.
    lateral = (-np.sin(theta) * (nearest[:, 0] - x) + np.cos(theta) * (nearest[:, 1] - y))
    followed = lateral < 0 if side == "right" else lateral > 0
    step = np.hypot(np.diff(x), np.diff(y))
    s = np.concatenate([[0.0], np.cumsum(step)])
    err = np.abs(d - rc)
    good = (err <= band) & followed & np.isfinite(d)
    start = _first_stretch(good, s, path)
    blind = (~followed) & (d <= 3.0 * rc)
    blind_path = float(np.sum(step[blind[:-1] & blind[1:]])) if len(step) else 0.0
    t_e = w0 = mean_err = max_err = s_e = math.nan
    if start is not None:
        t_e, s_e = float(t[start]), float(s[start])
        w0 = t_e + 0.5 * (float(t[-1]) - t_e)
        win = err[t >= w0]
        mean_err, max_err = float(win.mean()), float(win.max())
    return FollowMetrics(collided=bool(collided), min_clearance=float(np.min(clearance)),
                         engaged=start is not None, t_engage=t_e, s_engage=s_e,
                         mean_err=mean_err, max_err=max_err, window_start=w0,
                         path_length=float(s[-1]), min_d=float(np.min(d)),
                         final_d=float(d[-1]), blind_path=blind_path)


def _first_stretch(good: np.ndarray, s: np.ndarray, path: float) -> int | None:
    """Return the first index of the first unbroken run of ``good`` covering ``path`` of ``s``."""
    if not good.any():
        return None
    edges = np.diff(np.concatenate([[0], good.astype(np.int8), [0]]))
    begins = np.flatnonzero(edges == 1)
    ends = np.flatnonzero(edges == -1) - 1       # inclusive
    long_enough = np.flatnonzero(s[ends] - s[begins] >= path - 1e-9)
    return int(begins[long_enough[0]]) if len(long_enough) else None
