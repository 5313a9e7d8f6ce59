"""Hostile traces: mutated real traces (hypothesis) and a seeded corpus of damaged files.
`read_trace` returns a trace or raises TraceError; `mdle plot` draws it or says what is
wrong (exit 0 or 1), never an internal error."""

from __future__ import annotations

import io
import json
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mdle.cli import main
from mdle.core.errors import MdleError
from mdle.record.load import read_trace
from mdle.record.trace import TraceError
from mdle.view.plot import trace_figure
from tests.fuzz.conftest import examples

CORPUS = Path(__file__).parent / "corpus" / "traces"
PLAN = """\
atom a = (arc(0.3 m/s, 20 deg/s), never, 0.6 s)
atom b = (follow_boundary(side = right, rc = 1 m, v = 0.3 m/s), never, 0.6 s)
plan main = ((a, b), never, inf)
run main
"""


@pytest.fixture(scope="module")
def real(tmp_path_factory: pytest.TempPathFactory) -> bytes:
    """A real trace: two atoms (one with diagnostics) in a world with obstacles."""
    d = tmp_path_factory.mktemp("real")
    (d / "p.mdle").write_text(PLAN)
    assert main(["run", str(d / "p.mdle"), "--world", "default", "-q", "--trace",
                 str(d / "t.jsonl")]) == 0
    return (d / "t.jsonl").read_bytes()


JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False)
    | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=4), inner,
                                                                 max_size=3),
    max_leaves=6)


@st.composite
def mutated(draw: st.DrawFn, data: bytes) -> bytes:
    """The real trace with a few damages: flipped bytes, lost, repeated or cut lines, a
    field set to a value of any JSON type."""
    lines = data.splitlines(keepends=True)
    for _ in range(draw(st.integers(1, 3))):
        what = draw(st.sampled_from(["flip", "drop", "repeat", "cut", "field", "swap"]))
        i = draw(st.integers(0, len(lines) - 1))
        if what == "flip" and lines[i]:
            j = draw(st.integers(0, len(lines[i]) - 1))
            b = bytearray(lines[i])
            b[j] = draw(st.integers(0, 255))
            lines[i] = bytes(b)
        elif what == "drop" and len(lines) > 1:
            del lines[i]
        elif what == "repeat":
            lines.insert(i, lines[i])
        elif what == "cut":
            lines = lines[:i] + [lines[i][: draw(st.integers(0, len(lines[i])))]]
        elif what == "swap":
            k = draw(st.integers(0, len(lines) - 1))
            lines[i], lines[k] = lines[k], lines[i]
        else:
            try:
                rec = json.loads(lines[i])
            except ValueError:
                continue
            if isinstance(rec, dict) and rec:
                key = draw(st.sampled_from(sorted(rec)))
                rec[key] = draw(JSON_VALUES)
                lines[i] = json.dumps(rec).encode() + b"\n"
    return b"".join(lines)


def _read(tmp: Path, data: bytes) -> object:
    path = tmp / "t.jsonl"
    path.write_bytes(data)
    try:
        return read_trace(path)
    except TraceError:
        return None


@settings(max_examples=examples(150), deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_mutated_traces_read_or_fail_with_a_message(
        real: bytes, tmp_path: Path, data: st.DataObject) -> None:
    trace = _read(tmp_path, data.draw(mutated(real)))
    if trace is not None:
        for name in ("x", "y", "t", "diag.side_range"):
            trace.column(name)  # type: ignore[attr-defined]


@settings(max_examples=examples(20), deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_mutated_traces_plot_or_fail_with_a_message(
        real: bytes, tmp_path: Path, data: st.DataObject) -> None:
    trace = _read(tmp_path, data.draw(mutated(real)))
    if trace is None:
        return
    try:
        fig = trace_figure(trace)  # type: ignore[arg-type]
    except MdleError:
        return
    fig.savefig(io.BytesIO(), format="png", dpi=40)


@pytest.mark.parametrize("path", sorted(CORPUS.glob("*.jsonl")), ids=lambda p: p.name)
def test_the_corpus_of_damaged_traces(path: Path, tmp_path: Path,
                                      capsys: pytest.CaptureFixture[str],
                                      recwarn: pytest.WarningsRecorder) -> None:
    code = main(["plot", str(path), "-o", str(tmp_path / "p.png")])
    err = capsys.readouterr().err
    assert code in (0, 1), err
    assert "internal error" not in err
    # a library's warning would reach the user's terminal with its source line
    assert not [str(w.message) for w in recwarn], path.name
    if code == 1:
        assert str(path) in err  # the message names the file


def test_the_corpus_is_there() -> None:
    assert len(list(CORPUS.glob("*.jsonl"))) >= 8
