"""What a local sweep's fork server imports and builds once, before any worker forks.

A worker forked from the server starts with all of it in memory. Without it each worker
spends its first run importing the language, the simulator's world builder, shapely and
PyYAML, and building the language's parser: about 0.15 s of CPU a worker, paid again by
every added worker, a part of the sweep that more workers do not shorten.

Importing this module does the work (it is the fork server's preload:
:meth:`mdle.sweep.executors.LocalExecutor.start`). tests/sweep/test_sweep_local.py
checks that a run then imports nothing more.
"""

from __future__ import annotations

import numpy.random  # noqa: F401  (a run's seeded noise)
import shapely  # noqa: F401  (a world's obstacles)
import yaml  # noqa: F401  (a world's text)

import mdle.atoms.estimators  # noqa: F401  (imported by follow_boundary at its first tick)
import mdle.experiments.engagement  # noqa: F401  (the following metrics)
import mdle.runtime.api  # noqa: F401
import mdle.sim.backend  # noqa: F401
import mdle.sim.world_yaml  # noqa: F401
import mdle.sweep.metrics  # noqa: F401
import mdle.sweep.worker  # noqa: F401
import mdle.sweep.worlds  # noqa: F401
import mdle.trace  # noqa: F401  (kept traces)
from mdle.lang import load_text

__all__ = ["PLAN"]

#: Loaded once here, with a parameter set as a study sets one: it builds the parser and
#: the registry of every control law, and imports the parameter overrides.
PLAN = "atom a(v = 0.1 m/s) = (go(v), never, 1 s)\nrun a\n"

load_text(PLAN, "<preload>", settings={"v": "0.2 m/s"})
