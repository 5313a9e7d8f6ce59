"""The same sweep on a real dask.distributed LocalCluster (2 worker processes)."""

from __future__ import annotations

import functools
import operator
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from mdle.sweep import DaskExecutor, expand, read_study, run_sweep
from mdle.sweep.table import read_rows

distributed = pytest.importorskip("distributed")

TIMING = ("wall_time", "cpu_time", "worker")


@pytest.fixture(scope="module")
def client() -> Iterator[Any]:
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       host="127.0.0.1", dashboard_address=None,
                                       silence_logs=40)
    c = distributed.Client(cluster)
    try:
        yield c
    finally:
        c.close()
        cluster.close()


def _rows(path: Path) -> dict[str, dict[str, Any]]:
    return {r["key"]: {k: v for k, v in r.items() if k not in TIMING} for r in read_rows(path)}


def test_dask_rows_equal_local_rows(tiny_spec: Path, tmp_path: Path, client: Any) -> None:
    study = read_study(tiny_spec)
    local = run_sweep(study, tmp_path / "local", jobs=2)
    remote = run_sweep(study, tmp_path / "dask", executor=DaskExecutor(client))
    assert local.done == remote.done == 8 and remote.failed == 0
    a, b = _rows(tmp_path / "local"), _rows(tmp_path / "dask")
    assert a == b
    workers = {r["worker"] for r in read_rows(tmp_path / "dask")}
    assert len(workers) == 2          # both worker processes ran some


def test_dask_resume_skips_finished_runs(tiny_spec: Path, tmp_path: Path, client: Any) -> None:
    from dataclasses import replace

    study = read_study(tiny_spec)
    run_sweep(replace(study, seeds=(1,)), tmp_path / "o", executor=DaskExecutor(client))
    again = run_sweep(study, tmp_path / "o", executor=DaskExecutor(client))
    assert (again.skipped, again.done) == (4, 4)
    keys = [r["key"] for r in read_rows(tmp_path / "o")]
    assert len(keys) == len(set(keys)) == 8


def test_a_dask_worker_that_raises_records_an_error_row(tiny_spec: Path, client: Any) -> None:
    tasks = list(expand(read_study(tiny_spec)))[:2]
    raising = functools.partial(operator.truediv, 1)
    outcomes = list(DaskExecutor(client, function=raising).run(tasks))
    assert sorted(o.row["key"] for o in outcomes) == sorted(t.key for t in tasks)
    assert all(o.row["status"] == "error" and "TypeError" in o.row["cause"] for o in outcomes)


def test_an_unreachable_scheduler_is_a_clear_error() -> None:
    from mdle.core.errors import MdleError

    with pytest.raises(MdleError, match="cannot reach the scheduler"):
        DaskExecutor("tcp://127.0.0.1:9", timeout=1.0)


def test_mdle_sweep_dask_address_from_the_command_line(
        tiny_spec: Path, tmp_path: Path, client: Any, mdle_command: list[str]) -> None:
    import subprocess

    address = client.scheduler.address
    out = tmp_path / "cli"
    r = subprocess.run([*mdle_command, "sweep", str(tiny_spec), "--out", str(out), "--dask",
                        address], capture_output=True, text=True, timeout=180)
    assert r.returncode == 0, r.stderr
    assert f"Dask cluster {address}" in r.stderr and "8 runs done (0 failed)" in r.stderr
    local = run_sweep(read_study(tiny_spec), tmp_path / "local", jobs=2)
    assert local.done == 8 and _rows(out) == _rows(tmp_path / "local")
    both = subprocess.run([*mdle_command, "sweep", str(tiny_spec), "--dask", address,
                           "--jobs", "2"], capture_output=True, text=True, timeout=60)
    assert both.returncode == 2 and "--jobs is for local processes" in both.stderr
