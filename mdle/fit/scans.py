"""Fit the stretches in which a robot's ladar delivers scans at half its rate.

Over ARCOS, AMRISim's laser sends a scan with every report for a while, then with every
other report only (5 Hz instead of 10 Hz) for seconds at a time, and back: in its
2026-11-28 recordings a third of the time. Laws then steer on scans twice as old, and
the swings at the corridor's door jambs grow. A recording's scan stamps (the tick's time
minus its ``scan_age``) show the stretches: runs of gaps of two scan periods.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mdle.fit.recording import Recording
from mdle.sim.robot import HalfRate

__all__ = ["Stretches", "fit_half_rate", "half_rate_stretches"]

#: Gaps of two periods in a row that make a stretch: fewer are single lost scans.
MIN_GAPS = 3


@dataclass(frozen=True)
class Stretches:
    """The half-rate stretches of one recording (seconds, on its clock)."""

    starts: np.ndarray
    ends: np.ndarray
    span: float
    """From the first scan to the last, s."""

    @property
    def lengths(self) -> np.ndarray:
        """Return each stretch's length, s."""
        return self.ends - self.starts

    def covers(self, stamps: np.ndarray) -> np.ndarray:
        """Return which scan stamps lie inside a stretch (bool array like ``stamps``)."""
        inside = np.zeros(stamps.shape, dtype=bool)
        for a, b in zip(self.starts, self.ends, strict=True):
            inside |= (stamps >= a) & (stamps <= b)
        return inside


def scan_stamps(rec: Recording) -> np.ndarray:
    """Return when each tick's scan was taken (``t - scan_age``; NaN without a scan), s."""
    return rec.t - rec.scan_age


def half_rate_stretches(rec: Recording, period: float) -> Stretches:
    """Find the stretches of a recording in which scans came every two periods.

    A stretch is at least :data:`MIN_GAPS` gaps in a row between new scans that round to
    two periods; it runs from the scan before its first gap to the scan after its last.
    """
    stamps = scan_stamps(rec)
    stamps = np.unique(np.round(stamps[np.isfinite(stamps)], 6))
    if stamps.size < 2:
        return Stretches(np.zeros(0), np.zeros(0), 0.0)
    double = np.round(np.diff(stamps) / period) == 2
    # the runs of doubled gaps: where they begin and end in the gap sequence
    edges = np.diff(np.r_[0, double.astype(np.int8), 0])
    first, last = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    long = last - first >= MIN_GAPS
    return Stretches(stamps[first[long]], stamps[last[long]],
                     float(stamps[-1] - stamps[0]))


def fit_half_rate(recs: Sequence[Recording], period: float) -> HalfRate:
    """Return the share of time at half rate and the stretches' mean length, over ``recs``.

    ``HalfRate()`` (never) when no recording has scan ages or a stretch.
    """
    found = [half_rate_stretches(r, period) for r in recs]
    lengths = np.concatenate([s.lengths for s in found]) if found else np.zeros(0)
    span = sum(s.span for s in found)
    if lengths.size == 0 or span <= 0:
        return HalfRate()
    return HalfRate(round(float(lengths.sum() / span), 3), round(float(lengths.mean()), 2))
