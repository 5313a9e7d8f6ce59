"""The examples in the sim package's docstrings run and give what they say."""

from __future__ import annotations

import doctest
import importlib

import pytest

MODULES = ["mdle.sim", "mdle.sim.shapes", "mdle.sim.raycast", "mdle.sim.distance",
           "mdle.sim.world", "mdle.sim.world_yaml", "mdle.sim.catalog", "mdle.sim.robot",
           "mdle.sim.ladar", "mdle.sim.collision", "mdle.sim.backend", "mdle.sim.generated",
           "mdle.sim.starts", "mdle.sim.world_dump",
           "mdle.sim.faceindex", "mdle.sim.nearest_truth"]


@pytest.mark.parametrize("name", MODULES)
def test_doctests(name: str) -> None:
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0, f"{name} has no examples"
    assert result.failed == 0
