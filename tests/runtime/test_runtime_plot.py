"""Plots from traces: the path with obstacles or detected boundary, curvature vs distance."""

from __future__ import annotations

import math
import types
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from matplotlib.collections import LineCollection

from mdle.atoms.registry import Context
from mdle.core.backend import Command
from mdle.lang import AtomNode, Element
from mdle.record.load import read_trace
from mdle.record.trace import TraceWriter
from mdle.runtime import run
from mdle.runtime.scripted import ScriptedBackend
from mdle.view.figure_output import PlotError
from mdle.view.plot import boundary_points, plot_trace, trace_figure


def _wall_follower(ir: SimpleNamespace) -> AtomNode:
    """An atom driving an arc that records a side range and curvature like follow_boundary."""

    def step(args: Any, ctx: Context, state: Any) -> Command:
        ctx.cache["trace"] = {"side_hit": 1.0, "side_range": 0.5,
                              "side_curvature": -1.0 if ctx.t > 1.0 else 0.0}
        return Command(0.5, 0.3 if ctx.t > 1.0 else 0.0)

    return ir.atom("follow", law=ir.const_law("follow_boundary", step=step), timer=3.0)


def _traced(ir: SimpleNamespace, tmp_path: Path, element: Element,
            backend: ScriptedBackend | None = None, truth: bool = False) -> Path:
    path = tmp_path / "run.jsonl"
    if backend is None:
        script = (lambda t, k: {"truth": {"x": 0.5 * t, "y": 0.01, "theta": 0.0,
                                          "clearance": 0.4, "collided": False}}) if truth else ()
        backend = ScriptedBackend(script)
    run(element, backend, observers=[TraceWriter(path, {"program": {"element": element.label},
                                                        "world": {"name": "test"}})])
    return path


def test_boundary_points_lie_beside_the_path(ir: SimpleNamespace, tmp_path: Path) -> None:
    path = _traced(ir, tmp_path, _wall_follower(ir))
    pts = boundary_points(read_trace(path))
    # first second: driving along +x, the boundary 0.5 m to the right (y = -0.5)
    assert pts.shape[1] == 2 and len(pts) >= 10
    assert pts[:10, 1] == pytest.approx([-0.5] * 10)
    assert pts[:10, 0] == pytest.approx([0.05 * i for i in range(10)])


@pytest.mark.parametrize("ext", ["png", "svg", "pdf"])
def test_plot_is_written_in_each_format(ir: SimpleNamespace, tmp_path: Path, ext: str) -> None:
    trace = _traced(ir, tmp_path, ir.string("main", ir.atom("go", 1.0, timer=1.0),
                                            _wall_follower(ir)))
    out = tmp_path / f"plot.{ext}"
    assert plot_trace(trace, out) == str(out)
    data = out.read_bytes()
    assert len(data) > 2000
    magic = {"png": b"\x89PNG", "svg": b"<?xml", "pdf": b"%PDF"}[ext]
    assert data.startswith(magic)


def test_figure_has_curvature_panel_when_the_law_measured_it(ir: SimpleNamespace,
                                                             tmp_path: Path) -> None:
    fig = trace_figure(read_trace(_traced(ir, tmp_path, _wall_follower(ir))))
    path_ax, curv_ax = fig.axes
    assert curv_ax.get_xlabel() == "distance travelled (m)"
    dist, kappa = (np.asarray(a) for a in curv_ax.lines[0].get_data())
    assert dist[-1] == pytest.approx(1.5, abs=0.06) and min(kappa) == -1.0
    labels = path_ax.get_legend_handles_labels()[1]
    assert "atom follow" in labels and "detected boundary" in labels


def test_figure_without_curvature_has_one_panel_and_marks_events(ir: SimpleNamespace,
                                                                 tmp_path: Path) -> None:
    main = ir.string("main", ir.atom("go", 1.0, when="hit"), ir.atom("spin", 0, 1.0, timer=0.5))
    trace = _traced(ir, tmp_path, main, ScriptedBackend(ir.signals(30, hit=[5])))
    fig = trace_figure(read_trace(trace))
    assert len(fig.axes) == 1
    labels = fig.axes[0].get_legend_handles_labels()[1]
    assert {"atom go", "atom spin", "end: interrupt fired", "end: timer ran out",
            "end: string finished", "start"} <= set(labels)


def test_world_obstacles_are_drawn_and_truth_is_used(ir: SimpleNamespace, tmp_path: Path) -> None:
    import shapely

    geometry = shapely.GeometryCollection([shapely.box(0, -1, 3, -0.6),
                                           shapely.LineString([(0, 1), (3, 1)])])
    world = types.SimpleNamespace(geometry=geometry, bounds=(-0.5, -1.5, 3.5, 1.5), name="w")
    trace = _traced(ir, tmp_path, ir.atom("go", 1.0, timer=1.0), truth=True)
    fig = trace_figure(read_trace(trace), world)
    ax = fig.axes[0]
    assert len(ax.patches) == 1  # the box
    path_collection = ax.collections[0]
    assert isinstance(path_collection, LineCollection)
    path_line = path_collection.get_segments()
    assert path_line[0][0][1] == pytest.approx(0.01)  # true y, not odometry's 0
    x0, x1 = ax.get_xlim()
    # the obstacles and the path fill the panel (the world's free-space bounds may not)
    assert -0.5 < x0 < 0.0 and 3.0 < x1 < 3.5


def test_plot_errors_are_clear(ir: SimpleNamespace, tmp_path: Path) -> None:
    trace = _traced(ir, tmp_path, ir.atom("go", 1.0, timer=0.2))
    with pytest.raises(PlotError, match=r"must end in \.png, \.svg or \.pdf"):
        plot_trace(trace, tmp_path / "plot.gif")
    empty = tmp_path / "empty.jsonl"
    empty.write_text(trace.read_text().splitlines()[0] + "\n")
    with pytest.raises(PlotError, match="no samples"):
        plot_trace(empty, tmp_path / "x.png")
    assert not math.isnan(read_trace(trace).column("x")[0])


def test_first_collision_is_marked(ir: SimpleNamespace, tmp_path: Path) -> None:
    script = lambda t, k: {"truth": {"collided": k >= 3, "clearance": 0.0}}  # noqa: E731
    trace = _traced(ir, tmp_path, ir.atom("go", 1.0, timer=0.6), ScriptedBackend(script))
    ax = trace_figure(read_trace(trace)).axes[0]
    [star] = [ln for ln in ax.lines if ln.get_label() == "first collision"]
    assert np.asarray(star.get_xdata())[0] == pytest.approx(0.3)


def test_detected_boundary_is_drawn_where_the_obstacle_is(tmp_path: Path) -> None:
    # The plan's x, y, theta are odometry (0, 0, 0 at the start); the path is drawn from
    # the simulator's true pose: the boundary the law saw must be drawn in that frame too,
    # on the hexagon, not beside the odometry origin.
    import shapely

    from mdle import sim
    from mdle.lang import load_text

    world = sim.load_world("hexagon")
    program = load_text("atom f = (follow_boundary(side = right, rc = 0.5 m, v = 1 m/s), "
                        "never, 15 s)\nrun f\n")
    path = tmp_path / "hex.jsonl"
    run(program.elements["f"], sim.SimBackend(world, seed=3), rate=50.0,
        observers=[TraceWriter(path, {"program": {"element": "f"}, "world": {"name": "hexagon"}})])
    trace = read_trace(path)
    pts = boundary_points(trace, truth=True)
    assert len(pts) > 100
    obstacles = shapely.union_all([o.geometry() for o in world.obstacles]).boundary
    d = shapely.distance(obstacles, shapely.points(pts))
    assert float(np.median(d)) < 0.05  # on the boundary, up to the scan's noise
    odo = boundary_points(trace)  # the plan's frame: the start is the origin, far from it
    assert float(np.median(shapely.distance(obstacles, shapely.points(odo)))) > 1.0
