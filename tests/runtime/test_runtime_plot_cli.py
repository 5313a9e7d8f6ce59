"""`mdle plot` and `mdle worlds show` without -o (a window, or NAME.png here), several traces
overlaid, and `--animate` to a GIF (an MP4 without ffmpeg is a clear message)."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from mdle.cli import main
from mdle.record.load import read_trace
from mdle.record.trace import TraceWriter
from mdle.runtime import run
from mdle.runtime.scripted import ScriptedBackend
from mdle.view import figure_output
from mdle.view.plot_overlay import overlay_figure


def _trace(ir: SimpleNamespace, path: Path, v: float = 1.0, rc: float | None = None) -> Path:
    """A short scripted run with ground truth (and an rc, like follow_boundary records)."""

    def step(args: Any, ctx: Any, state: Any) -> Any:
        from mdle.core.backend import Command

        if rc is not None:
            ctx.cache["trace"] = {"rc": rc}
        return Command(v, 0.4)

    law = ir.const_law("follow", step=step)
    def script(t: float, k: int) -> dict[str, Any]:
        return {"truth": {"x": v * t, "y": 0.1 * t, "theta": 0.1,
                          "clearance": 0.6 + 0.1 * t, "collided": False}}

    run(ir.atom("follow", law=law, timer=2.0), ScriptedBackend(script),
        observers=[TraceWriter(path, {})])
    return path


@pytest.fixture
def no_display(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(figure_output.sys, "platform", "linux")
    here = tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    return here


def test_plot_without_output_and_no_display_writes_name_png_here(
        ir: SimpleNamespace, tmp_path: Path, no_display: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    trace = _trace(ir, tmp_path / "run7.jsonl")
    assert main(["plot", str(trace)]) == 0
    out = no_display / "run7.png"
    assert out.read_bytes()[:4] == b"\x89PNG"
    assert f"no display: plot written to {out}" in capsys.readouterr().out


def test_worlds_show_without_output_writes_name_png_here(
        no_display: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["worlds", "show", "hexagon", "--no-scan"]) == 0
    assert (no_display / "hexagon.png").read_bytes()[:4] == b"\x89PNG"
    assert str(no_display / "hexagon.png") in capsys.readouterr().out


def test_with_a_display_the_figure_opens_in_a_window(
        ir: SimpleNamespace, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    shown: list[str] = []
    monkeypatch.setenv("DISPLAY", ":0")
    monkeypatch.setattr(figure_output, "open_window", lambda fig, title: shown.append(title))
    monkeypatch.chdir(tmp_path)
    assert main(["plot", str(_trace(ir, tmp_path / "r.jsonl"))]) == 0
    assert shown == ["r"] and not (tmp_path / "r.png").exists()
    assert "shown in a window" in capsys.readouterr().out


def test_a_window_that_cannot_open_falls_back_to_a_file(tmp_path: Path,
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    from matplotlib.figure import Figure

    def fail(fig: Any, title: str) -> None:
        raise figure_output.WindowError("no Tk")

    monkeypatch.chdir(tmp_path)
    line = figure_output.show_or_write(Figure(), "w", display=True, window=fail)
    assert line.startswith("cannot open a window (no Tk): plot written to")
    assert (tmp_path / "w.png").exists()


def test_open_window_refuses_a_file_only_backend(monkeypatch: pytest.MonkeyPatch) -> None:
    import matplotlib
    from matplotlib.figure import Figure

    monkeypatch.setattr(matplotlib, "get_backend", lambda: "agg")
    with pytest.raises(figure_output.WindowError, match="cannot open a window"):
        figure_output.open_window(Figure(), "x")


def test_several_traces_are_overlaid(ir: SimpleNamespace, tmp_path: Path,
                                     capsys: pytest.CaptureFixture[str]) -> None:
    a = _trace(ir, tmp_path / "a.jsonl", 1.0, rc=0.5)
    b = _trace(ir, tmp_path / "b.jsonl", 0.5, rc=0.5)
    out = tmp_path / "both.png"
    assert main(["plot", str(a), str(b), "-o", str(out)]) == 0
    assert out.read_bytes()[:4] == b"\x89PNG"
    fig = overlay_figure([(read_trace(a), None), (read_trace(b), None)])
    path_ax, err_ax = fig.axes
    labels = path_ax.get_legend_handles_labels()[1]
    assert labels[:2] == ["a.jsonl", "b.jsonl"]
    assert err_ax.get_ylabel() == "following error |d - rc| (m, log)"
    assert [ln.get_label() for ln in err_ax.lines] == ["a.jsonl", "b.jsonl"]


def test_animate_writes_a_gif(ir: SimpleNamespace, tmp_path: Path,
                              capsys: pytest.CaptureFixture[str]) -> None:
    from PIL import Image

    out = tmp_path / "run.gif"
    assert main(["plot", str(_trace(ir, tmp_path / "r.jsonl")), "--animate", str(out)]) == 0
    with Image.open(out) as im:
        assert getattr(im, "n_frames", 1) > 5
    assert "animation written to" in capsys.readouterr().out
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_animate_mp4_without_ffmpeg_says_so(ir: SimpleNamespace, tmp_path: Path,
                                            monkeypatch: pytest.MonkeyPatch,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    from matplotlib import animation

    monkeypatch.setattr(animation.writers, "is_available", lambda name: False)
    out = tmp_path / "run.mp4"
    assert main(["plot", str(_trace(ir, tmp_path / "r.jsonl")), "--animate", str(out)]) == 1
    err = capsys.readouterr().err
    assert "needs ffmpeg" in err and "run.gif" in err and not out.exists()
    assert main(["plot", str(tmp_path / "r.jsonl"), "--animate", str(tmp_path / "x.avi")]) == 1
    assert ".gif or .mp4" in capsys.readouterr().err
