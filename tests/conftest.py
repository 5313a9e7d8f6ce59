"""Shared fixtures and the catalogue of canonical inputs (plans, scans, worlds)."""

from __future__ import annotations

from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
PLANS = REPO / "plans"


@pytest.fixture
def repo() -> Path:
    """The repository root (plans/, docs/ live there; the code is the installed package)."""
    return REPO
