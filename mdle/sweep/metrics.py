"""What a run measured: collisions, clearance, path, boundary following, chosen trace fields.

Everything is computed once at the end of a run from its samples (ground truth from the
simulator), vectorised. Boundary following is measured on the ticks a
``follow_boundary`` atom was running, against that atom's ``rc`` and ``side``:

* ``follow_mean_err`` / ``follow_max_err``: mean and max of ``|d - rc|`` over the second
  half (in time) of those ticks, ``d`` the true distance from the robot's centre to the
  nearest boundary;
* ``engaged`` (the engagement measure of :mod:`mdle.sweep.engagement`): the robot
  held ``|d - rc| <= 0.2 m`` with the nearest boundary on the followed side for 4 m of path
  without a break; ``engage_time``/``engage_distance`` when that stretch began (s, m of
  path from the run's start); ``engaged_mean_err``/``engaged_max_err`` over the second half
  of the time after it.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["FollowSpec", "follow_atoms", "follow_metrics", "field_summary", "path_length",
           "FOLLOW_COLUMNS"]

#: The columns :func:`follow_metrics` fills.
FOLLOW_COLUMNS = ("follow_rc", "follow_mean_err", "follow_max_err", "engaged", "engage_time",
                  "engage_distance", "engaged_mean_err", "engaged_max_err")


@dataclass(frozen=True)
class FollowSpec:
    """A boundary-following atom's distance ``rc`` (m) and ``side`` (``right``/``left``)."""

    rc: float
    side: str


def follow_atoms(element: Any, law: str = "follow_boundary") -> dict[str, FollowSpec]:
    """Map the run paths of ``element``'s boundary-following atoms to their rc and side.

    Paths are named as the scheduler names them (``main/follow``, a repeated label
    gets ``#2``).
    """
    from mdle.lang import AtomNode

    out: dict[str, FollowSpec] = {}

    def walk(node: Any, path: str) -> None:
        if isinstance(node, AtomNode):
            if node.law.name == law:
                out[path] = FollowSpec(float(node.args["rc"]), str(node.args["side"]))
            return
        seen: dict[str, int] = {}
        for child in node.elements:
            n = seen[child.label] = seen.get(child.label, 0) + 1
            walk(child, f"{path}/{child.label if n == 1 else f'{child.label}#{n}'}")

    walk(element, element.label)
    return out


def path_length(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Return the cumulative path length at each sample (m), starting at 0."""
    if len(x) == 0:
        return np.zeros(0)
    return np.concatenate(([0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))))


def follow_metrics(t: np.ndarray, x: np.ndarray, y: np.ndarray, theta: np.ndarray,
                   d: np.ndarray, near: np.ndarray, clearance: np.ndarray, rc: np.ndarray,
                   right: np.ndarray, following: np.ndarray) -> dict[str, float | bool | None]:
    """Measure boundary following from per-tick truth.

    Parameters
    ----------
    t, x, y, theta : (N,) arrays
        Time (s) and true pose (m, m, rad).
    d : (N,) array
        True distance from the robot's centre to the nearest boundary, m.
    near : (N, 2) array
        That nearest boundary point.
    clearance : (N,) array
        True body clearance, m.
    rc : (N,) array
        The following distance of the atom running at each tick (NaN when none).
    right : (N,) bool array
        The boundary is to be kept on the right.
    following : (N,) bool array
        A boundary-following atom was running.

    Returns
    -------
    dict
        ``follow_rc`` (the first atom's rc), ``follow_mean_err`` and ``follow_max_err``
        (second half of the following time, engaged or not), and the engagement measures
        of :func:`mdle.sweep.engagement.follow_metrics` on the following ticks:
        ``engaged``, ``engage_time``, ``engage_distance`` (from the start of the run),
        ``engaged_mean_err``, ``engaged_max_err`` (second half of the time after
        engagement); None where no tick was following.
    """
    from mdle.sweep.engagement import follow_metrics as engagement

    none: dict[str, float | bool | None] = dict.fromkeys(FOLLOW_COLUMNS)
    if not following.any():
        return none
    idx = np.flatnonzero(following)
    # The following time runs from its first tick to the tick its atom ended (that tick's
    # sample, the state the atom ended in, counts too).
    span = np.append(idx, idx[-1] + 1) if idx[-1] + 1 < len(t) else idx
    second = span[t[span] >= t[span[0]] + (t[span[-1]] - t[span[0]]) / 2.0]
    err = np.abs(d[second] - rc[idx[0]])
    rc0, right0 = float(rc[idx[0]]), bool(right[idx[0]])
    # One rc and side for the engagement measure: those of the first following atom.
    same = idx[(rc[idx] == rc0) & (right[idx] == right0)]
    m = engagement(t[same], x[same], y[same], theta[same], d[same], near[same],
                   clearance[same], collided=False, side="right" if right0 else "left",
                   rc=rc0)
    s = path_length(x, y)

    def opt(v: float) -> float | None:
        return None if math.isnan(v) else float(v)

    return {"follow_rc": rc0, "follow_mean_err": float(err.mean()),
            "follow_max_err": float(err.max()), "engaged": bool(m.engaged),
            "engage_time": opt(m.t_engage),
            "engage_distance": None if not m.engaged else float(
                s[same][0] + m.s_engage),
            "engaged_mean_err": opt(m.mean_err), "engaged_max_err": opt(m.max_err)}


def field_summary(samples: Sequence[Any], names: Iterable[str],
                  sample_fields: Sequence[str]) -> dict[str, float | None]:
    """Return ``NAME_mean`` and ``NAME_max`` of each chosen trace field over the samples.

    A name is a sample field (``cmd_v``, ``clearance``...) or a control-law diagnostic
    (``side_range``...); ticks without a value are skipped; None when no tick has one.
    """
    out: dict[str, float | None] = {}
    for name in names:
        if name in sample_fields:
            vals = [getattr(s, name) for s in samples]
        else:
            vals = [s.diag.get(name) if isinstance(s.diag, Mapping) else None for s in samples]
        arr = np.array([math.nan if v is None else float(v) for v in vals], dtype=float)
        arr = arr[np.isfinite(arr)]
        out[f"{name}_mean"] = float(arr.mean()) if len(arr) else None
        out[f"{name}_max"] = float(arr.max()) if len(arr) else None
    return out
