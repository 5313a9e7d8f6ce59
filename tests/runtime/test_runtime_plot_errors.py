"""`mdle plot` on damaged traces and unwritable outputs: a message with the place, exit 1,
never an internal error (exit 70)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mdle.cli import main

PLAN = "atom a = (arc(0.3 m/s, 20 deg/s), never, 2 s)\nrun a\n"


@pytest.fixture(scope="module")
def good(tmp_path_factory: pytest.TempPathFactory) -> bytes:
    """The bytes of a real trace (a 2 s run in the empty world)."""
    d = tmp_path_factory.mktemp("trace")
    (d / "p.mdle").write_text(PLAN)
    assert main(["run", str(d / "p.mdle"), "--world", "empty", "-q", "--trace",
                 str(d / "t.jsonl")]) == 0
    return (d / "t.jsonl").read_bytes()


def _plot(tmp_path: Path, data: bytes, capsys: pytest.CaptureFixture[str],
          out: str = "p.png") -> tuple[int, str]:
    trace = tmp_path / "t.jsonl"
    trace.write_bytes(data)
    code = main(["plot", str(trace), "-o", str(tmp_path / out)])
    return code, capsys.readouterr().err


def _edit(data: bytes, kind: str, **fields: object) -> bytes:
    """Set ``fields`` in every record of type ``kind``."""
    lines = []
    for line in data.splitlines():
        rec = json.loads(line)
        if rec["type"] == kind:
            rec.update(fields)
        lines.append(json.dumps(rec).encode())
    return b"\n".join(lines) + b"\n"


def test_the_real_trace_plots(tmp_path: Path, good: bytes,
                              capsys: pytest.CaptureFixture[str]) -> None:
    code, err = _plot(tmp_path, good, capsys)
    assert code == 0, err
    assert (tmp_path / "p.png").read_bytes().startswith(b"\x89PNG")
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


@pytest.mark.parametrize("edit, message", [
    (lambda d: d.replace(b'"sample"', b'"sam\xffple"', 1), ":1: error: not UTF-8 text (byte 0xff"),
    (lambda d: _edit(d, "header", version="1"), "`version` of the header record must be a "
                                                "whole number"),
    (lambda d: _edit(d, "header", version=1.5), "whole number"),
    (lambda d: _edit(d, "header", world={"spec": 7}), "`world.spec` of the header record"),
    (lambda d: _edit(d, "header", seed="zero"), "`seed` of the header record"),
    (lambda d: _edit(d, "sample", x="abc"), "`x` of the sample record must be a number"),
    (lambda d: _edit(d, "sample", diag={"side_range": "far"}), "`diag.side_range`"),
    (lambda d: _edit(d, "event", t=[1]), "`t` of the event record must be a number"),
    (lambda d: _edit(d, "end", duration={}), "`duration` of the end record"),
    (lambda d: _edit(d, "sample", x=None, true_x=None), "no sample with a finite position"),
    (lambda d: d.replace(b'{"type":"sample"', b'[' * 100_000, 1), "nested too deeply"),
])
def test_damaged_traces_are_messages_with_a_place(
        tmp_path: Path, good: bytes, capsys: pytest.CaptureFixture[str],
        edit: object, message: str) -> None:
    code, err = _plot(tmp_path, edit(good), capsys)  # type: ignore[operator]
    assert code == 1, err
    assert message in err and "internal error" not in err


def test_a_non_utf8_byte_in_a_cut_off_last_line_is_a_cut_trace(
        tmp_path: Path, good: bytes, capsys: pytest.CaptureFixture[str]) -> None:
    code, err = _plot(tmp_path, good.rstrip(b"\n")[:-5] + b"\xe2\x82", capsys)
    assert code == 0, err


def test_an_output_that_cannot_be_written_is_refused_before_drawing(
        tmp_path: Path, good: bytes, capsys: pytest.CaptureFixture[str]) -> None:
    code, err = _plot(tmp_path, good, capsys, out="missing/p.png")
    assert code == 1 and "-o" in err and "no folder" in err
    (tmp_path / "d.svg").mkdir()
    code, err = _plot(tmp_path, good, capsys, out="d.svg")
    assert code == 1 and "is a folder" in err
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        code, err = _plot(tmp_path, good, capsys, out="ro/p.png")
        if code == 0:  # root writes anywhere: then the plot must have been written
            assert (ro / "p.png").exists()
        else:
            assert code == 1 and "cannot be created" in err
    finally:
        ro.chmod(0o700)


def test_a_plot_that_fails_while_written_leaves_no_partial_file(
        tmp_path: Path, good: bytes, monkeypatch: pytest.MonkeyPatch) -> None:
    import errno

    from matplotlib.figure import Figure

    from mdle.view.figure_output import PlotError
    from mdle.view.plot import plot_trace

    def full(self: Figure, *args: object, **kwargs: object) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    (tmp_path / "t.jsonl").write_bytes(good)
    monkeypatch.setattr(Figure, "savefig", full)
    with pytest.raises(PlotError, match="cannot write the plot .*No space left"):
        plot_trace(tmp_path / "t.jsonl", tmp_path / "p.png")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.jsonl"]


def test_a_sample_without_a_heading_draws_no_boundary_point_and_the_rest_plots(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Found by the fuzz tier: a following sample whose `theta` key was damaged gave its
    boundary point a NaN, and the figure a NaN height (an internal error)."""
    (tmp_path / "p.mdle").write_text(
        "atom f = (follow_boundary(rc = 1 m, v = 0.3 m/s), never, 1.5 s)\nrun f\n")
    assert main(["run", str(tmp_path / "p.mdle"), "--world", "default", "-q", "--trace",
                 str(tmp_path / "run.jsonl")]) == 0
    lines = []
    damaged = 0
    for line in (tmp_path / "run.jsonl").read_bytes().splitlines():
        rec = json.loads(line)
        if rec["type"] == "sample" and "diag" in rec and not damaged:
            rec[" heta"] = rec.pop("theta")
            rec.pop("true_theta", None)
            damaged += 1
        lines.append(json.dumps(rec).encode())
    assert damaged
    code, err = _plot(tmp_path, b"\n".join(lines) + b"\n", capsys)
    assert code == 0, err
    assert (tmp_path / "p.png").read_bytes().startswith(b"\x89PNG")
