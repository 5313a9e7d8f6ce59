"""Shared fixtures and the catalogue of canonical inputs (plans, scans, worlds)."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
PLANS = REPO / "plans"


@pytest.fixture
def mdle_command() -> list[str]:
    """The installed ``mdle`` command as a subprocess argv prefix.

    The one beside this Python (the venv under test) first, else the one on PATH.
    """
    exe = Path(sys.executable).with_name("mdle")
    if exe.exists():
        return [str(exe)]
    found = shutil.which("mdle")
    assert found, "the `mdle` command is not installed"
    return [found]


@pytest.fixture
def repo() -> Path:
    """The repository root (plans/, docs/ live there; the code is the installed package)."""
    return REPO
