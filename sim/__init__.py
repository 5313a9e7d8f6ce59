"""The embedded simulator: worlds from YAML, a Pioneer II with a SICK LMS-200 ladar.

>>> import sim
>>> world = sim.load_world("ellipse")
>>> backend = sim.SimBackend(world, seed=1)
>>> obs = backend.observe()
>>> len(obs.scan.ranges), obs.truth["collided"]
(181, False)

The names below are imported on first use, so that reading a robot profile or a world's
robot (``mdle check`` does, to compare a plan's speeds with the robot's) costs no numpy.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from sim.backend import SimBackend
    from sim.catalog import DEFAULT_WORLD, list_worlds, load_world
    from sim.world import World

__all__ = ["DEFAULT_WORLD", "SimBackend", "World", "list_worlds", "load_world"]

_HOME = {"SimBackend": "sim.backend", "DEFAULT_WORLD": "sim.catalog",
         "list_worlds": "sim.catalog", "load_world": "sim.catalog", "World": "sim.world"}


def __getattr__(name: str) -> Any:
    home = _HOME.get(name)
    if home is None:
        raise AttributeError(f"module 'sim' has no attribute {name!r}")
    value = getattr(importlib.import_module(home), name)
    globals()[name] = value
    return value
