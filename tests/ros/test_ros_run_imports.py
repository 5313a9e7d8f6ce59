"""`mdle run` imports the ROS recorder only for a run that records (start-up time)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

PLAN = "atom a = (go(0.2 m/s), never, 1 s)\nplan main = ((a), never, 2 s)\nrun main\n"
PROBE = ("import sys\nfrom mdle.cli import main\ncode = main(sys.argv[1:])\n"
         "print('recorder' if 'mdle.ros.recorder' in sys.modules else 'none')\n"
         "sys.exit(code)\n")


def _run(tmp_path: Path, *extra: str) -> str:
    proc = subprocess.run([sys.executable, "-c", PROBE, "run", str(tmp_path / "p.mdle"),
                           "--world", "empty", "-q", *extra],
                          capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.strip().splitlines()[-1]


def test_a_run_that_does_not_record_leaves_the_recorder_unloaded(tmp_path: Path) -> None:
    (tmp_path / "p.mdle").write_text(PLAN)
    assert _run(tmp_path) == "none"
    assert _run(tmp_path, "--trace", str(tmp_path / "t.jsonl")) == "none"
    assert _run(tmp_path, "--record", str(tmp_path / "r.mcap")) == "recorder"
