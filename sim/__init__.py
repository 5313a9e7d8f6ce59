"""The embedded simulator: worlds from YAML, a Pioneer II with a SICK LMS-200 ladar.

>>> import sim
>>> world = sim.load_world("ellipse")
>>> backend = sim.SimBackend(world, seed=1)
>>> obs = backend.observe()
>>> len(obs.scan.ranges), obs.truth["collided"]
(181, False)
"""

from sim.backend import SimBackend
from sim.catalog import DEFAULT_WORLD, list_worlds, load_world
from sim.world import World

__all__ = ["DEFAULT_WORLD", "SimBackend", "World", "list_worlds", "load_world"]
