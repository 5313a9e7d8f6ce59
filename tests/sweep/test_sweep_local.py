"""A small sweep on local processes: rows, failures as rows, resume, lost workers."""

from __future__ import annotations

import functools
import gzip
import operator
import os
import signal
import threading
import time
from dataclasses import replace
from pathlib import Path

import pytest

from mdle.sweep import LocalExecutor, expand, parse_study, read_study, run_sweep
from mdle.sweep.table import read_rows
from mdle.sweep.worker import execute

TIMING = ("wall_time", "cpu_time", "worker")


def test_a_small_sweep_writes_one_row_per_run(tiny_spec: Path, tmp_path: Path) -> None:
    study = read_study(tiny_spec)
    seen: list[dict[str, object]] = []
    summary = run_sweep(study, tmp_path / "out", jobs=2, on_row=seen.append)
    assert (summary.total, summary.done, summary.skipped, summary.failed) == (8, 8, 0, 0)
    rows = read_rows(tmp_path / "out")
    assert sorted(r["key"] for r in rows) == sorted(t.key for t in expand(study))
    for r in rows:
        assert r["status"] == "ok" and r["ended"] == "completed" and r["collided"] is False
        assert r["duration"] == pytest.approx(4.0, abs=0.11) and r["ticks"] >= 40
        assert 3.5 < r["distance"] < 4.1 and r["min_clearance"] > 0
        assert r["follow_rc"] == 1.0 and 0 <= r["follow_mean_err"] <= r["follow_max_err"]
        assert r["cmd_omega_max"] >= r["cmd_omega_mean"] and r["side_range_mean"] is not None
        assert r["param_kf"] in ("0.5", "2") and r["attempts"] == 1
    # The Parquet copy, read back by pyarrow itself, holds the same typed rows.
    pq = pytest.importorskip("pyarrow.parquet")
    table = pq.read_table(tmp_path / "out" / "results.parquet")
    assert table.num_rows == 8 and str(table.schema.field("collided").type) == "bool"
    assert sorted(table.column("key").to_pylist()) == sorted(r["key"] for r in rows)


def test_rows_are_the_same_whatever_runs_them(tiny_spec: Path, tmp_path: Path) -> None:
    tasks = list(expand(read_study(tiny_spec)))[:3]
    here = [execute(t).row for t in tasks]
    run_sweep(read_study(tiny_spec), tmp_path / "o", jobs=2)
    there = {r["key"]: r for r in read_rows(tmp_path / "o" / "results.csv")}
    for row in here:
        other = there[row["key"]]
        assert {k: v for k, v in row.items() if k not in TIMING} == \
               {k: v for k, v in other.items() if k not in TIMING and k in row}


def test_resume_skips_finished_runs(tiny_spec: Path, tmp_path: Path) -> None:
    study = read_study(tiny_spec)
    first = run_sweep(replace(study, seeds=(0,)), tmp_path / "o", jobs=1)
    assert first.done == 4
    again = run_sweep(study, tmp_path / "o", jobs=2)
    assert (again.skipped, again.done) == (4, 4)
    keys = [r["key"] for r in read_rows(tmp_path / "o")]
    assert len(keys) == len(set(keys)) == 8


def test_a_cut_off_last_line_is_dropped_on_resume(tiny_spec: Path, tmp_path: Path) -> None:
    study = read_study(tiny_spec)
    run_sweep(replace(study, seeds=(0,)), tmp_path / "o", jobs=1)
    table = tmp_path / "o" / "results.csv"
    text = table.read_text()
    table.write_text(text[: len(text) - 30])     # as if killed in the middle of a write
    again = run_sweep(study, tmp_path / "o", jobs=2)
    assert again.skipped == 3 and again.done == 5
    keys = [r["key"] for r in read_rows(table)]
    assert len(keys) == len(set(keys)) == 8


def test_another_studys_table_is_refused(tiny_spec: Path, tmp_path: Path) -> None:
    from mdle.core.errors import MdleError

    study = read_study(tiny_spec)
    run_sweep(replace(study, seeds=(0,)), tmp_path / "o", jobs=1)
    with pytest.raises(MdleError, match="another study"):
        run_sweep(replace(study, trace_fields=()), tmp_path / "o", jobs=1)


FAILING = """\
plan: {text: "atom follow(rc = 1 m) = (follow_boundary(rc = rc, v = 1 m/s), never, 3 s)\\n\
atom ram = (go(1 m/s), never, 20 s)\\n"}
worlds: [wall]
robots: [ideal]
entry: %s
starts: [[0, 2, -90]]
"""


def test_failing_runs_are_rows_with_their_cause(tmp_path: Path) -> None:
    ram = parse_study(FAILING % "ram")
    bad = [replace(t, settings=(("rc", "-1 s"),)) for t in expand(parse_study(FAILING % "follow"))]
    outcomes = list(LocalExecutor(2).run([*expand(ram), *bad]))
    rows = {o.row["entry"]: o.row for o in outcomes}
    assert rows["ram"]["status"] == "collision" and rows["ram"]["collided"] is True
    assert rows["ram"]["collisions"] == 1 and "collided" in rows["ram"]["cause"]
    assert rows["follow"]["status"] == "error" and "rc" in rows["follow"]["cause"]


def test_a_worker_that_raises_records_an_error_row(tiny_spec: Path) -> None:
    tasks = list(expand(read_study(tiny_spec)))[:2]
    raising = functools.partial(operator.truediv, 1)   # raises TypeError in the worker
    outcomes = list(LocalExecutor(2, function=raising).run(tasks))
    assert len(outcomes) == 2
    for o in outcomes:
        assert o.row["status"] == "error" and "TypeError" in o.row["cause"]
        assert o.row["key"] in {t.key for t in tasks}


def test_an_internal_error_in_a_run_is_a_row(tiny_spec: Path) -> None:
    task = next(iter(expand(read_study(tiny_spec))))
    broken = replace(task, rate=float("nan"))
    row = execute(broken).row
    assert row["status"] == "error" and row["cause"]


def _killer(executor: LocalExecutor, kills: int, done: threading.Event) -> None:
    killed: set[int] = set()
    deadline = time.monotonic() + 60
    while len(killed) < kills and not done.is_set() and time.monotonic() < deadline:
        for pid in executor.worker_pids():
            if pid not in killed:
                time.sleep(0.4)              # let it take a run
                os.kill(pid, signal.SIGKILL)
                killed.add(pid)
                break
        time.sleep(0.02)


@pytest.mark.parametrize("kills", [1, 2])
def test_a_lost_worker_is_retried_once_then_recorded_lost(tiny_spec: Path, kills: int) -> None:
    study = read_study(tiny_spec)
    tasks = [replace(t, until=None) for t in expand(replace(study, rates=(50.0,)))][:1]
    # long enough (6000 ticks) that the worker is still running when the killer strikes,
    # by a wide margin (30 s of it once ended before the second kill, after a faster sim)
    slow = [replace(t, plan_text=t.plan_text.replace("4 s)", "120 s)")) for t in tasks]
    executor = LocalExecutor(1)
    done = threading.Event()
    killer = threading.Thread(target=_killer, args=(executor, kills, done), daemon=True)
    killer.start()
    outcomes = list(executor.run(slow))
    done.set()
    killer.join(10)
    assert len(outcomes) == 1
    row = outcomes[0].row
    if kills == 1:
        assert row["status"] == "ok" and row["attempts"] == 2
    else:
        assert row["status"] == "lost" and row["attempts"] == 2
        assert "worker lost twice" in row["cause"]


def test_traces_are_kept_on_request(tiny_spec: Path, tmp_path: Path) -> None:
    study = replace(read_study(tiny_spec), seeds=(0,), keep_traces=True)
    run_sweep(study, tmp_path / "o", jobs=2)
    traces = sorted((tmp_path / "o" / "traces").glob("*.jsonl.gz"))
    assert len(traces) == 4
    from mdle.record.load import read_trace

    plain = tmp_path / "t.jsonl"
    plain.write_bytes(gzip.decompress(traces[0].read_bytes()))
    trace = read_trace(plain)
    assert len(trace.column("time")) >= 40


def test_a_sweep_over_generated_shapes(tmp_path: Path) -> None:
    plan = ("atom follow(rc = 0.5 m) = (follow_boundary(rc = rc, v = 1 m/s), never, 6 s)"
            "\\n")
    study = parse_study(f'plan: {{text: "{plan}"}}\nentry: follow\n'
                        "worlds: [{generated: {seed: 0, count: 2}}]\nrates: [20]\n"
                        "starts: {random: {count: 1, distance: [1, 2], seed: 2}}\n")
    summary = run_sweep(study, tmp_path / "o", jobs=2)
    rows = read_rows(tmp_path / "o")
    assert summary.done == 2 and {r["world"] for r in rows} == {"star-0-0", "nonconvex-0-1"}
    for r in rows:
        assert r["status"] in ("ok", "collision") and r["follow_rc"] == 0.5
        assert r["engaged"] in (True, False) and r["distance"] > 1.0


# A worker forked from the fork server, which imported mdle.sweep.preload, runs a task:
# the modules the run imports beyond that (mdle's own, or its heavy dependencies) would
# be imported again by every worker of every sweep.
_FRESH_WORKER = """\
import pickle, sys
import mdle.sweep.preload
task = pickle.loads(sys.stdin.buffer.read())
before = set(sys.modules)
from mdle.sweep.worker import execute
row = execute(task).row
print(row["status"], row["ticks"])
print(" ".join(sorted(set(sys.modules) - before)))
"""


def test_the_fork_servers_preload_leaves_a_run_nothing_to_import(tiny_spec: Path) -> None:
    import pickle
    import subprocess
    import sys

    task = next(iter(expand(read_study(tiny_spec))))
    out = subprocess.run([sys.executable, "-c", _FRESH_WORKER], input=pickle.dumps(task),
                         capture_output=True, check=True, timeout=120).stdout.decode()
    status, imported = out.splitlines()[0], out.splitlines()[1].split()
    assert status.split()[0] == "ok" and int(status.split()[1]) >= 40
    heavy = ("mdle", "numpy", "yaml", "shapely", "lark")
    assert [m for m in imported if m.split(".")[0] in heavy] == []
