"""Parameter studies and Monte Carlo: many seeded simulator runs of a plan, on all cores.

A study (YAML, :mod:`mdle.sweep.spec`) combines worlds, robots, sensing, rates, seeds,
start poses and plan parameters; :func:`run_sweep` runs each combination once (local
processes or a Dask cluster, :mod:`mdle.sweep.executors`) and appends a row per run to a
results table (:mod:`mdle.sweep.table`) that a rerun resumes; :mod:`mdle.sweep.report`
summarises and plots it. ``mdle sweep`` is the command line.
"""

from mdle.sweep.engine import SweepSummary, run_sweep
from mdle.sweep.executors import DaskExecutor, LocalExecutor
from mdle.sweep.spec import SpecError, Study, parse_study, read_study
from mdle.sweep.tasks import RunTask, expand

__all__ = ["DaskExecutor", "LocalExecutor", "RunTask", "SpecError", "Study", "SweepSummary",
           "expand", "parse_study", "read_study", "run_sweep"]
