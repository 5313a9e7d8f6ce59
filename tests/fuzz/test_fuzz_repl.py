"""Hostile REPL input: random lines and commands with random arguments (hypothesis), random
bytes on a piped stdin, and a seeded corpus. The REPL answers every line (True or False)
and never reports an internal error; the session goes on."""

from __future__ import annotations

import io
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mdle.repl.commands import COMMANDS, Repl
from mdle.repl.plain import run_plain
from mdle.repl.session import Session
from tests.fuzz.conftest import examples

CORPUS = Path(__file__).parent / "corpus" / "repl"

WORDS = st.sampled_from([
    "atom", "behavior", "plan", "interrupt", "run", "never", "inf", "and", "or", "not", "go",
    "turn", "arc", "follow_boundary", "range", "stalled", "t", "x", "a", "main", "(", ")",
    ",", "=", "...", "m/s", "deg", "1", "-1", "0", "1e308", "nan", "inf", "-inf", "1 m",
    "2 s", "0.3 m/s", "#", '"', "'", "\\", "seed", "until", "realtime", "on", "/dev/zero",
    "/nonexistent/x", "99999999999999999999", "\x00", "\u2028", "\x0c", "\udcff"])
ARGS = st.one_of(WORDS, st.text(max_size=10), st.floats().map(repr),
                 st.integers(-2**70, 2**70).map(str))
FILE_COMMANDS = {"save", "trace", "plot"}  # they write files: given names inside tmp


@st.composite
def lines(draw: st.DrawFn) -> str:
    kind = draw(st.sampled_from(["command", "words", "text"]))
    if kind == "command":
        name = draw(st.sampled_from(sorted(COMMANDS)))
        args = draw(st.lists(ARGS, max_size=3))
        if name in FILE_COMMANDS:
            args = [f"out.{draw(st.sampled_from(['png', 'svg', 'mdle', 'jsonl', 'gif']))}"]
        return ":" + " ".join([name, *args])
    if kind == "words":
        return " ".join(draw(st.lists(WORDS, min_size=1, max_size=12)))
    return draw(st.text(max_size=40))


@pytest.fixture(scope="module")
def repl() -> tuple[Repl, io.StringIO, io.StringIO]:
    out, err = io.StringIO(), io.StringIO()
    r = Repl(Session("empty", until=1.0), out, err)
    assert r.handle("atom a = (go(0.3 m/s), never, 0.5 s)")
    return r, out, err


@settings(max_examples=examples(80), deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(text=lines())
def test_random_lines_never_break_the_session(
        repl: tuple[Repl, io.StringIO, io.StringIO], text: str, tmp_path: Path,
        monkeypatch: pytest.MonkeyPatch) -> None:
    r, out, err = repl
    monkeypatch.chdir(tmp_path)  # :save, :trace, :plot write here
    r.quit_requested = False
    r.session.until = 1.0 if r.session.until is None or r.session.until > 1.0 \
        else r.session.until
    mark = err.tell()
    assert r.handle(text) in (True, False)
    assert "internal error" not in err.getvalue()[mark:], (text, err.getvalue()[mark:])
    r.handle("a")  # the session still takes input (a may have been redefined, or collide)
    assert "internal error" not in err.getvalue()[mark:], (text, err.getvalue()[mark:])


@settings(max_examples=examples(40), deadline=None)
@given(raw=st.lists(st.binary(max_size=30), max_size=6))
def test_random_bytes_on_a_piped_stdin(raw: list[bytes]) -> None:
    out, err = io.StringIO(), io.StringIO()
    r = Repl(Session("empty", until=1.0), out, err)
    text = b"\n".join([*raw, b"(go(0.3 m/s), never, 0.3 s)"]).decode("utf-8",
                                                                     "surrogateescape")
    code = run_plain(r, io.StringIO(text + "\n"))
    assert code in (0, 1)
    assert "internal error" not in err.getvalue()


@pytest.mark.parametrize("path", sorted(CORPUS.glob("*.txt")), ids=lambda p: p.name)
def test_the_corpus_of_hostile_sessions(path: Path, tmp_path: Path,
                                        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    out, err = io.StringIO(), io.StringIO()
    r = Repl(Session("empty", until=1.0), out, err)
    text = path.read_bytes().decode("utf-8", "surrogateescape")
    assert run_plain(r, io.StringIO(text)) in (0, 1)
    assert "internal error" not in err.getvalue(), err.getvalue()
