"""Hostile option values for `mdle run` (hypothesis): every combination ends in a message
and a documented exit code (0 done, 1 input, 2 usage, 3 collision), never an internal
error. (Robot and laser URLs are fuzzed with the drivers, tests/drivers.)"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mdle.cli import main
from tests.fuzz.conftest import examples

PLAN = "atom a = (arc(0.3 m/s, 20 deg/s), never, 1 s)\nplan main = ((a), never, 2 s)\nrun main\n"

NUMBERS = st.one_of(st.sampled_from(["-1", "0", "1", "1e308", "-1e308", "inf", "-inf", "nan",
                                     "0x10", "1_000", "", " ", "1.5", "2**40",
                                     "4294967296", "99999999999999999999999"]),
                    st.floats().map(repr), st.integers(-2**64, 2**64).map(str),
                    st.text(max_size=6))
OPTIONS = st.sampled_from(["--seed", "--rate", "--until", "--world", "--plan", "--robot",
                           "--sensing", "--laser", "--plot", "--trace"])


@settings(max_examples=examples(40), deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(pairs=st.lists(st.tuples(OPTIONS, NUMBERS), min_size=1, max_size=3))
def test_run_options_end_in_a_documented_code(
        pairs: list[tuple[str, str]], tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.chdir(tmp_path)
    plan = tmp_path / "p.mdle"
    plan.write_text(PLAN)
    argv = ["run", str(plan), "--world", "empty", "-q", "--until", "0.5"]
    for option, value in pairs:
        argv += [f"{option}={value}"]
    code = main(argv)
    err = capsys.readouterr().err
    assert code in (0, 1, 2, 3), (argv, code, err)
    assert "internal error" not in err and "Traceback" not in err, (argv, err)


@pytest.mark.parametrize("option", ["--trace", "--plot", "--world", "--plan", "--robot"])
def test_a_nul_in_a_file_name_is_an_input_error(
        option: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.chdir(tmp_path)
    plan = tmp_path / "p.mdle"
    plan.write_text(PLAN)
    code = main(["run", str(plan), "--world", "empty", "-q", "--until", "0.5", f"{option}=a\x00b"])
    err = capsys.readouterr().err
    assert code in (1, 2) and "internal error" not in err, err
