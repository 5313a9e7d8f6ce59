"""The embedded simulator: worlds from YAML, a Pioneer II with a SICK LMS-200 ladar.

>>> from mdle import sim
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
    from mdle.sim.backend import SimBackend
    from mdle.sim.catalog import DEFAULT_WORLD, list_worlds, load_world
    from mdle.sim.world import World

__all__ = ["DEFAULT_WORLD", "SimBackend", "World", "list_worlds", "load_world"]

_HOME = {"SimBackend": ".backend", "DEFAULT_WORLD": ".catalog",
         "list_worlds": ".catalog", "load_world": ".catalog", "World": ".world"}


def __getattr__(name: str) -> Any:
    home = _HOME.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(home, __name__), name)
    globals()[name] = value
    return value
