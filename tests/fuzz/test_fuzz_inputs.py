"""Hostile input on every file surface ends in an MdleError, never anything else.

A seeded corpus of hostile files (``corpus/``: plans, worlds, traces, raw bytes) is
read through the same functions the commands use, and hypothesis mutates worlds and
byte streams. Any exception other than :class:`~mdle.core.errors.MdleError` (a RecursionError,
OverflowError, OSError, UnicodeDecodeError...) fails; so does a message without a place
where the corpus file says where. The example counts keep the suite well under a
minute.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as hs

from mdle.core.errors import MdleError, render_diagnostic
from mdle.lang import load_program, read_source
from mdle.record.load import read_trace
from mdle.sim.world_yaml import parse_world, read_world
from tests.fuzz.conftest import examples

CORPUS = Path(__file__).resolve().parent / "corpus"
FILES = sorted(CORPUS.iterdir())


def _only_mdle_errors(path: Path) -> MdleError | None:
    """Read ``path`` as the commands would; return the MdleError it raised, if any."""
    try:
        if path.suffix == ".mdle":
            load_program(path)
        elif path.suffix == ".yaml":
            read_world(path)
        else:
            trace = read_trace(path)
            from mdle.view.plot import world_of

            world_of(trace)  # the world a header names is read safely, or skipped
    except MdleError as err:
        for d in err.diagnostics:
            render_diagnostic(d, err.sources)
        return err
    return None


@pytest.mark.parametrize("path", FILES, ids=[p.name for p in FILES])
def test_corpus_file_gives_a_message_or_loads(path: Path) -> None:
    err = _only_mdle_errors(path)
    if path.name.startswith(("plan_", "world_")) and err is not None:
        assert any(d.span is not None and d.span.line >= 1 for d in err.diagnostics), err


def test_corpus_covers_every_surface() -> None:
    kinds = {p.name.split("_")[0] for p in FILES}
    assert {"plan", "world", "trace", "bytes"} <= kinds
    assert len(FILES) >= 25


_YAML_PIECES = ["obstacles:", "\n  - ", "{type: circle, center: [0, 0], radius: 1}", "&a ",
                "*a", "[", "]", "{", "}", ": ", "- ", "1e308", "9" * 400, "name: ", "start: ",
                "ladar: ", "robot: ", "{rate: 5}", "? ", "!!python/object:os.system",
                "\t", "\n", "x", ",", "'", '"', "-1", "nan", ".inf", "~", "seed: "]


@settings(max_examples=examples(120), deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(hs.lists(hs.sampled_from(_YAML_PIECES), max_size=40).map("".join))
def test_world_token_soup(text: str) -> None:
    try:
        parse_world(text, file="fuzz.yaml")
    except MdleError as err:
        for d in err.diagnostics:
            render_diagnostic(d, err.sources)


@settings(max_examples=examples(80), deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(hs.binary(max_size=400), hs.sampled_from(["plan.mdle", "world.yaml"]))
def test_random_bytes_on_every_file_reader(tmp_path_factory: pytest.TempPathFactory,
                                           data: bytes, name: str) -> None:
    path = tmp_path_factory.mktemp("bytes") / name
    path.write_bytes(data)
    if name.endswith(".mdle"):
        try:
            read_source(path)
        except MdleError:
            pass
    _only_mdle_errors(path)
