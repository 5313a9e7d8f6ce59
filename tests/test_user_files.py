"""Every path a user names is read safely: regular files of at most 64 MB, or a message.

``/dev/zero`` (endless), a FIFO with no writer (blocks forever), a directory and a file
over the limit are refused with a message naming the file, whichever command meets them:
a plan, an import, a world, a trace, the world a trace header names, ``:load`` in the
REPL. The commands run as subprocesses with a hard deadline and a memory ceiling, so a
regression fails the test instead of hanging it or eating the machine's memory.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
from pathlib import Path

import pytest

from mdle.core.userfile import MAX_FILE_BYTES, UserFileError, open_user_file, read_user_file

DEADLINE = 60.0
ZERO = "/dev/zero"


def _limits() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (2 * 1024 ** 3, 2 * 1024 ** 3))


def run(argv: list[str], cwd: Path, stdin: str | None = None) -> subprocess.CompletedProcess[str]:
    """Run a command with a hard deadline and a 2 GB address-space ceiling."""
    return subprocess.run(argv, cwd=cwd, input=stdin if stdin is not None else "",
                          capture_output=True, text=True, timeout=DEADLINE,
                          preexec_fn=_limits)


@pytest.fixture
def fifo(tmp_path: Path) -> Path:
    """A named pipe no one writes to."""
    path = tmp_path / "pipe.mdle"
    os.mkfifo(path)
    return path


@pytest.fixture
def big(tmp_path: Path) -> Path:
    """A sparse file one byte over the limit (no disk space used)."""
    path = tmp_path / "big.mdle"
    with open(path, "wb") as f:
        f.truncate(MAX_FILE_BYTES + 1)
    return path


# ------------------------------------------------------------------ the helper itself


def test_helper_refuses_devices_fifos_directories_and_big_files(
        tmp_path: Path, fifo: Path, big: Path) -> None:
    cases = {ZERO: "character device", str(fifo): "FIFO", str(tmp_path): "directory",
             str(big): "64.0 MB", str(tmp_path / "missing"): "no such file"}
    for path, words in cases.items():
        with pytest.raises(UserFileError) as err:
            read_user_file(path)
        assert words in err.value.reason and path in str(err.value)


def test_helper_reads_a_regular_file(tmp_path: Path) -> None:
    f = tmp_path / "ok.mdle"
    f.write_bytes(b"run main\n")
    assert read_user_file(f) == b"run main\n"
    with open_user_file(f) as stream:
        assert stream.readline() == b"run main\n"
    with pytest.raises(UserFileError, match="at most 5 bytes"):
        read_user_file(f, limit=5)


# ------------------------------------------------------------------ every command


@pytest.mark.parametrize("target", ["zero", "fifo", "big"])
def test_check_and_import_refuse(target: str, tmp_path: Path, fifo: Path, big: Path,
                                 mdle_command: list[str]) -> None:
    path = {"zero": ZERO, "fifo": str(fifo), "big": str(big)}[target]
    r = run([*mdle_command, "check", path], tmp_path)
    assert r.returncode == 1 and f"cannot read `{path}`" in r.stdout, r.stdout + r.stderr
    plan = tmp_path / "main.mdle"
    plan.write_text(f'import "{path}"\natom a = (go(0.3 m/s), never, 1 s)\n', encoding="utf-8")
    r = run([*mdle_command, "check", str(plan)], tmp_path)
    assert r.returncode == 1, r.stdout + r.stderr
    assert "main.mdle:1:1: error: cannot import" in r.stdout, r.stdout
    assert ("not a regular file" if target != "big" else "at most 64.0 MB") in r.stdout, r.stdout


@pytest.mark.parametrize("target", ["zero", "fifo"])
def test_run_world_refuses(target: str, tmp_path: Path, fifo: Path,
                           mdle_command: list[str], repo: Path) -> None:
    path = ZERO if target == "zero" else str(fifo)
    plan = repo / "plans" / "language" / "tour.mdle"
    r = run([*mdle_command, "run", str(plan), "--world", path, "--until", "1"], tmp_path)
    assert r.returncode == 1, r.stdout + r.stderr
    assert path in r.stderr and "not a regular file" in r.stderr, r.stderr


def test_plot_refuses_a_trace_that_is_a_device_and_a_header_world_that_is_one(
        tmp_path: Path, fifo: Path, mdle_command: list[str]) -> None:
    r = run([*mdle_command, "plot", ZERO, "-o", str(tmp_path / "p.png")], tmp_path)
    assert r.returncode == 1 and ZERO in r.stderr and "not a regular file" in r.stderr, r.stderr
    r = run([*mdle_command, "plot", str(fifo), "-o", str(tmp_path / "p.png")], tmp_path)
    assert r.returncode == 1 and "FIFO" in r.stderr, r.stderr
    trace = tmp_path / "t.jsonl"
    records = [{"type": "header", "format": "mdle-trace", "version": 1,
                "world": {"spec": ZERO}},
               {"type": "sample", "t": 0.0, "x": 0.0, "y": 0.0, "theta": 0.0, "path": "a"},
               {"type": "sample", "t": 0.1, "x": 0.1, "y": 0.0, "theta": 0.0, "path": "a"}]
    trace.write_text("".join(json.dumps(r) + "\n" for r in records), encoding="utf-8")
    r = run([*mdle_command, "plot", str(trace), "-o", str(tmp_path / "p.png")], tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr  # the world is skipped, the plot drawn


def test_repl_load_refuses_and_the_session_goes_on(tmp_path: Path, fifo: Path,
                                                   mdle_command: list[str]) -> None:
    script = f":load {ZERO}\n:load {fifo}\natom a = (go(0.3 m/s), never, 1 s)\n:defs\n"
    r = run([*mdle_command, "repl", "--plain"], tmp_path, stdin=script)
    assert ZERO in r.stderr and "FIFO" in r.stderr, r.stderr
    assert "atom a = " in r.stdout, r.stdout
