"""A team's run as one animation (``mdle plot run.a.jsonl run.b.jsonl --animate team.gif``).

Every robot of the team in one world, on one clock: its path so far in its own colour,
its body and heading, and the element it is running; a message (other than pose beacons)
is shown beside its receiver for a second after it arrived. The robots' traces share
their time stamps (one tick loop), so frame ``k`` shows every robot at the same instant.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import Any

from mdle.core.errors import Diagnostic
from mdle.record.trace import Trace

__all__ = ["animate_team"]

_SHOW_MESSAGE = 1.0  # s a received message stays on screen


def animate_team(traces: Sequence[Trace], world: Any, out: str | os.PathLike[str],
                 max_frames: int | None = None) -> str:
    """Write the team run as an animation to ``out`` (.gif or .mp4); return ``out``.

    Raises
    ------
    PlotError
        Unknown extension, no ffmpeg for an MP4, a trace without samples, or the file
        cannot be written.
    """
    import numpy as np
    from matplotlib import animation
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle

    from mdle.view.animate import FPS, _writer, frame_indices
    from mdle.view.figure_output import PlotError, atomic_output
    from mdle.view.plot import draw_world, robot_radius, run_pose
    from mdle.view.team_plot import robot_name

    out = os.fspath(out)
    writer = _writer(out)
    robots = []
    for trace in traces:
        if not trace.samples:
            raise PlotError(Diagnostic(None, f"trace `{trace.path}` has no samples to animate"))
        x, y, th, _ = run_pose(trace, world)
        received = [(float(m.get("t") or 0.0), f"{m.get('channel')} = {m.get('value'):.3g}"
                     f" from {m.get('from')}") for m in trace.extra
                    if m.get("type") == "message" and m.get("dir") == "received"
                    and isinstance(m.get("value"), (int, float))]
        robots.append((robot_name(trace), trace.column("t"), x, y, th, trace.paths(),
                       max(robot_radius(trace, world), 0.12), received))
    times = np.unique(np.concatenate([r[1] for r in robots]))
    frames = times[frame_indices(times) if max_frames is None
                   else frame_indices(times, max_frames)]
    fig = Figure(figsize=(7.0, 5.6), layout="constrained")
    ax = fig.subplots()
    if world is not None:
        draw_world(ax, world)
    artists = []
    for k, (name, _, x, y, _, _, body, _) in enumerate(robots):
        colour = f"C{k % 10}"
        ax.plot(x, y, lw=0.8, color="0.8", zorder=2)
        (done,) = ax.plot([], [], lw=2.0, color=colour, zorder=3, label=name)
        disc = Circle((float(x[0]), float(y[0])), body, facecolor=colour, alpha=0.45,
                      edgecolor=colour, zorder=4)
        ax.add_patch(disc)
        (nose,) = ax.plot([], [], lw=2.0, color="k", zorder=5)
        note = ax.text(0, 0, "", fontsize="x-small", color=colour, zorder=6)
        artists.append((done, disc, nose, note))
    label = ax.text(0.01, 0.99, "", transform=ax.transAxes, va="top", fontsize="small",
                    family="monospace", bbox={"facecolor": "white", "alpha": 0.8, "lw": 0})
    xs = np.concatenate([r[2] for r in robots])
    ys = np.concatenate([r[3] for r in robots])
    good = np.isfinite(xs) & np.isfinite(ys)
    if world is not None:
        x0, y0, x1, y1 = world.bounds
    else:
        x0, y0, x1, y1 = xs[good].min(), ys[good].min(), xs[good].max(), ys[good].max()
    ax.set_xlim(min(float(x0), float(xs[good].min())) - 0.5,
                max(float(x1), float(xs[good].max())) + 0.5)
    ax.set_ylim(min(float(y0), float(ys[good].min())) - 0.5,
                max(float(y1), float(ys[good].max())) + 0.5)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(loc="upper right", fontsize="small")
    t0 = float(times[0])

    def draw(now: float) -> None:
        lines = [f"t {now - t0:6.1f} s"]
        for (name, t, x, y, th, paths, body, received), (done, disc, nose, note) in zip(
                robots, artists, strict=True):
            i = int(np.clip(np.searchsorted(t, now + 1e-9, side="right") - 1, 0, len(t) - 1))
            px, py, pth = float(x[i]), float(y[i]), float(th[i])
            if not (math.isfinite(px) and math.isfinite(py)):
                continue
            done.set_data(x[: i + 1], y[: i + 1])
            disc.set_center((px, py))
            nose.set_data([px, px + 2 * body * math.cos(pth)],
                          [py, py + 2 * body * math.sin(pth)])
            heard = [text for at, text in received if now - _SHOW_MESSAGE < at <= now]
            note.set_position((px + body, py + body))
            note.set_text(heard[-1] if heard else "")
            lines.append(f"{name}: {paths[i] or '-'}")
        label.set_text("\n".join(lines))

    anim = animation.FuncAnimation(fig, draw, frames=[float(f) for f in frames],
                                   interval=1000.0 / FPS, blit=False)
    with atomic_output(out) as tmp:
        anim.save(tmp, writer=writer, dpi=72)
    return out
