"""`mdle check`, `mdle fmt`, `mdle show` as a user runs them (the installed console script)."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

BIN = Path(sys.executable).parent
MDLE = str(BIN / "mdle")
REPO = Path(__file__).resolve().parents[2]
TOUR = str(REPO / "plans" / "language" / "tour.mdle")


def mdle(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([MDLE, *args], capture_output=True, text=True, timeout=60, cwd=cwd)


def test_check_clean_plan_exits_0() -> None:
    r = mdle("check", TOUR)
    assert r.returncode == 0, r.stdout + r.stderr
    # the tour reads x and y: check says which frame they are in
    assert r.stdout.startswith("checked 1 file: 0 errors, 0 warnings\nnote: x, y, theta and "
                               "dist_to are odometry (REP-105 odom frame)") and r.stderr == ""


def test_check_folder_checks_every_plan() -> None:
    r = mdle("check", str(REPO / "plans" / "language"))
    assert r.returncode == 0, r.stdout
    assert r.stdout.startswith("checked 4 files")


def test_check_errors_exit_1_with_messages_on_stdout(tmp_path: Path) -> None:
    bad = tmp_path / "bad.mdle"
    bad.write_text("atom a = (go(1 m), never, 1 s)\natom b = (go(1 m/s), stalled)\n")
    r = mdle("check", "bad.mdle", cwd=tmp_path)
    assert r.returncode == 1
    assert r.stdout.splitlines()[:3] == [
        "bad.mdle:1:14: error: `v` of `go` is a speed such as `0.3 m/s`, found a length (`1 m`)",
        "    atom a = (go(1 m), never, 1 s)",
        "                 ^^^"]
    assert "bad.mdle:2:29: error: expected a timer such as `10 s` or `inf`" in r.stdout
    assert r.stdout.endswith("checked 1 file: 2 errors, 0 warnings\n")
    assert "Traceback" not in r.stdout + r.stderr


def test_check_warnings_exit_0_unless_strict(tmp_path: Path) -> None:
    p = tmp_path / "w.mdle"
    p.write_text("atom a = (go(1 m/s), never, inf)\nbehavior b = ((a, a), stalled, 5 s)\n")
    r = mdle("check", str(p))
    assert r.returncode == 0 and "warning: `a` is never reached" in r.stdout
    assert mdle("check", "--strict", str(p)).returncode == 1
    assert mdle("check", "-q", str(p)).stdout == ""


@pytest.mark.parametrize("content", [b"\x00\xff\xfe binary", b"", b"(" * 1_000_000,
                                     b"atom a = (go(3 ft), never, 1 s)",
                                     b'import "missing.mdle"\n'])
def test_hostile_files_exit_0_or_1_without_traceback(tmp_path: Path, content: bytes) -> None:
    p = tmp_path / "h.mdle"
    p.write_bytes(content)
    r = mdle("check", str(p))
    assert r.returncode == (0 if content == b"" else 1)
    assert "Traceback" not in r.stdout + r.stderr and "internal error" not in r.stderr


def test_usage_errors_exit_2() -> None:
    r = mdle("check")
    assert r.returncode == 2 and "usage:" in r.stderr
    assert mdle("check", "--no-such-option", TOUR).returncode == 2
    assert mdle("fmt", "--write", "--check", TOUR).returncode == 2


def test_missing_file_exits_1(tmp_path: Path) -> None:
    r = mdle("check", str(tmp_path / "absent.mdle"))
    assert r.returncode == 1 and "no such file" in r.stdout


def test_check_does_not_import_numpy_or_shapely() -> None:
    code = ("import sys\nfrom mdle.cli import main\n"
            f"code = main(['check', '-q', {TOUR!r}])\n"
            "heavy = sorted(m for m in ('numpy', 'shapely', 'matplotlib') if m in sys.modules)\n"
            "print(code, heavy)\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.stdout.strip() == "0 []", r.stdout + r.stderr


def test_fmt_prints_check_and_write(tmp_path: Path) -> None:
    p = tmp_path / "f.mdle"
    p.write_text("atom a=(go(1 m/s),never,1s)  # c\n")
    r = mdle("fmt", str(p))
    assert r.returncode == 0 and r.stdout == "atom a = (go(1 m/s), never, 1 s)  # c\n"
    assert mdle("fmt", "--check", str(p)).returncode == 1
    assert mdle("fmt", "--write", str(p)).returncode == 0
    assert p.read_text() == "atom a = (go(1 m/s), never, 1 s)  # c\n"
    assert mdle("fmt", "--check", str(p)).returncode == 0
    p.write_text("atom a = (")
    r = mdle("fmt", str(p))
    assert r.returncode == 1 and "unbalanced parentheses" in r.stderr


def test_show_prints_tree_and_figures() -> None:
    r = mdle("show", TOUR)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0] == "plan main  [stalled | 10 min]"
    assert "\u251c\u2500\u2500 behavior patrol  [never | 5 min]" in lines
    assert lines[-1] == ("atoms: 14   distinct control laws: 4 (arc, go, stop, turn)   "
                         "nesting depth: 3   worst-case duration: 10 min")
    r = mdle("show", TOUR, "--plan", "spin")
    assert r.stdout.startswith("atom spin: turn(rate = 30 deg/s)  [never | 3 s]")
    assert mdle("show", TOUR, "--plan", "nope").returncode == 1


@pytest.fixture
def read_only_plan(tmp_path: Path) -> Iterator[Path]:
    """A badly laid out plan that cannot be written: mode 0444, or (as root, who writes
    anyway) on a tmpfs remounted read-only; skipped where neither can be made."""
    text = "atom  a = (go(0.1 m/s),never, 1 s)\n"
    if os.geteuid() != 0:
        p = tmp_path / "ro.mdle"
        p.write_text(text)
        p.chmod(0o444)
        yield p
        return
    point = tmp_path / "ro"
    point.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(point)],
                      capture_output=True, timeout=30).returncode != 0:
        pytest.skip("root, and no tmpfs can be mounted here")
    try:
        (point / "ro.mdle").write_text(text)
        subprocess.run(["mount", "-o", "remount,ro", str(point)], check=True,
                       capture_output=True, timeout=30)
        yield point / "ro.mdle"
    finally:
        subprocess.run(["umount", "-l", str(point)], capture_output=True, timeout=30)


def test_fmt_write_on_a_read_only_file_is_a_message(read_only_plan: Path) -> None:
    before = read_only_plan.read_text()
    res = mdle("fmt", "--write", str(read_only_plan))
    assert res.returncode == 1, res.stderr
    assert f"cannot write `{read_only_plan}`" in res.stdout + res.stderr
    assert "internal error" not in res.stdout + res.stderr
    assert read_only_plan.read_text() == before


def test_fmt_write_replaces_the_file_whole_and_keeps_its_mode(tmp_path: Path) -> None:
    p = tmp_path / "p.mdle"
    p.write_text("atom  a = (go(0.1 m/s),never, 1 s)\n")
    p.chmod(0o640)
    res = mdle("fmt", "--write", str(p))
    assert res.returncode == 0, res.stderr
    assert p.read_text() == "atom a = (go(0.1 m/s), never, 1 s)\n"
    assert p.stat().st_mode & 0o777 == 0o640
    assert sorted(x.name for x in tmp_path.iterdir()) == ["p.mdle"]


def test_run_with_a_negative_seed_is_a_usage_error(tmp_path: Path) -> None:
    p = tmp_path / "p.mdle"
    p.write_text("atom a = (go(0.1 m/s), never, 1 s)\n")
    res = mdle("run", str(p), "--seed", "-1")
    assert res.returncode == 2 and "a seed is a whole number from 0" in res.stderr


def test_check_and_run_compare_speeds_with_the_robot_the_run_uses(tmp_path: Path) -> None:
    plan = tmp_path / "dash.mdle"
    plan.write_text("atom dash = (go(3 m/s), never, 1 s)\nrun dash\n")
    r = mdle("check", "dash.mdle", cwd=tmp_path)
    assert r.returncode == 0
    assert r.stdout.startswith("dash.mdle:1:17: warning: `v` of `go` is 3 m/s, more than the "
                               "robot can do: the top speed of `pioneer2dx` (the default "
                               "robot) is 2.2 m/s\n"), r.stdout
    assert mdle("check", "--strict", "dash.mdle", cwd=tmp_path).returncode == 1
    # a world beside the plan names the robot; --robot overrides it
    (tmp_path / "dash.world.yaml").write_text("robot: ideal\n")
    r = mdle("check", "dash.mdle", cwd=tmp_path)
    assert "the top speed of `ideal` (the robot of `dash.world.yaml` beside the plan) is 1 m/s" \
        in r.stdout
    assert "1 warning" in mdle("check", "--robot", "pioneer2dx", "dash.mdle", cwd=tmp_path).stdout
    plan.write_text("atom dash = (go(2 m/s), never, 1 s)\nrun dash\n")
    assert "0 warnings" in mdle("check", "--robot", "pioneer2dx", "dash.mdle", cwd=tmp_path).stdout
    r = mdle("check", "--world", "corridor", "dash.mdle", cwd=tmp_path)
    assert "0 warnings" in r.stdout, r.stdout
    # mdle run warns with the same robot, and still runs
    r = mdle("run", "dash.mdle", cwd=tmp_path)
    assert r.returncode == 0 and "the top speed of `ideal`" in r.stdout + r.stderr
    r = mdle("check", "--world", "no-such-world", "dash.mdle", cwd=tmp_path)
    assert r.returncode == 1 and "unknown world `no-such-world`" in r.stdout


def test_check_warns_about_a_file_run_cannot_run(tmp_path: Path) -> None:
    (tmp_path / "lib.mdle").write_text("atom creep = (go(0.2 m/s), never, 1 s)\n")
    r = mdle("check", "lib.mdle", cwd=tmp_path)
    assert r.returncode == 0
    assert r.stdout.splitlines()[:2] == [
        "lib.mdle:2:1: warning: nothing to run: the file has no `run NAME` line and no plan "
        "named `main`, so `mdle run` cannot run it",
        "  hint: add `run creep` (runnable here: creep); a file that other plans only import "
        "needs none"]
    assert mdle("run", "lib.mdle", cwd=tmp_path).returncode == 1  # what the warning foretells
    # checked with a plan that imports it, it is a library: no warning
    (tmp_path / "main.mdle").write_text('import "lib.mdle"\nrun creep\n')
    r = mdle("check", "lib.mdle", "main.mdle", cwd=tmp_path)
    assert r.stdout == "checked 2 files: 0 errors, 0 warnings\n", r.stdout


def test_check_reads_a_world_file_as_a_world(tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    """A world file given to check is checked as a world, not refused as a bad team file."""
    from mdle.cli import main

    world = REPO / "plans" / "paper" / "fig6-corridor.world.yaml"
    assert main(["check", str(world)]) == 0
    out = capsys.readouterr().out
    assert f"{world}: a world, 12 obstacles" in out and "unknown key" not in out
    bad = tmp_path / "bad.world.yaml"
    bad.write_text("name: x\nobstacles:\n  - {type: circle, center: [3, 0]}\n")
    assert main(["check", str(bad)]) == 1
    assert f"{bad}:3:5: error: obstacles[0]: missing key `radius`" in capsys.readouterr().out
    # a team file (it names its world) is still read as a team
    team = tmp_path / "t.yaml"
    team.write_text("world: ellipse\nname: x\nrobots: {}\n")
    assert main(["check", str(team)]) == 1
    assert "unknown key `name`" in capsys.readouterr().out
