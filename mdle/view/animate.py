"""A run as an animation (``mdle plot --animate run.gif|run.mp4``).

Each frame shows the world, the path so far, the robot's body and heading, the ladar
rays of the scan it had then (from the trace's ``scan`` records) and the running
element's name and time. matplotlib's animation writers do the encoding: Pillow for a GIF
(always there: matplotlib needs it), ffmpeg for an MP4 when it is installed (else a
message that says so and suggests a GIF). Frames are spread evenly over the run: at most
:data:`MAX_FRAMES`, shown at :data:`FPS` frames a second.
"""

from __future__ import annotations

import math
import os
from typing import TYPE_CHECKING, Any

from mdle.core.errors import Diagnostic
from mdle.record.trace import Trace, decode_ranges
from mdle.view.figure_output import PlotError, atomic_output
from mdle.view.plot import draw_world, robot_radius, run_pose

if TYPE_CHECKING:
    import numpy as np

__all__ = ["animate_trace", "FPS", "MAX_FRAMES", "frame_indices"]

FPS = 12
MAX_FRAMES = 150


def frame_indices(times: "np.ndarray", max_frames: int = MAX_FRAMES) -> "np.ndarray":
    """Sample indices of the frames: evenly spread in time, first and last included.

    >>> import numpy as np
    >>> frame_indices(np.arange(0.0, 10.0, 0.01), 5).tolist()
    [0, 250, 500, 750, 999]
    """
    import numpy as np

    n = len(times)
    if n <= max_frames:
        return np.arange(n)
    want = np.linspace(float(times[0]), float(times[-1]), max_frames)
    return np.unique(np.searchsorted(times, want).clip(0, n - 1))


def _writer(out: str) -> Any:
    """Return the matplotlib writer for ``out``'s extension, or raise a clear PlotError."""
    from matplotlib import animation

    ext = os.path.splitext(out)[1].lower()
    if ext == ".gif":
        return animation.PillowWriter(fps=FPS)
    if ext == ".mp4":
        if not animation.writers.is_available("ffmpeg"):
            raise PlotError(Diagnostic(None, f"cannot write `{out}`: an MP4 needs ffmpeg, which "
                                             "is not installed here; install ffmpeg, or write "
                                             "a GIF (`--animate run.gif`)"))
        return animation.FFMpegWriter(fps=FPS)
    raise PlotError(Diagnostic(None, f"cannot animate to `{out}`: the file name must end in "
                                     ".gif or .mp4"))


def _scans(trace: Trace) -> tuple["np.ndarray", list[Any], "np.ndarray | None"]:
    """Return the scans' times, their ranges and the beam bearings (robot frame), if recorded."""
    import numpy as np

    laser = trace.lasers[0] if trace.lasers else None
    if laser is None or not trace.scans:
        return np.zeros(0), [], None
    try:
        n = int(laser["count"])
        bearings = (float(laser["angle_min"]) + float(laser["angle_increment"]) * np.arange(n)
                    + float(laser["mount"][2]))
        ranges = [decode_ranges(s["ranges"]) for s in trace.scans]
    except (KeyError, TypeError, ValueError, IndexError):
        return np.zeros(0), [], None
    times = np.array([float(s.get("t", math.nan)) for s in trace.scans])
    return times, ranges, bearings


def animate_trace(trace: Trace, world: Any, out: str | os.PathLike[str],
                  max_frames: int = MAX_FRAMES) -> str:
    """Write the run in ``trace`` as an animation to ``out`` (.gif or .mp4); return ``out``.

    Raises
    ------
    PlotError
        Unknown extension, no ffmpeg for an MP4, no samples, or the file cannot be written.
    """
    import numpy as np
    from matplotlib import animation
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle


    out = os.fspath(out)
    writer = _writer(out)
    if not trace.samples:
        raise PlotError(Diagnostic(None, f"trace `{trace.path}` has no samples to animate"))
    x, y, th, _ = run_pose(trace, world)
    ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(th)
    if not ok.any():
        raise PlotError(Diagnostic(None, f"trace `{trace.path}` has no sample with a finite "
                                         "pose to animate"))
    t = trace.column("t")
    paths = trace.paths()
    keep = np.flatnonzero(ok)
    frames = keep[frame_indices(t[keep], max_frames)]
    scan_t, scan_r, bearings = _scans(trace)
    radius = robot_radius(trace, world)
    body = max(radius, 0.12)

    fig = Figure(figsize=(7.0, 5.6), layout="constrained")
    ax = fig.subplots()
    if world is not None:
        draw_world(ax, world)
    ax.plot(x[ok], y[ok], lw=0.8, color="0.75", zorder=2)
    (done,) = ax.plot([], [], lw=2.0, color="tab:blue", zorder=3)
    rays = None
    if bearings is not None:
        from matplotlib.collections import LineCollection

        rays = LineCollection([], colors="tab:orange", lw=0.4, alpha=0.5, zorder=2.5)
        ax.add_collection(rays)
    disc = Circle((x[frames[0]], y[frames[0]]), body, facecolor="tab:blue", alpha=0.45,
                  edgecolor="tab:blue", zorder=4)
    ax.add_patch(disc)
    (nose,) = ax.plot([], [], lw=2.0, color="k", zorder=5)
    label = ax.text(0.01, 0.99, "", transform=ax.transAxes, va="top", fontsize="small",
                    family="monospace", bbox={"facecolor": "white", "alpha": 0.8, "lw": 0})
    xs, ys = x[ok], y[ok]
    pad = 1.0 + body
    ax.set_xlim(float(xs.min()) - pad, float(xs.max()) + pad)
    ax.set_ylim(float(ys.min()) - pad, float(ys.max()) + pad)
    if world is not None and getattr(world, "geometry", None) is not None:
        gx0, gy0, gx1, gy1 = world.geometry.bounds
        ax.set_xlim(min(ax.get_xlim()[0], gx0 - 0.5), max(ax.get_xlim()[1], gx1 + 0.5))
        ax.set_ylim(min(ax.get_ylim()[0], gy0 - 0.5), max(ax.get_ylim()[1], gy1 + 0.5))
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, lw=0.3, alpha=0.5)
    t0 = float(t[keep[0]])

    def draw(i: int) -> None:
        px, py, pth = float(x[i]), float(y[i]), float(th[i])
        done.set_data(x[: i + 1][ok[: i + 1]], y[: i + 1][ok[: i + 1]])
        disc.set_center((px, py))
        nose.set_data([px, px + 2 * body * math.cos(pth)], [py, py + 2 * body * math.sin(pth)])
        if rays is not None and bearings is not None and len(scan_t):
            k = int(np.searchsorted(scan_t, t[i], side="right")) - 1
            if k >= 0:
                r = np.asarray(scan_r[k], dtype=float)
                n = min(len(r), len(bearings))
                good = np.isfinite(r[:n])
                a = pth + bearings[:n][good]
                seg = np.empty((len(a), 2, 2))
                seg[:, 0] = (px, py)
                seg[:, 1, 0] = px + r[:n][good] * np.cos(a)
                seg[:, 1, 1] = py + r[:n][good] * np.sin(a)
                rays.set_segments(list(seg))
        label.set_text(f"t {t[i] - t0:6.1f} s   {paths[i] or '-'}")

    anim = animation.FuncAnimation(fig, draw, frames=[int(i) for i in frames],
                                   interval=1000.0 / FPS, blit=False)
    with atomic_output(out) as tmp:
        anim.save(tmp, writer=writer, dpi=72)
    return out
