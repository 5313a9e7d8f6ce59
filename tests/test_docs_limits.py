"""docs/limits.md says what the code does: every exit code, and the value of every budget.

Each budget's behaviour is tested beside it (the expansion budget in
tests/language/test_language_expansion.py, ranges in tests/test_cli_ranges.py, study
counts in tests/sweep/test_sweep_spec.py, export limits in tests/ros/test_ros_export.py,
the trace's reserve in tests/runtime/test_runtime_cli_faults.py, files in
tests/test_user_files.py and tests/test_user_file_faults.py); this file keeps the page
and the constants from drifting apart.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from mdle.console import output

PAGE = (Path(__file__).resolve().parents[1] / "docs" / "limits.md").read_text(encoding="utf-8")


def _exit_table() -> dict[int, str]:
    section = PAGE[PAGE.index("## Exit codes"):]
    rows = re.findall(r"^\| (\d+) \| (.+?) \|$", section, re.MULTILINE)
    return {int(code): meaning for code, meaning in rows}


def test_every_exit_code_of_the_command_line_is_in_the_table() -> None:
    codes = {v for k, v in vars(output).items() if k.startswith("EXIT_") and isinstance(v, int)}
    codes |= {128 + 1, 128 + 15}  # SIGHUP, SIGTERM: 128 + the signal's number
    assert set(_exit_table()) == codes


@pytest.mark.parametrize(("text", "value"), [
    ("20,000 (`mdle.lang.expansion.MAX_EXPANSION`)", "mdle.lang.expansion:MAX_EXPANSION"),
    ("100,000 each (`mdle.sweep.spec.MAX_AXIS`)", "mdle.sweep.spec:MAX_AXIS"),
    ("| runs in one study | 10,000,000 |", "mdle.sweep.spec:_MAX_RUNS"),
    ("| a seed | 0 to 2**63 - 1", "mdle.sweep.spec:MAX_STUDY_SEED"),
    ("| control rate | 0.001 to 1,000 Hz", "mdle.core.ranges:RATE"),
    ("| start coordinates | within 1,000,000 m", "mdle.core.ranges:COORDINATE"),
    ("| start heading | -360 to 360 degrees", "mdle.core.ranges:HEADING"),
    ("within 1,000,000,000 s", "mdle.record.export:MAX_TIME"),
    ("A trace keeps 16 KiB free", "mdle.record.trace:RESERVE_BYTES"),
    ("At most **64 MB** per file", "mdle.core.userfile:MAX_FILE_BYTES"),
    ("| obstacles listed in one world | 250,000", "mdle.sim.world_obstacles:MAX_OBSTACLES"),
    ("| obstacles other than circles | 20,000", "mdle.sim.world_obstacles:MAX_SHAPES"),
])
def test_each_budget_on_the_page_is_the_code_s(text: str, value: str) -> None:
    import importlib

    module, name = value.split(":")
    constant = getattr(importlib.import_module(module), name)
    assert text in PAGE
    expected = {
        "MAX_EXPANSION": 20_000, "MAX_AXIS": 100_000, "_MAX_RUNS": 10_000_000,
        "MAX_STUDY_SEED": 2**63 - 1, "MAX_TIME": 1e9, "RESERVE_BYTES": 16 * 1024,
        "MAX_FILE_BYTES": 64 * 1024 * 1024, "MAX_OBSTACLES": 250_000,
        "MAX_SHAPES": 20_000,
    }
    if name == "RATE":
        assert (constant.low, constant.high, constant.unit) == (0.001, 1000.0, "Hz")
    elif name == "HEADING":
        assert constant.problem(math.radians(360.0)) is None
        assert constant.problem(math.radians(360.001)) is not None
        assert constant.problem(math.radians(-360.001)) is not None
    elif name == "COORDINATE":
        assert (constant.low, constant.high, constant.unit) == (-1e6, 1e6, "m")
    else:
        assert constant == expected[name]
