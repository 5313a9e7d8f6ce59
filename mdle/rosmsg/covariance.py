"""The covariances of ``nav_msgs/Odometry``, from the simulator's odometry noise model.

A simulated robot's odometry errs as its profile's ``odometry`` model says (``sim/robot.py``,
``OdometryNoise``): per step, the distance driven with a standard deviation of
``distance * sqrt(ds)``, the heading with ``turn * sqrt(|dtheta|)`` plus
``drift * sqrt(ds)``, each drawn independently and accumulated. So after a path of
length ``S`` with ``A`` radians turned in all:

* the heading's variance is ``var_yaw = turn**2 * A + drift**2 * S`` (exact: a sum of
  independent steps);
* along the path the position's variance is ``distance**2 * S``; across it, a heading
  error that grew as a random walk over a path of length ``S`` moves the end by a
  variance of ``var_yaw * S**2 / 3`` (a straight path's, the usual approximation).

The pose covariance (row-major, x y z roll pitch yaw) carries ``distance**2 * S +
var_yaw * S**2 / 3`` on x and y (the larger of the two directions, as the path's
direction changes), ``var_yaw`` on yaw, and 0 elsewhere: z, roll and pitch are exactly 0
in a planar simulation. The twist (the measured speed and turn rate) is the simulator's
exact motion: covariance 0. With no odometry noise the odometry is exact, and all zeros
are the truth.

A robot whose noise mdle does not know (hardware) gets the convention REP-145 gives
for ``sensor_msgs/Imu``, the only one the ROS message docs state: ``-1`` in a
covariance's first element means "no estimate", so no filter takes the odometry as
exact.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["OdometryCovariance", "UNKNOWN"]

#: A covariance with no estimate (REP-145): -1 in its first element.
UNKNOWN = np.concatenate(([-1.0], np.zeros(35)))


class OdometryCovariance:
    """Per-tick odometry covariances for a run, from its trace header's ``odometry``.

    ``model`` is the header's ``odometry`` mapping (``distance``, ``turn``, ``drift``)
    or None (unknown: :data:`UNKNOWN`). :meth:`batch` takes the ticks in order, a batch
    at a time, and carries the path length and turning from one batch to the next.
    """

    def __init__(self, model: Mapping[str, Any] | None) -> None:
        self.known = isinstance(model, Mapping)
        m = model if isinstance(model, Mapping) else {}
        self.distance = float(m.get("distance", 0.0) or 0.0)
        self.turn = float(m.get("turn", 0.0) or 0.0)
        self.drift = float(m.get("drift", 0.0) or 0.0)
        self.noisy = self.known and (self.distance > 0 or self.turn > 0 or self.drift > 0)
        self._last: tuple[float, float, float] | None = None
        self._path = 0.0
        self._turned = 0.0

    @property
    def constant(self) -> tuple[np.ndarray, np.ndarray]:
        """The covariances when they do not change: exact (zeros) or unknown."""
        if not self.known:
            return UNKNOWN, UNKNOWN
        return np.zeros(36), np.zeros(36)

    def batch(self, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """Return the pose and twist covariances (k x 36 each) of ticks at ``pose``.

        ``pose`` is k x 3 (odometry x, y, theta, in order). None when they are
        :attr:`constant`.
        """
        if not self.noisy or not len(pose):
            return None
        x, y, th = pose[:, 0], pose[:, 1], pose[:, 2]
        last = self._last if self._last is not None else (x[0], y[0], th[0])
        step = np.hypot(np.diff(x, prepend=last[0]), np.diff(y, prepend=last[1]))
        turn = np.abs((np.diff(th, prepend=last[2]) + np.pi) % (2 * np.pi) - np.pi)  # wrapped
        # one sequential sum, however the ticks are batched (the export's batches differ)
        path = np.cumsum(np.concatenate(([self._path], step)))[1:]
        turned = np.cumsum(np.concatenate(([self._turned], turn)))[1:]
        self._last = (float(x[-1]), float(y[-1]), float(th[-1]))
        self._path, self._turned = float(path[-1]), float(turned[-1])
        var_yaw = self.turn ** 2 * turned + self.drift ** 2 * path
        var_xy = self.distance ** 2 * path + var_yaw * path ** 2 / 3.0
        cov = np.zeros((len(pose), 36))
        cov[:, 0] = cov[:, 7] = var_xy
        cov[:, 35] = var_yaw
        return cov, np.zeros((len(pose), 36))
