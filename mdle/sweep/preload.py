"""What a local sweep's fork server imports and builds once, before any worker forks.

A worker forked from the server starts with all of it in memory. Without it each worker
spent its first run importing the language, the simulator's world builder, shapely and
PyYAML, and building the language's parser: about 0.16 s of CPU a worker, paid again by
every added worker, a part of the sweep that more workers do not shorten.

Importing this module does the work (it is the fork server's preload:
:meth:`mdle.sweep.executors.LocalExecutor.start`): it runs :data:`WARM_UP`, a run of a
third of a second that goes the way a study's runs go (a plan with a parameter set,
``follow_boundary`` on a scan, a world from its text, a trace kept), so whatever a run
imports or builds once per process is there before the workers fork.
tests/sweep/test_sweep_local.py checks that a run then imports nothing more.
"""

from __future__ import annotations

from mdle.sweep.tasks import RunTask
from mdle.sweep.worker import execute

__all__ = ["WARM_UP"]

#: The run the server makes; its outcome is not used (a failing run is a row, never
#: an exception, so a server always starts).
WARM_UP = RunTask(
    plan_text="atom a(rc = 0.5 m) = (follow_boundary(rc = rc, v = 0.3 m/s), never, 1 s)\n"
              "run a\n",
    plan_files=(), entry=None, settings=(("rc", "0.6 m"),),
    world_text="name: warm-up\nstart: {x: 0, y: 0, theta: 0}\n"
               "obstacles:\n  - {type: circle, center: [1.5, 0], radius: 0.5}\n",
    robot=None, sensing="scan", rate=10.0, seed=0, pose=None, until=0.3,
    trace_fields=("side_range",), keep_trace=True)

execute(WARM_UP)
