"""The SICK LMS-200 ladar model: beams, range limit, noise, resolution, rate, oracle mode.

A :class:`LadarProfile` is plain data; a :class:`Ladar` owns the random generator and
the preallocated noise buffer and turns ray-cast ground truth into a
:class:`mdle.core.backend.Scan`. Beams: ``beams`` bearings evenly over ``fov``, index 0 at
``-fov/2`` (the robot's right), counter-clockwise. A beam that sees nothing within
``max_range`` is flagged invalid and reported at ``max_range``.

Noise models (``noise``):

* ``relative`` (default, sigma 0.008): Gaussian error with standard deviation
  ``sigma * range``, the paper's "relative range error typically below 0.8 %";
* ``absolute``: Gaussian error with standard deviation ``sigma`` metres (the
  LMS-200 data sheet quotes a statistical error of about 5 mm, 1 sigma, in mm mode);
* ``none``: exact ranges.

Noisy ranges are then rounded to ``resolution`` (the LMS-200 mm mode: 1 mm) and
clipped to ``[0, max_range]``.

>>> p = LADAR_PROFILES["lms200"]
>>> b = p.bearings()
>>> len(b), round(math.degrees(b[0]), 9), round(math.degrees(b[90]), 9)
(181, -90.0, 0.0)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from mdle.core.backend import Scan, plain_scan
from mdle.core.errors import WorldError
from mdle.sim.raycast import MAX_RANGE_SLACK, FanCaster, RayCaster, RayHits

__all__ = ["LADAR_PROFILES", "NOISE_MODELS", "Ladar", "LadarProfile", "ladar_profile",
           "settle_rows"]

NOISE_MODELS = ("relative", "absolute", "none")


def _compiled_settle() -> Callable[..., None] | None:
    """Return the scans' noise, quantum and clipping in C (sim/_kernels.c), or None.

    An optional build; without it numpy settles the scans, with the same numbers (only
    products, sums, quotients, rounding to even and comparisons, each rounded once).
    """
    try:
        from mdle.sim._kernels import settle
    except ImportError:
        return None
    return settle


_SETTLE = _compiled_settle()


@dataclass(frozen=True)
class LadarProfile:
    """A planar ladar (SI units).

    Attributes
    ----------
    name : str
    beams : int
    fov : float, radians
        Angle from the first beam to the last.
    max_range : float, metres
    noise : str
        One of :data:`NOISE_MODELS`.
    sigma : float
        Relative (fraction of the range) or absolute (metres), per ``noise``.
    resolution : float, metres
        Range quantum (0: none).
    rate : float, Hz
        Scans per second; 0 means a fresh scan at every observation.
    source : str
        Where the numbers come from.
    """

    name: str
    beams: int = 181
    fov: float = math.pi
    max_range: float = 10.0
    noise: str = "relative"
    sigma: float = 0.008
    resolution: float = 0.001
    rate: float = 10.0
    source: str = ""

    def bearings(self) -> np.ndarray:
        """Return the (beams,) bearings in the ladar frame, radians, ``-fov/2`` to ``+fov/2``."""
        return np.linspace(-self.fov / 2.0, self.fov / 2.0, self.beams)

    def with_overrides(self, **changes: Any) -> LadarProfile:
        """Return a copy with some fields replaced (values already in SI)."""
        return replace(self, **changes)

    @property
    def noise_free(self) -> LadarProfile:
        """The same ladar without noise or quantisation."""
        return replace(self, noise="none", sigma=0.0, resolution=0.0)


#: SICK LMS-200 as in the paper: 180 degrees at 1 degree (181 readings), 10 m, relative
#: error below 0.8 %. Range resolution 1 mm (mm mode). Rate 10 Hz: a 181-value telegram
#: takes about 97 ms at 38,400 baud, the usual RS-232 setting on a Pioneer
#: (shared/hardware/sick-lms200.md).
LMS200 = LadarProfile(
    name="lms200",
    source="paper (Sensor used); shared/hardware/sick-lms200.md (timing at 38400 baud)",
)
LMS200_IDEAL = replace(LMS200.noise_free, name="lms200-ideal")

LADAR_PROFILES: dict[str, LadarProfile] = {p.name: p for p in (LMS200, LMS200_IDEAL)}


def ladar_profile(name: str) -> LadarProfile:
    """Return the named ladar profile.

    Raises
    ------
    WorldError
        Unknown name; the message lists the known names.
    """
    try:
        return LADAR_PROFILES[name]
    except KeyError:
        known = ", ".join(sorted(LADAR_PROFILES))
        raise WorldError(f"unknown ladar profile `{name}` (known: {known})") from None


class Ladar:
    """A ladar instance: turns ground-truth ray hits into scans, with seeded noise.

    Parameters
    ----------
    profile : LadarProfile
    rng : numpy.random.Generator
        The only source of randomness (noise draws).
    mount : (x, y, theta)
        Ladar pose in the robot frame (m, m, rad).
    oracle : bool
        Exact ranges, no noise, and ``Scan.tangents`` / ``Scan.curvatures`` filled.
    """

    def __init__(self, profile: LadarProfile, rng: np.random.Generator,
                 mount: tuple[float, float, float] = (0.0, 0.0, 0.0), oracle: bool = False):
        self.profile = profile.noise_free if oracle else profile
        self.oracle = oracle
        self.rng = rng
        self.mount = mount
        bearings = self.profile.bearings() + mount[2]
        bearings.setflags(write=False)
        self.bearings = bearings
        rel = bearings - bearings[0]
        rel.setflags(write=False)
        #: Beam angles relative to the first (ascending), for :meth:`RayCaster.cast`.
        self.rel = rel
        self._noise = np.empty(self.profile.beams)
        self._angles = np.empty(self.profile.beams)
        self._settling = _Settling.of(self.profile)

    def origin(self, x: float, y: float, th: float) -> tuple[float, float]:
        """Return the world position of the ladar on a robot at ``(x, y, th)``."""
        mx, my, _ = self.mount
        c, s = math.cos(th), math.sin(th)
        return x + c * mx - s * my, y + s * mx + c * my

    def world_angles(self, th: float) -> np.ndarray:
        """Return the beam directions in the world frame for heading ``th`` (reused buffer)."""
        return np.add(self.bearings, th, out=self._angles)

    def fan(self, caster: RayCaster, compiled: bool | None = None) -> FanCaster:
        """Make a fan caster for this ladar's beams in ``caster``'s world (for :meth:`scan`).

        ``compiled``: as :class:`sim.raycast.FanCaster` takes it.
        """
        return caster.fan(self.rel, self.profile.max_range, compiled)

    def scan(self, fan: FanCaster, x: float, y: float, th: float, stamp: float) -> Scan:
        """Take a noisy scan from a robot at ``(x, y, th)`` (fast path; not in oracle mode).

        ``fan`` comes from :meth:`fan`. The same as casting :meth:`world_angles` from
        :meth:`origin` and calling :meth:`measure`, with about a third of the numpy calls.
        """
        mx, my, _ = self.mount                      # the mount's angle is in bearings
        c, s = math.cos(th), math.sin(th)
        ranges, hit = fan.cast(x + c * mx - s * my, y + s * mx + c * my,
                               th + float(self.bearings[0]))
        return self.finish(ranges, hit, stamp)

    def measure(self, hits: RayHits, heading: float, stamp: float) -> Scan:
        """Turn the ground truth of one fan of rays into a scan.

        ``hits`` must come from rays cast along :meth:`world_angles` (with ``detail`` in
        oracle mode); ``heading`` is the robot's true heading (for the oracle's tangents).
        """
        p = self.profile
        valid = hits.hit & (hits.ranges <= p.max_range * (1.0 + MAX_RANGE_SLACK))
        ranges = np.where(valid, hits.ranges, p.max_range)
        if not self.oracle:
            return self.finish(ranges, valid, stamp)
        np.clip(ranges, 0.0, p.max_range, out=ranges)
        tangents = curvatures = None
        if hits.tangents is not None and hits.curvatures is not None:
            tangents = np.where(valid, np.mod(hits.tangents - heading + math.pi, 2 * math.pi)
                                - math.pi, math.nan)
            curvatures = np.where(valid, hits.curvatures, math.nan)
            tangents.setflags(write=False)
            curvatures.setflags(write=False)
        ranges.setflags(write=False)
        valid.setflags(write=False)
        return Scan(ranges=ranges, bearings=self.bearings, valid=valid, stamp=stamp,
                    max_range=p.max_range, tangents=tangents, curvatures=curvatures)

    def finish(self, ranges: np.ndarray, valid: np.ndarray, stamp: float) -> Scan:
        """Add noise, quantise and clip, in place; return the scan.

        ``ranges`` (``max_range`` where not ``valid``) and ``valid`` are new arrays that
        the scan then owns.
        """
        self.settle(ranges, valid)
        return plain_scan(ranges, self.bearings, valid, stamp, self.profile.max_range)

    def settle(self, ranges: np.ndarray, valid: np.ndarray) -> None:
        """Add noise, quantise and clip the ranges in place, then make both read-only.

        For a scan made before its ranges were final (a team's robots occlude each
        other's scans once all have moved): the same draws as :meth:`finish`.
        """
        how = self._settling
        how.settle(ranges, valid, self.rng.standard_normal(out=self._noise) if how.noisy else None)


def settle_rows(ladars: Sequence[Ladar], ranges: np.ndarray, valid: np.ndarray) -> None:
    """:meth:`Ladar.settle` for the scans of several ladars of one profile, as one block.

    Row ``k`` of ``ranges`` and ``valid`` (S, B) is a scan of ``ladars[k]``; each ladar
    draws its own noise, then noise, quantisation and clipping are applied to the block
    at once: element by element the same arithmetic as :meth:`Ladar.settle`, so each row
    comes out as that call would leave it. Both arrays are read-only afterwards.
    """
    p = ladars[0].profile
    if any(lad.profile is not p and lad.profile != p for lad in ladars):  # `is`: no __eq__
        raise ValueError("settle_rows needs ladars of one profile")
    how = ladars[0]._settling
    noise = None
    if how.noisy:
        noise = np.empty(ranges.shape)
        for lad, row in zip(ladars, noise, strict=True):
            lad.rng.standard_normal(out=row)
    how.settle(ranges, valid, noise)


@dataclass(frozen=True)
class _Settling:
    """What :meth:`Ladar.settle` applies to a profile's scans.

    The noise, quantum and range limit as 0-d arrays: a ufunc takes them far faster than
    Python floats.
    """

    noisy: bool
    relative: bool
    sigma: np.ndarray
    resolution: np.ndarray | None
    zero: np.ndarray
    max_range: np.ndarray

    @classmethod
    def of(cls, p: LadarProfile) -> _Settling:
        """Return the settling of profile ``p``."""
        return cls(p.noise != "none" and p.sigma > 0, p.noise == "relative",
                   np.array(float(p.sigma)),
                   np.array(float(p.resolution)) if p.resolution > 0 else None,
                   np.array(0.0), np.array(float(p.max_range)))

    def settle(self, ranges: np.ndarray, valid: np.ndarray, noise: np.ndarray | None
               ) -> None:
        """Add the standard normal draws ``noise`` (scaled here), quantise, clip, freeze.

        In one compiled call where the install has it (:data:`_SETTLE`): the same
        operations on each number, so the same numbers.
        """
        if (_SETTLE is not None and ranges.flags.c_contiguous and valid.flags.c_contiguous
                and (noise is None or noise.flags.c_contiguous)):
            _SETTLE(ranges, valid, noise, float(self.sigma), self.relative,
                    0.0 if self.resolution is None else float(self.resolution),
                    float(self.max_range))
            ranges.setflags(write=False)
            valid.setflags(write=False)
            return
        self.settle_numpy(ranges, valid, noise)

    def settle_numpy(self, ranges: np.ndarray, valid: np.ndarray, noise: np.ndarray | None
                     ) -> None:
        """:meth:`settle` in numpy: the compiled loop's reference."""
        if noise is not None:
            noise *= self.sigma
            if self.relative:
                noise *= ranges
            noise *= valid                  # no noise on invalid beams (adding 0 keeps them)
            ranges += noise
        if self.resolution is not None:
            ranges /= self.resolution
            np.rint(ranges, out=ranges)
            ranges *= self.resolution
        np.maximum(ranges, self.zero, out=ranges)
        np.minimum(ranges, self.max_range, out=ranges)
        ranges.setflags(write=False)
        valid.setflags(write=False)
