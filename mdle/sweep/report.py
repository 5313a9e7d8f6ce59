"""Summaries and plots of a results table: per value of each swept axis.

An axis is a column that varies across the table: a plan parameter (``param_kf``), the
control rate, sensing, robot, world or seed. For each value: runs, failures, collisions,
engagement (of runs that follow a boundary), quantiles of the following error
``follow_mean_err`` (m) and the closest approach. The plots show a metric against each
axis (every run a dot, the median a line) beside box plots per value.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["axes", "summarise", "format_summary", "plot_axes", "numeric"]

_AXIS_ORDER = ("rate", "sensing", "robot", "world", "entry", "plan")
_FAILED = ("collision", "error", "lost")
#: Axis labels with units for the metrics a run records.
_LABELS = {"follow_mean_err": "mean |d - rc|, second half (m)",
           "follow_max_err": "max |d - rc|, second half (m)",
           "min_clearance": "closest approach (m)", "distance": "distance travelled (m)",
           "duration": "duration (s)", "wall_time": "wall time (s)",
           "engage_distance": "path before engaging (m)", "rate": "control rate (Hz)"}


def numeric(value: Any) -> float | None:
    """Read a parameter value's number (``0.8 m`` gives 0.8), None if it has none."""
    if isinstance(value, bool) or value is None:
        return None
    if isinstance(value, (int, float)):
        return float(value)
    m = re.match(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)", str(value))
    return float(m.group(1)) if m else None


def axes(rows: Sequence[dict[str, Any]]) -> list[str]:
    """Return the columns that vary across ``rows``: parameters first, then the others."""
    params = [c for c in (rows[0] if rows else {}) if c.startswith("param_")]
    out = []
    for c in [*params, *_AXIS_ORDER]:
        if c in (rows[0] if rows else {}) and len({_key(r.get(c)) for r in rows}) > 1:
            out.append(c)
    return out


def _key(v: Any) -> Any:
    return "" if v is None else v


def _sorted_values(rows: Sequence[dict[str, Any]], axis: str) -> list[Any]:
    values = list(dict.fromkeys(_key(r.get(axis)) for r in rows))
    nums = [numeric(v) for v in values]
    if all(n is not None for n in nums):
        order = sorted(range(len(values)), key=lambda i: float(nums[i] or 0.0))
        return [values[i] for i in order]
    return sorted(values, key=str)


def _q(values: Iterable[float | None], q: float) -> float | None:
    arr = np.array([v for v in values if v is not None and math.isfinite(v)], dtype=float)
    return float(np.quantile(arr, q)) if len(arr) else None


def summarise(rows: Sequence[dict[str, Any]], axis: str) -> list[dict[str, Any]]:
    """Return one summary per value of ``axis`` (runs, failures, engagement, quantiles)."""
    out = []
    for value in _sorted_values(rows, axis):
        group = [r for r in rows if _key(r.get(axis)) == value]
        following = [r for r in group if r.get("engaged") is not None]
        errs = [r.get("follow_mean_err") for r in group]
        clear = [r.get("min_clearance") for r in group]
        out.append({
            "value": value, "runs": len(group),
            "failures": sum(r.get("status") in _FAILED for r in group),
            "collisions": sum(bool(r.get("collided")) for r in group),
            "errors": sum(r.get("status") in ("error", "lost") for r in group),
            "engaged": sum(bool(r.get("engaged")) for r in following),
            "following": len(following),
            "err_p50": _q(errs, 0.5), "err_p90": _q(errs, 0.9), "err_max": _q(errs, 1.0),
            "clear_min": _q(clear, 0.0),
        })
    return out


def _f(v: float | None, width: int, digits: int = 3) -> str:
    return f"{'-':>{width}}" if v is None else f"{v:{width}.{digits}f}"


def format_summary(rows: Sequence[dict[str, Any]], axis_names: Sequence[str] | None = None
                   ) -> str:
    """Return the plain-text summary tables, one per axis (all runs when nothing varies)."""
    names = list(axis_names) if axis_names else axes(rows)
    ok = sum(r.get("status") == "ok" for r in rows)
    lines = [f"{len(rows)} runs: {ok} ok, {len(rows) - ok} failed "
             f"({sum(r.get('status') == 'collision' for r in rows)} collisions, "
             f"{sum(r.get('status') == 'error' for r in rows)} errors, "
             f"{sum(r.get('status') == 'lost' for r in rows)} lost)"]
    head = (f"{'runs':>5} {'failed':>6} {'collided':>8} {'engaged':>9} "
            f"{'|d-rc| p50':>10} {'p90':>7} {'max':>7} {'closest':>8}")
    for axis in names or ["(all)"]:
        label = axis.removeprefix("param_")
        lines += ["", f"by {label}",
                  f"{label:>12} {head}"]
        groups = summarise(rows, axis) if axis != "(all)" else [
            {**summarise([{**r, "_": 0} for r in rows], "_")[0], "value": "all"}]
        for g in groups:
            eng = (f"{g['engaged']}/{g['following']}" if g["following"] else "-")
            lines.append(f"{str(g['value'])[:12]:>12} {g['runs']:5d} {g['failures']:6d} "
                         f"{g['collisions']:8d} {eng:>9} {_f(g['err_p50'], 10)} "
                         f"{_f(g['err_p90'], 7)} {_f(g['err_max'], 7)} "
                         f"{_f(g['clear_min'], 8)}")
    lines += ["", "engaged: runs that held |d - rc| <= 0.2 m with the boundary on the "
              "followed side for 4 m of path, of the runs that followed a boundary;",
              "|d-rc|: quantiles over runs of the mean following error in the second half "
              "of following (m); closest: smallest true clearance of the body (m)."]
    return "\n".join(lines)


def plot_axes(rows: Sequence[dict[str, Any]], folder: str | Path, metric: str,
              axis_names: Sequence[str] | None = None, group: str | None = None
              ) -> list[Path]:
    """Draw ``metric`` against each axis (dots and median; box plots); return the files.

    With ``group`` (another column) the left panel draws one median line per value of
    that column instead of a single one.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir = Path(folder)
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for axis in list(axis_names) if axis_names else axes(rows):
        values = _sorted_values(rows, axis)
        data = [np.array([r[metric] for r in rows if _key(r.get(axis)) == v
                          and isinstance(r.get(metric), (int, float))
                          and math.isfinite(r[metric])], dtype=float) for v in values]
        if not any(len(d) for d in data):
            continue
        nums = [numeric(v) for v in values]
        numeric_axis = all(n is not None for n in nums) and axis not in ("seed",)
        label = axis.removeprefix("param_")
        fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
        xs = [float(n) if numeric_axis and n is not None else float(i)
              for i, n in enumerate(nums)]
        for x, d in zip(xs, data, strict=True):
            left.plot(np.full(len(d), x), d, "o", color="tab:blue", alpha=0.35, ms=4)
        if group is None or group == axis:
            med = [(x, float(np.median(d))) for x, d in zip(xs, data, strict=True) if len(d)]
            left.plot([m[0] for m in med], [m[1] for m in med], "-", color="tab:red",
                      label="median")
        else:
            for gv in _sorted_values(rows, group):
                sub = [r for r in rows if _key(r.get(group)) == gv]
                pts = []
                for x, v in zip(xs, values, strict=True):
                    vals = [r[metric] for r in sub if _key(r.get(axis)) == v
                            and isinstance(r.get(metric), (int, float))
                            and math.isfinite(r[metric])]
                    if vals:
                        pts.append((x, float(np.median(vals))))
                left.plot([p[0] for p in pts], [p[1] for p in pts], "o-",
                          label=f"median, {group.removeprefix('param_')} = {gv}")
        if not numeric_axis:
            left.set_xticks(xs, [str(v) for v in values], rotation=30, ha="right")
        left.set_xlabel(_LABELS.get(axis, label))
        left.set_ylabel(_LABELS.get(metric, metric))
        left.set_title(f"{metric} vs {label} (each dot a run)")
        left.legend(loc="best")
        left.grid(alpha=0.3)
        right.boxplot([d if len(d) else np.array([np.nan]) for d in data])
        right.set_xticks(range(1, len(values) + 1), [str(v) for v in values], rotation=30,
                         ha="right")
        right.set_xlabel(_LABELS.get(axis, label))
        right.set_ylabel(_LABELS.get(metric, metric))
        right.set_title(f"{metric} per {label}")
        right.grid(alpha=0.3)
        suffix = f"-by-{group.removeprefix('param_')}" if group and group != axis else ""
        path = out_dir / f"{metric}-vs-{label}{suffix}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)
    return written
