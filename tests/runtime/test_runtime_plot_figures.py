"""The run figure as a reviewer reads it: the followed side, curvature limits and truth, the
legend beside the path, footprints, doors, stretched corridors, end marks that stay visible."""

from __future__ import annotations

import math
import types
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from mdle.atoms.registry import Context
from mdle.cli import main
from mdle.core.backend import Command
from mdle.record.load import read_trace
from mdle.record.trace import Trace, TraceWriter
from mdle.runtime import run
from mdle.runtime.scripted import ScriptedBackend
from mdle.view.plot import CAUSE_WORDS, boundary_points, run_pose, trace_figure
from mdle.view.plot_curvature import measured_curvature, robust_limits

LEFT_PLAN = """\
atom follow_left = (follow_boundary(side = left, rc = 1 m, v = 1 m/s), never, 22 s)
plan main = ((follow_left), never, inf)
run main
"""


@pytest.fixture(scope="module")
def left_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Trace, Any]:
    """A real run following the ellipse with the boundary on the robot's left."""
    from mdle import sim

    d = tmp_path_factory.mktemp("left")
    plan = d / "left.mdle"
    plan.write_text(LEFT_PLAN)
    trace = d / "left.jsonl"
    assert main(["run", str(plan), "--world", "ellipse", "--start=-9,-0.3,0", "--quiet",
                 "--rate", "20", "--trace", str(trace)]) == 0
    return read_trace(trace), sim.load_world("ellipse")


def test_left_side_boundary_is_drawn_on_the_obstacle(left_run: tuple[Trace, Any]) -> None:
    trace, world = left_run
    bearing = trace.column("diag.side_bearing")[trace.column("diag.side_hit") > 0.5]
    # where the nearest boundary point followed lies: on the left, about abeam when following
    assert len(bearing) and (bearing > 0).mean() > 0.95
    assert np.median(bearing) == pytest.approx(math.pi / 2, abs=0.1)
    x, y, th, truth = run_pose(trace, world)
    assert truth
    pts = boundary_points(trace, (x, y, th))
    assert len(pts) > 100
    # every detected point lies on the ellipse (the scan's noise aside), none in free space
    d = world.nearest_boundary(pts).distance
    assert np.median(d) < 0.03 and np.percentile(d, 95) < 0.1


def test_left_side_curvature_is_drawn_convex_negative_beside_the_truth(
        left_run: tuple[Trace, Any]) -> None:
    trace, world = left_run
    k = measured_curvature(trace)
    assert k is not None and np.nanmedian(k.values) < -0.1  # the ellipse is convex
    fig = trace_figure(trace, world)
    axk = fig.axes[1]
    assert "convex negative" in axk.get_ylabel() and "1/m" in axk.get_ylabel()
    [truth] = [ln for ln in axk.lines if ln.get_label() == "truth at the nearest point"]
    t = np.asarray(truth.get_ydata(), dtype=float)
    # the ellipse's true curvature at the nearest point: between -a/b^2 and -b/a^2
    assert len(t) > 50 and t.max() < -0.1 and t.min() > -1.05


def _spiky(ir: SimpleNamespace, tmp_path: Path) -> Path:
    """A run whose measured curvature is small, with two huge spikes."""

    def step(args: Any, ctx: Context, state: Any) -> Command:
        k = -0.3 + 0.05 * math.sin(ctx.t * 7)
        if abs(ctx.t - 1.0) < 0.005:
            k = -15.0
        if abs(ctx.t - 2.0) < 0.005:
            k = 12.0
        ctx.cache["trace"] = {"side_hit": 1.0, "side_range": 0.5, "side_curvature": k}
        return Command(0.5, 0.1)

    element = ir.atom("follow", law=ir.const_law("follow_boundary", step=step), timer=3.0)
    path = tmp_path / "spiky.jsonl"
    run(element, ScriptedBackend(()), rate=100,
        observers=[TraceWriter(path, {"robot": "pioneer2dx"})])
    return path


def test_curvature_spikes_are_clipped_and_marked(ir: SimpleNamespace, tmp_path: Path) -> None:
    fig = trace_figure(read_trace(_spiky(ir, tmp_path)))
    axk = fig.axes[1]
    lo, hi = axk.get_ylim()
    assert -1.5 < lo < -0.35 and -0.25 < hi < 1.5  # the signal fills the panel
    marks = [ln for ln in axk.lines if str(ln.get_label()).startswith("beyond the axis")]
    assert marks and "(2 values)" in str(marks[0].get_label())


def test_robust_limits_keep_the_truth_in_view() -> None:
    lo, hi = robust_limits(np.zeros(100), np.array([-2.0, 0.5]))
    assert lo < -2.0 and hi > 0.5


def test_legend_sits_beside_the_path_and_robot_marks_are_drawn(ir: SimpleNamespace,
                                                               tmp_path: Path) -> None:
    from matplotlib.patches import Circle
    from matplotlib.quiver import Quiver

    fig = trace_figure(read_trace(_spiky(ir, tmp_path)))
    fig.canvas.draw()
    ax = fig.axes[0]
    legend = ax.get_legend()
    assert legend is not None
    assert legend.get_window_extent().x0 >= ax.get_window_extent().x1
    circles = [p for c in ax.collections for p in getattr(c, "get_paths", lambda: [])()]
    assert any(isinstance(c, Quiver) for c in ax.collections)
    assert circles  # the pioneer's footprint (radius 0.25 m) along the path
    labels = ax.get_legend_handles_labels()[1]
    assert any(lab.startswith("robot and heading, every") for lab in labels)
    assert not any(isinstance(p, Circle) for p in ax.patches)  # footprints are one collection


def test_doors_are_drawn_and_a_long_scene_is_stretched(ir: SimpleNamespace,
                                                       tmp_path: Path) -> None:
    from mdle import sim

    world = sim.load_world("corridor")
    def script(t: float, k: int) -> dict[str, Any]:
        return {"truth": {"x": 0.5 * t, "y": -0.45, "theta": 0.0, "clearance": 0.3,
                          "collided": False}}

    path = tmp_path / "c.jsonl"
    run(ir.atom("go", 0.5, timer=2.0), ScriptedBackend(script),
        observers=[TraceWriter(path, {})])
    fig = trace_figure(read_trace(path), world)
    ax = fig.axes[0]
    labels = ax.get_legend_handles_labels()[1]
    assert labels.count("door") == 1
    doors = [p for p in ax.patches if p.get_label() == "door"]
    assert doors
    assert "taller" in ax.get_ylabel() and float(ax.get_aspect()) > 2.0


def test_a_timer_mark_stays_visible_inside_its_strings_end(ir: SimpleNamespace,
                                                          tmp_path: Path) -> None:
    path = tmp_path / "t.jsonl"
    run(ir.string("main", ir.atom("go", 1.0, timer=0.5)), ScriptedBackend(()),
        observers=[TraceWriter(path, {})])
    ax = trace_figure(read_trace(path)).axes[0]
    marks = {ln.get_label(): ln for ln in ax.lines}
    timer = marks["end: " + CAUSE_WORDS["timer"]]
    done = marks["end: " + CAUSE_WORDS["completed"]]
    assert timer.get_zorder() > done.get_zorder()
    assert timer.get_markersize() < done.get_markersize()
    assert done.get_markerfacecolor() == "none"


def test_worlds_show_title_is_not_doubled(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    from mdle.cli.worlds import world_title

    world = types.SimpleNamespace(name="default", description="Default: a 12 m room")
    assert world_title(world) == "default: a 12 m room"
    world = types.SimpleNamespace(name="corridor", description="Paper experiment: corridor")
    assert world_title(world) == "corridor: Paper experiment: corridor"
