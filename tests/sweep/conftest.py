"""Tiny studies for the sweep's tests: short runs, so the suite stays fast on 2 cores."""

from __future__ import annotations

from pathlib import Path

import pytest

#: A plan with settable parameters: follow the boundary for a few seconds.
FOLLOW_PLAN = """\
atom follow(rc = 1 m, kf = 0.5) = (follow_boundary(rc = rc, v = 1 m/s, kf = kf), never, 4 s)
plan main = ((follow), stalled, inf)
"""

TINY_SPEC = """\
name: tiny
plan: follow.mdle
worlds: [ellipse]
robots: [ideal]
rates: [10]
seeds: [0, 1]
starts: {random: {count: 2, distance: [1, 3], seed: 4}}
parameters: {grid: {kf: [0.5, 2]}}
trace_fields: [side_range, cmd_omega]
"""


@pytest.fixture
def tiny_spec(tmp_path: Path) -> Path:
    """Write the tiny study (8 runs of 4 s at 10 Hz) and its plan; return the spec's path."""
    (tmp_path / "follow.mdle").write_text(FOLLOW_PLAN)
    spec = tmp_path / "tiny.yaml"
    spec.write_text(TINY_SPEC)
    return spec


@pytest.fixture
def follow_plan() -> str:
    """The text of the settable following plan."""
    return FOLLOW_PLAN
