"""The generated random-starts study: pure runs, same rows whatever --jobs, and its CLI."""

from __future__ import annotations

import csv
import math
import subprocess
from dataclasses import replace
from pathlib import Path

import pytest

from mdle.cli import main
from mdle.experiments.generated import (
    StudyConfig,
    outcome,
    plan_text,
    run_spec,
    run_study,
    study_specs,
)
from mdle.lang import load_text

SMALL = StudyConfig(shapes=3, starts=1, duration=4.0, blind=True)


def test_plan_text_is_a_valid_mdle_atom() -> None:
    for kf in (None, 2.0):
        text = plan_text("left", 0.55, 0.3, kf, 12.5)
        program = load_text(text, file="<gen>")
        assert "f" in program.elements
        assert ("kf = 2" in text) == (kf is not None)
        assert "never, 12.5 s" in text


def test_specs_cover_the_shapes_starts_and_blind_side_deterministically() -> None:
    specs = study_specs(replace(SMALL, starts=2))
    assert len(specs) == 3 * 2 * 2
    assert [s.shape_index for s in specs if not s.blind] == [0, 0, 1, 1, 2, 2]
    assert sum(s.blind for s in specs) == 6
    assert study_specs(replace(SMALL, starts=2)) == specs
    assert len({s.sim_seed for s in specs}) == len(specs)
    assert all(s.duration == 4.0 for s in specs)
    assert StudyConfig(v=0.3).run_duration == pytest.approx(100.0)
    assert StudyConfig().run_duration == 40.0
    assert StudyConfig(rate=50).accuracy == 0.08 and StudyConfig().accuracy == 0.10


def test_a_run_is_a_pure_function_of_its_spec() -> None:
    spec = study_specs(replace(SMALL, shapes=1))[0]
    a, b = run_spec(spec), run_spec(spec)
    assert a == b or all(  # NaNs compare unequal: compare field by field
        (x == y) or (isinstance(x, float) and math.isnan(x) and math.isnan(y))
        for x, y in zip(a.values(), b.values(), strict=True))
    # the ideal unicycle has no body: the simulator's clearance is the distance d
    assert a["min_clearance"] == pytest.approx(a["min_d"], abs=1e-6)
    assert 0 < a["path_length"] <= 4.0 + 1e-6


def _same(rows_a: list[dict[str, object]], rows_b: list[dict[str, object]]) -> bool:
    def key(r: dict[str, object]) -> list[object]:
        return [("nan" if isinstance(v, float) and math.isnan(v) else v) for v in r.values()]

    return [key(r) for r in rows_a] == [key(r) for r in rows_b]


def test_rows_do_not_depend_on_the_number_of_processes() -> None:
    one = run_study(SMALL, jobs=1)
    two = run_study(SMALL, jobs=2)
    assert len(one) == 6 and _same(one, two)
    for r in one:
        assert r["outcome"] == outcome(r, SMALL.accuracy)
        assert r["outcome"] in ("collided", "never engaged", "inaccurate", "ok")
        assert r["path_length"] > 1.0  # the robot drove


def test_outcome_classes() -> None:
    base = {"collided": False, "engaged": True, "mean_err": 0.05}
    assert outcome(base, 0.08) == "ok"
    assert outcome({**base, "mean_err": 0.09}, 0.08) == "inaccurate"
    assert outcome({**base, "engaged": False}, 0.08) == "never engaged"
    assert outcome({**base, "collided": True}, 0.08) == "collided"


def test_cli_runs_a_small_study_and_writes_one_csv_row_per_run(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "runs.csv"
    code = main(["experiment", "random-starts", "--generated", "--shapes", "2", "--starts", "1",
                 "--duration", "4", "--jobs", "1", "--blind-side", "--rate", "20",
                 "--csv", str(out)])
    text = capsys.readouterr().out
    assert code in (0, 3)
    assert "collision-course starts" in text and "blind-side starts" in text
    assert "star" in text and "nonconvex" in text and "all" in text
    assert "worst clearance (m)" in text and "20 Hz" in text
    with out.open(newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 4
    assert {r["blind"] for r in rows} == {"True", "False"}
    assert {"theta0_deg", "incidence_deg", "engaged", "mean_err", "outcome"} <= set(rows[0])
    assert all(float(r["rate"]) == 20.0 and r["robot"] == "ideal" for r in rows)


@pytest.mark.parametrize(("argv", "message"), [
    (["--generated", "--shapes", "0"], "--shapes must be at least 1"),
    (["--generated", "--rate", "-1"], "--rate: the rate must be from 0.001 to 1,000 Hz"),
    (["--generated", "--robot", "pioner"], "unknown robot profile"),
    (["--generated", "--jobs", "0"], "--jobs must be at least 1"),
    (["--generated", "--shapes", "100000000"], "--shapes must be at least 1 and at most 100,000"),
    (["--generated", "--starts", "100000000"], "--starts must be at least 1 and at most 100,000"),
    # more than the first shape offers: was "internal error: ValueError" (exit 70)
    (["--generated", "--starts", "20000"], "of 20000 collision-course starts"),
    (["--generated", "--runs", "5"], "--runs is for the paper shapes"),
    (["--shapes", "3"], "--shapes needs --generated"),
    (["--blind-side"], "--blind-side needs --generated"),
])
def test_cli_refuses_bad_options_with_a_message(
        argv: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["experiment", "random-starts", *argv]) == 2
    assert message in capsys.readouterr().err


def test_cli_generated_only_applies_to_random_starts(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["experiment", "following", "--generated"]) == 2
    assert "only applies to random-starts" in capsys.readouterr().err


def test_cli_makes_the_csv_s_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]
                                    ) -> None:
    # the folder is made (and proved writable) before the study, as --out's is
    code = main(["experiment", "random-starts", "--generated", "--shapes", "1", "--starts", "1",
                 "--duration", "1", "--jobs", "1", "--csv", str(tmp_path / "no" / "x.csv")])
    captured = capsys.readouterr()
    assert code in (0, 3), captured.err
    assert "collision-course starts" in captured.out
    assert (tmp_path / "no" / "x.csv").read_text().startswith("family,shape,")


def test_paper_random_starts_benchmark_runs_from_the_repo_root(repo: Path) -> None:
    """Even where mdle is not installed: the editable install's finder is taken away first."""
    import sys

    code = ("import runpy, sys\n"
            "sys.meta_path[:] = [f for f in sys.meta_path\n"
            "                    if 'editable' not in getattr(f, '__module__', '')\n"
            "                    and 'editable' not in getattr(f, '__name__', '')]\n"
            "sys.path[:] = [p for p in sys.path if p not in ('', '.')]  # as for a script\n"
            "sys.argv = ['benchmarks/random_starts.py', '--runs', '1', '--duration', '1',\n"
            "            '--shapes', 'ellipse']\n"
            "runpy.run_path('benchmarks/random_starts.py', run_name='__main__')\n")
    r = subprocess.run([sys.executable, "-c", code], cwd=repo, capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    assert "ellipse" in r.stdout


def test_a_run_that_raises_is_an_error_row_not_the_end_of_the_study() -> None:
    from mdle.experiments.generated import run_specs

    good = study_specs(replace(SMALL, shapes=1, blind=False, duration=1.0))[0]
    bad = replace(good, robot="no-such-robot")
    rows = run_specs([bad, good], jobs=2)
    assert "no-such-robot" in rows[0]["error"] and rows[1]["error"] == ""
    assert outcome(rows[0], 0.1) == "error" and outcome(rows[1], 0.1) != "error"
    assert math.isnan(rows[0]["min_clearance"]) and set(rows[0]) == set(rows[1])


def test_failing_runs_are_saved_ready_for_mdle_run_and_replay_exactly(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import json

    folder = tmp_path / "failures"
    code = main(["experiment", "random-starts", "--generated", "--shapes", "1", "--starts", "2",
                 "--duration", "3", "--jobs", "1", "--save-failures", str(folder),
                 "--csv", str(tmp_path / "runs.csv")])
    assert code in (0, 3)
    out = capsys.readouterr().out
    with (tmp_path / "runs.csv").open(newline="") as f:
        rows = list(csv.DictReader(f))
    failing = [r for r in rows if r["outcome"] != "ok"]  # 3 s is too short to engage
    assert len(failing) == 2 and f"wrote 2 failing runs to {folder}" in out
    r = failing[0]
    plan = folder / f"{r['shape']}-start-{r['start']}.mdle"
    assert plan.exists() and plan.with_suffix(".world.yaml").exists()
    trace = tmp_path / "t.jsonl"
    assert main(["run", str(plan), "--rate", "10", "--sensing", "scan", "--quiet",
                 "--trace", str(trace)]) in (0, 3)
    last = [json.loads(line) for line in trace.read_text().splitlines()
            if '"sample"' in line][-1]
    assert last["true_x"] == pytest.approx(float(r["x_end"]), abs=1e-6)
    assert last["true_y"] == pytest.approx(float(r["y_end"]), abs=1e-6)
