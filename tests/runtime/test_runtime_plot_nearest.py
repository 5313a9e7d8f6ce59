"""The whole-scan model's curvature panel: what the model used, beside the true nearest point.

Real runs of the paper's plans, drawn as docs/figures/make_figures.py draws them.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mdle.atoms.closest import POINT_KAPPA
from mdle.cli import main
from mdle.record.trace import Trace
from mdle.view.plot import trace_and_world, trace_figure
from mdle.view.plot_nearest import (
    NearestPanel,
    followed_side,
    is_nearest_point_trace,
    nearest_measured,
    nearest_truth,
)

ROOT = Path(__file__).resolve().parents[2]


def _run(tmp: Path, plan: Path, *args: str) -> tuple[Trace, Any]:
    trace = tmp / "run.jsonl"
    assert main(["run", str(plan), *args, "--quiet", "--trace", str(trace)]) == 0
    return trace_and_world(trace)


@pytest.fixture(scope="module")
def u_exact(tmp_path_factory: pytest.TempPathFactory) -> tuple[Trace, Any]:
    """Figure 3's run: the U followed on the right with exact sensing, 100 Hz."""
    return _run(tmp_path_factory.mktemp("u"), ROOT / "plans/paper/fig3-u-shape.mdle",
                "--rate", "100", "--sensing", "exact")


def test_figure_3_exact_has_a_tenth_axis_with_every_corner_off_it(
        u_exact: tuple[Trace, Any]) -> None:
    trace, world = u_exact
    assert is_nearest_point_trace(trace)
    fig = trace_figure(trace, world)
    axk = fig.axes[1]
    assert "nearest point" in axk.get_title()
    lo, hi = axk.get_ylim()
    assert lo == pytest.approx(-0.1) and hi == pytest.approx(0.1)  # straight faces: 0 +- 0.1
    labels = {str(ln.get_label()): ln for ln in axk.lines}
    truth = np.asarray(labels["truth at the nearest point"].get_ydata(), dtype=float)
    assert set(truth[np.isfinite(truth)].tolist()) == {0.0}  # a polygon: 0 on every face
    [points] = [ln for name, ln in labels.items() if name.startswith("model: a point")]
    [corners] = [ln for name, ln in labels.items() if name.startswith("truth: a corner")]
    # the clamped ticks and the true corners are marked inside the axis, at its bottom
    for line in (points, corners):
        y = np.asarray(line.get_ydata(), dtype=float)
        assert len(y) > 10 and (y > lo).all() and (y < lo + 0.2 * (hi - lo)).all()
    panel = NearestPanel(nearest_measured(trace).values,  # type: ignore[union-attr]
                         nearest_truth(trace, world), exact=True)
    assert f"({int(panel.point.sum())} ticks)" in str(points.get_label())
    # the U has 8 corners (two concave, never nearest): the run passes convex ones many times
    assert panel.episodes(panel.corner) >= 8
    # every dip is off the axis: a tick whose value left the axis is marked, none is drawn
    model = np.asarray(labels["model (exact scan)"].get_ydata(), dtype=float)
    off = np.isfinite(model) & ((model < lo) | (model > hi))
    assert off.sum() == panel.under.sum() + panel.over.sum() > 0
    assert (panel.measured[panel.point] == POINT_KAPPA).all()


def test_the_model_takes_a_point_mostly_where_the_truth_is_a_corner(
        u_exact: tuple[Trace, Any]) -> None:
    trace, world = u_exact
    panel = NearestPanel(nearest_measured(trace).values,  # type: ignore[union-attr]
                         nearest_truth(trace, world), exact=True)
    near_corner = np.convolve(panel.corner.astype(float), np.ones(41), "same") > 0
    assert panel.point.sum() > 50
    assert (panel.point & near_corner).mean() / panel.point.mean() > 0.75  # within 0.2 s


def test_a_left_run_is_judged_left_and_drawn_convex_negative(tmp_path: Path) -> None:
    trace, world = _run(tmp_path, ROOT / "plans/paper/fig2-hexagon.mdle", "--rate", "50",
                        "--plan", "mirrored", "--until", "20")
    atom = np.array([p.endswith("/follow_left") for p in trace.paths()])
    assert atom.sum() > 900 and (followed_side(trace)[atom] == 1.0).all()
    measured = nearest_measured(trace)
    assert measured is not None
    k = measured.values[np.isfinite(measured.values)]
    # a convex hexagon: faces near 0, vertices taken as points at -100 (never +100)
    assert (k == POINT_KAPPA).any() and not (k == -POINT_KAPPA).any()


def test_a_two_ray_trace_keeps_the_side_ray_panel(tmp_path: Path) -> None:
    plan = tmp_path / "rays.mdle"
    plan.write_text((ROOT / "plans/paper/fig2-hexagon.mdle").read_text("utf-8")
                    .replace("v = 1 m/s)", "v = 1 m/s, model = rays)"))
    trace, world = _run(tmp_path, plan, "--world", str(ROOT / "plans/paper/fig2-hexagon."
                                                           "world.yaml"),
                        "--rate", "50", "--until", "20")
    assert not is_nearest_point_trace(trace)
    assert trace_figure(trace, world).axes[1].get_title() == "boundary curvature at the side ray"


def test_the_left_plot_keeps_its_curvature_label_on_the_canvas(tmp_path: Path) -> None:
    """The hexagon followed on the left with the two rays: its label was cut (issue 25)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    plan = tmp_path / "rays.mdle"
    plan.write_text((ROOT / "plans/paper/fig2-hexagon.mdle").read_text("utf-8")
                    .replace("v = 1 m/s)", "v = 1 m/s, model = rays)"))
    trace, world = _run(tmp_path, plan, "--world", str(ROOT / "plans/paper/fig2-hexagon."
                                                           "world.yaml"),
                        "--rate", "50", "--plan", "mirrored")
    fig = trace_figure(trace, world)
    canvas = FigureCanvasAgg(fig)
    fig.savefig(io.BytesIO(), format="png", dpi=100)  # as make_figures.py writes it
    renderer = canvas.get_renderer()
    for ax in fig.axes:
        box = ax.yaxis.label.get_window_extent(renderer)
        assert box.x0 >= 0.0, f"{ax.get_ylabel()!r} starts {box.x0:.1f} px off the canvas"
