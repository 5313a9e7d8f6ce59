"""Run a study: expand it, skip finished runs, execute the rest, write rows as they come.

>>> from mdle.sweep import parse_study, run_sweep                 # doctest: +SKIP
>>> summary = run_sweep(parse_study(open("study.yaml").read()), "out", jobs=2)
>>> summary.done, summary.failed

The results folder holds ``results.csv`` (the journal, one row per finished run),
``results.parquet`` (with pyarrow), ``spec.yaml`` (the spec as given, when known) and
``traces/KEY.jsonl.gz`` for studies that keep traces.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from mdle.core.collector import collector_paused, release_in_slices
from mdle.sweep.executors import Executor, LocalExecutor, Task
from mdle.sweep.spec import Study
from mdle.sweep.table import ResultsTable, columns_for, write_parquet
from mdle.sweep.tasks import expand

__all__ = ["run_sweep", "run_tasks", "SweepSummary", "Progress", "FAILED"]

#: Statuses counted as failures in progress and summaries.
FAILED = ("collision", "error", "lost")


class Progress(Protocol):
    """What a sweep reports while it runs (a rich progress bar, a test's list)."""

    def start(self, total: int, skipped: int) -> None:
        """Handle the start: ``total`` runs in the study, ``skipped`` already in the table."""

    def advance(self, row: dict[str, Any]) -> None:
        """Handle a finished run's row."""

    def interrupted(self) -> None:
        """Handle Ctrl-C or a signal, at once: the workers are stopped and the table closed next."""

    def stop(self) -> None:
        """Handle the end of the sweep (also after Ctrl-C)."""


@dataclass
class SweepSummary:
    """How a sweep went: runs in the study, skipped (already done), done now, failures."""

    total: int
    skipped: int
    done: int = 0
    failed: int = 0
    interrupted: bool = False
    table: Path | None = None
    parquet: Path | None = None


def run_sweep(study: Study, out: str | os.PathLike[str], *, executor: Executor | None = None,
              jobs: int | None = None, progress: Progress | None = None,
              spec_text: str | None = None,
              on_row: Callable[[dict[str, Any]], None] | None = None) -> SweepSummary:
    """Run every run of ``study`` not yet in ``out/results.csv``; return the summary.

    Parameters
    ----------
    study : Study
        From :func:`mdle.sweep.read_study` or :func:`mdle.sweep.parse_study`.
    out : path-like
        The results folder (created).
    executor : Executor, optional
        Where runs execute; default local processes (``jobs``, default all cores).
    progress : Progress, optional
        Told of the start, each finished row and the end.
    spec_text : str, optional
        The spec as written, saved beside the table.
    on_row : callable, optional
        Called with each row after it is written.

    Ctrl-C (KeyboardInterrupt) stops the sweep: finished rows stay in the table, the
    summary says ``interrupted``, and running the same sweep again resumes.

    Raises
    ------
    MdleError
        The folder holds a table of another study, or random starts cannot be placed.
    """
    columns = columns_for(study.parameter_names, study.trace_fields)
    with collector_paused():  # up to millions of tasks that live as long as the sweep
        tasks = list(expand(study))
    if spec_text is not None:
        Path(out).mkdir(parents=True, exist_ok=True)
        (Path(out) / "spec.yaml").write_text(spec_text, encoding="utf-8")
    try:
        return run_tasks(tasks, columns, out, executor=executor, jobs=jobs, progress=progress,
                         on_row=on_row)
    finally:
        release_in_slices(tasks)  # freed at once, 600,000 tasks held signals for 70 ms


def run_tasks(tasks: Sequence[Task], columns: Sequence[str],
              out: str | os.PathLike[str] | None, *, executor: Executor | None = None,
              jobs: int | None = None, progress: Progress | None = None,
              on_row: Callable[[dict[str, Any]], None] | None = None) -> SweepSummary:
    """Run the tasks not yet in ``out/results.csv`` and append their rows.

    The engine under :func:`run_sweep` and the experiments: any picklable tasks with a
    ``key``, an ``attempt`` and a ``row()`` of descriptive columns, run by the
    executor's function. ``out=None`` keeps no table (nothing to resume): rows go to
    ``on_row`` only.
    """
    folder = Path(out) if out is not None else None
    table: ResultsTable | None = None
    done: set[str] = set()
    if folder is not None:
        folder.mkdir(parents=True, exist_ok=True)
        table = ResultsTable(folder / "results.csv", columns)
        done = table.done
    todo = [t for t in tasks if t.key not in done]
    summary = SweepSummary(len(tasks), len(tasks) - len(todo),
                           table=table.path if table is not None else None)
    runner = executor if executor is not None else LocalExecutor(jobs)
    if progress is not None:
        progress.start(summary.total, summary.skipped)
    stream = runner.run(todo)
    try:
        for outcome in stream:
            row = outcome.row
            if outcome.trace is not None and folder is not None:
                traces = folder / "traces"
                traces.mkdir(exist_ok=True)
                tmp = traces / f".{row['key']}.tmp"
                tmp.write_bytes(outcome.trace)
                os.replace(tmp, traces / f"{row['key']}.jsonl.gz")
            if table is not None:
                table.append(row)
            summary.done += 1
            summary.failed += row.get("status") in FAILED
            if progress is not None:
                progress.advance(row)
            if on_row is not None:
                on_row(row)
    except KeyboardInterrupt:
        summary.interrupted = True
        if progress is not None:  # the user hears now, not after the workers have ended
            progress.interrupted()
    finally:
        close = getattr(stream, "close", None)
        if close is not None:
            close()
        if table is not None:
            table.close()
        if progress is not None:
            progress.stop()
    if folder is not None and table is not None and write_parquet(
            table.path, folder / "results.parquet"):
        summary.parquet = folder / "results.parquet"
    return summary
