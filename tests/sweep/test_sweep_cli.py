"""`mdle sweep` as a user runs it: interrupted (SIGINT, SIGKILL) and resumed, report, errors."""

from __future__ import annotations

import csv
import io
import signal
import subprocess
import time
from pathlib import Path

import pytest

SPEC = """\
plan: follow.mdle
worlds: [ellipse, hexagon]
robots: [ideal]
rates: [10]
seeds: {count: 6}
starts: {random: {count: 2, distance: [1, 3]}}
parameters: {grid: {kf: [0.5, 2]}}
"""
TOTAL = 2 * 6 * 2 * 2


def _lines(path: Path) -> list[str]:
    if not path.exists():
        return []
    text = path.read_text()
    return text[: text.rfind("\n") + 1].splitlines()


def _study(tmp_path: Path, plan: str) -> Path:
    (tmp_path / "follow.mdle").write_text(plan)
    spec = tmp_path / "study.yaml"
    spec.write_text(SPEC)
    return spec


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGKILL])
def test_a_killed_sweep_resumes_without_losing_or_repeating_rows(
        tmp_path: Path, mdle_command: list[str], sig: signal.Signals, follow_plan: str) -> None:
    spec = _study(tmp_path, follow_plan)
    out = tmp_path / "out"
    table = out / "results.csv"
    cmd = [*mdle_command, "sweep", str(spec), "--out", str(out), "--jobs", "2"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 90
        while len(_lines(table)) < 4 and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.05)
        assert proc.poll() is None, "the sweep ended before it could be interrupted"
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    if sig == signal.SIGINT:
        assert proc.returncode == 130, err
        assert "interrupted" in err and "resume" in err
        # said at once, before the workers have ended and the table is closed
        said = err.index("interrupted: stopping the workers")
        assert said < err.index("runs done"), err
    else:
        assert proc.returncode == -signal.SIGKILL
    before = _lines(table)
    assert 4 <= len(before) < TOTAL + 1
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=180)
    assert done.returncode == 0, done.stderr
    after = _lines(table)
    assert after[: len(before)] == before            # no finished row lost or rewritten
    rows = list(csv.DictReader(io.StringIO("\n".join(after))))
    keys = [r["key"] for r in rows]
    assert len(keys) == len(set(keys)) == TOTAL       # none repeated, none missing
    assert f"{len(before) - 1} already in the table" in done.stderr
    assert all(r["status"] == "ok" for r in rows)


def test_report_prints_a_summary_and_draws_plots(tmp_path: Path, mdle_command: list[str],
                                                 follow_plan: str) -> None:
    spec = _study(tmp_path, follow_plan)
    spec.write_text(SPEC.replace("seeds: {count: 6}", "seeds: [0]").replace(
        "worlds: [ellipse, hexagon]", "worlds: [ellipse]"))
    out = tmp_path / "out"
    run = subprocess.run([*mdle_command, "sweep", str(spec), "--out", str(out)],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    rep = subprocess.run([*mdle_command, "sweep", "report", str(out)], capture_output=True,
                         text=True, timeout=120)
    assert rep.returncode == 0, rep.stderr
    assert "4 runs: 4 ok, 0 failed" in rep.stdout
    assert "by kf" in rep.stdout and "|d-rc| p50" in rep.stdout
    png = out / "plots" / "follow_mean_err-vs-kf.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    bad = subprocess.run([*mdle_command, "sweep", "report", str(out), "--by", "zeta"],
                         capture_output=True, text=True, timeout=60)
    assert bad.returncode == 1 and "--by zeta: no such column (swept: kf)" in bad.stderr


def test_spec_errors_are_located_and_exit_1(tmp_path: Path, mdle_command: list[str],
                                            follow_plan: str) -> None:
    spec = _study(tmp_path, follow_plan)
    bad = tmp_path / "bad.yaml"
    bad.write_text(SPEC + "parameters2: {}\n")
    r = subprocess.run([*mdle_command, "sweep", str(bad)], capture_output=True, text=True,
                       timeout=60, cwd=tmp_path)
    assert r.returncode == 1
    assert f"{bad}:8:1: error: parameters2: unknown key `parameters2`" in r.stderr
    assert "Traceback" not in r.stderr
    dry = subprocess.run([*mdle_command, "sweep", str(spec), "--dry-run"],
                         capture_output=True, text=True, timeout=60, cwd=tmp_path)
    assert dry.returncode == 0 and f"{TOTAL} runs" in dry.stdout
    for argv, message in ((["report"], "give the results folder"),
                          (["report", str(tmp_path / "nope")], "no results table"),
                          ([str(tmp_path / "none.yaml")], "study spec not found")):
        r = subprocess.run([*mdle_command, "sweep", *argv], capture_output=True, text=True,
                           timeout=60, cwd=tmp_path)
        assert r.returncode in (1, 2) and message in r.stderr


@pytest.mark.parametrize(("sig", "code"), [(signal.SIGTERM, 143), (signal.SIGHUP, 129)])
def test_a_sweep_ends_with_the_code_of_its_signal_and_no_library_traceback(
        tmp_path: Path, mdle_command: list[str], follow_plan: str, sig: signal.Signals,
        code: int) -> None:
    # 130 for every signal once; and a worker still starting when the pool let go of its
    # queues printed multiprocessing's traceback (SemLock._rebuild): signals come at
    # several moments from the workers' start on. Runs of 2 min (not the fixture's 4 s): on a
    # quiet machine the 48 short runs ended before the last signal went out
    plan = follow_plan.replace("never, 4 s)", "never, 2 min)")
    assert plan != follow_plan
    spec = _study(tmp_path, plan)
    for delay in (0.0, 0.3, 0.8, 1.5):
        out = tmp_path / f"out-{delay}"
        proc = subprocess.Popen([*mdle_command, "sweep", str(spec), "--out", str(out),
                                 "--jobs", "2"], stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        try:
            deadline = time.monotonic() + 90
            while not (out / "results.csv").exists() and time.monotonic() < deadline:
                time.sleep(0.01)  # the table exists just before the workers start
            time.sleep(delay)
            assert proc.poll() is None, ("the sweep ended before the signal", delay)
            proc.send_signal(sig)
            _, err = proc.communicate(timeout=60)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait(10)
        assert proc.returncode == code, (delay, err)
        assert "Traceback" not in err and "Error" not in err, (delay, err)
        assert "interrupted" in err
