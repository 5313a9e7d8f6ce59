"""What a run measured: collisions, clearance, path, boundary following, chosen trace fields.

Everything is computed once at the end of a run from its samples (ground truth from the
simulator), vectorised. Boundary following is measured on the ticks a
``follow_boundary`` atom was running, against that atom's ``rc`` and ``side``:

* ``follow_mean_err`` / ``follow_max_err``: mean and max of ``|d - rc|`` over the second
  half (in time) of those ticks, ``d`` the true distance from the robot's centre to the
  nearest boundary;
* ``engaged``: the robot held ``|d - rc| <= 0.2 m`` with the nearest boundary on the
  followed side for 4 m of path without a break; ``engage_distance`` the path length
  travelled before that stretch began (m).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["FollowSpec", "follow_atoms", "follow_metrics", "field_summary", "path_length",
           "ENGAGE_TOLERANCE", "ENGAGE_PATH"]

#: Largest |d - rc| (m) that counts as following, and the path (m) it must last.
ENGAGE_TOLERANCE = 0.2
ENGAGE_PATH = 4.0


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
    from mdle.program import AtomNode

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
                   d: np.ndarray, near: np.ndarray, rc: np.ndarray, right: np.ndarray,
                   following: np.ndarray) -> dict[str, float | bool | None]:
    """Measure boundary following from per-tick truth.

    Parameters
    ----------
    t, x, y, theta : (N,) arrays
        Time (s) and true pose (m, m, rad).
    d : (N,) array
        True distance from the robot's centre to the nearest boundary, m.
    near : (N, 2) array
        That nearest boundary point.
    rc : (N,) array
        The following distance of the atom running at each tick (NaN when none).
    right : (N,) bool array
        The boundary is to be kept on the right.
    following : (N,) bool array
        A boundary-following atom was running.

    Returns
    -------
    dict
        ``follow_rc`` (the first rc), ``follow_mean_err``, ``follow_max_err``,
        ``engaged``, ``engage_distance``; None where no tick was following.
    """
    none: dict[str, float | bool | None] = {"follow_rc": None, "follow_mean_err": None,
                                            "follow_max_err": None, "engaged": None,
                                            "engage_distance": None}
    if not following.any():
        return none
    idx = np.flatnonzero(following)
    tf = t[idx]
    second = idx[tf >= tf[0] + (tf[-1] - tf[0]) / 2.0]
    err = np.abs(d[second] - rc[second])
    # Which side the nearest boundary point lies on: the cross product of heading and
    # the vector to it is negative when it is to the right.
    cross = np.cos(theta) * (near[:, 1] - y) - np.sin(theta) * (near[:, 0] - x)
    on_side = np.where(right, cross < 0.0, cross > 0.0)
    ok = following & on_side & (np.abs(d - rc) <= ENGAGE_TOLERANCE)
    s = path_length(x, y)
    engaged, engage_at = _first_stretch(ok, s, ENGAGE_PATH)
    return {"follow_rc": float(rc[idx[0]]), "follow_mean_err": float(err.mean()),
            "follow_max_err": float(err.max()), "engaged": engaged,
            "engage_distance": engage_at}


def _first_stretch(ok: np.ndarray, s: np.ndarray, length: float) -> tuple[bool, float | None]:
    """Find the first unbroken run of ``ok`` ticks covering ``length`` of path."""
    if not ok.any():
        return False, None
    padded = np.concatenate(([False], ok, [False])).astype(np.int8)
    edges = np.diff(padded)
    starts = np.flatnonzero(edges == 1)
    ends = np.flatnonzero(edges == -1) - 1
    covered = s[ends] - s[starts]
    good = np.flatnonzero(covered >= length)
    if len(good) == 0:
        return False, None
    return True, float(s[starts[good[0]]])


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
