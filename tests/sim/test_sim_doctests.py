"""The examples in the sim package's docstrings run and give what they say."""

from __future__ import annotations

import doctest
import importlib

import pytest

MODULES = ["sim", "sim.shapes", "sim.raycast", "sim.distance", "sim.world", "sim.world_yaml",
           "sim.catalog", "sim.robot", "sim.ladar", "sim.collision", "sim.backend",
           "sim.generated", "sim.starts", "sim.world_dump"]


@pytest.mark.parametrize("name", MODULES)
def test_doctests(name: str) -> None:
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0, f"{name} has no examples"
    assert result.failed == 0
