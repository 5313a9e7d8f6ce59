"""The examples in the atoms modules' docstrings run and hold."""

from __future__ import annotations

import doctest
import importlib

import pytest

MODULES = ["mdle.atoms.estimators", "mdle.atoms.boundary", "mdle.atoms.steering",
           "mdle.atoms.memo", "mdle.atoms.ramped_arcs"]


@pytest.mark.parametrize("name", MODULES)
def test_doctests(name: str) -> None:
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0
    assert result.failed == 0
