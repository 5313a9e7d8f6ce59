"""`mdle repl` as a piped, non-terminal session: the installed command in a subprocess.

A first session defines atoms, runs them and saves the definitions; a second loads them
again and goes on. Poses are checked against closed forms (the ellipse world's ideal
unicycle starts at (-9, 0.3) heading east, with no acceleration limits or odometry noise).
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import time
from collections.abc import Callable
from pathlib import Path

import pytest

Repl = Callable[..., "subprocess.CompletedProcess[str]"]


@pytest.fixture
def repl(mdle_command: list[str]) -> Repl:
    """``repl(stdin, *args, cwd=..., timeout=120)``: one piped ``mdle repl`` session."""
    def run(stdin: str, *args: str, cwd: Path, timeout: float = 120
            ) -> subprocess.CompletedProcess[str]:
        env = {**os.environ, "XDG_DATA_HOME": str(cwd / "data")}
        return subprocess.run([*mdle_command, "repl", *args], input=stdin, capture_output=True,
                              check=False, text=True, cwd=cwd, timeout=timeout, env=env)

    return run


def pose_in(out: str) -> tuple[float, float, float]:
    """The last odometry pose `:pose` printed."""
    found = re.findall(r"^odometry x (-?[0-9.]+) m  y (-?[0-9.]+) m  heading (-?[0-9.]+) deg",
                       out, re.MULTILINE)
    assert found, out
    x, y, h = found[-1]
    return float(x), float(y), float(h)


FIRST = """\
# a first session: two atoms, typed over several lines
atom creep(v = 0.5 m/s) =
    (go(v), never, 2 s)
atom quarter(rate = 90 deg/s) = (turn(rate),
                                  never,
                                  1 s)
creep
quarter
creep(1 m/s)
:pose
:save tuned.mdle
"""


def test_define_run_save_then_load_in_a_second_session(tmp_path: Path, repl: Repl,
                                                         mdle_command: list[str]) -> None:
    res = repl(FIRST, "--world", "ellipse", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert res.stderr == ""
    assert "\x1b" not in res.stdout  # no control codes off a terminal
    out = res.stdout
    assert "defined creep\n" in out and "defined quarter\n" in out
    assert "creep (level 0) ended by timer at 2.00 s" in out
    assert "quarter (level 0) ended by timer at 1.00 s" in out
    # east 1 m, a quarter turn left, north 2 m
    # odometry from the session's start, the world's (-9, 0.3): the world's (-8, 2.3)
    assert pose_in(out) == pytest.approx((1.0, 2.0, 90.0), abs=0.006)
    assert ("saved 2 definitions to tuned.mdle (3 lines, ending `run creep`: `mdle run "
            "tuned.mdle` runs it)") in out
    saved = (tmp_path / "tuned.mdle").read_text()
    # the run line names the definition last run (`creep(1 m/s)`), so the file runs
    assert saved == ("atom creep(v = 0.5 m/s) = (go(v), never, 2 s)\n"
                     "atom quarter(rate = 90 deg/s) = (turn(rate), never, 1 s)\n"
                     "run creep\n")
    # the saved file is what `mdle fmt` prints: formatting it changes nothing
    fmt = subprocess.run([*mdle_command, "fmt", "--check", "tuned.mdle"], cwd=tmp_path,
                         capture_output=True, text=True, timeout=60, check=False)
    assert fmt.returncode == 0, fmt.stdout + fmt.stderr
    run = subprocess.run([*mdle_command, "run", "-q", "tuned.mdle"], cwd=tmp_path,
                         capture_output=True, text=True, timeout=60, check=False)
    assert run.returncode == 0, run.stdout + run.stderr

    # a second session loads them (the FILE argument), goes on, and :load again is quiet
    second = "quarter(-90 deg/s)\ncreep\n:pose\n:load tuned.mdle\n:defs\n"
    res = repl(second, "--world", "ellipse", "tuned.mdle", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    out = res.stdout
    assert out.startswith("loaded tuned.mdle: creep, quarter\n")
    # a quarter turn right (heading -90), then 1 m south
    assert pose_in(out) == pytest.approx((0.0, -1.0, -90.0), abs=0.006)  # odometry
    assert "loaded tuned.mdle: nothing new" in out
    assert out.endswith(saved)


def test_failed_inputs_give_exit_1_and_the_session_goes_on(tmp_path: Path, repl: Repl) -> None:
    script = """\
atom creep = (go(0.5 m/s), never, 2 s)
atom broken = (go(2 s), never, 1 s)
crep
creep
(go(1 m/s), never, 20 s)
:pose
:reset -9 -3 0
:pose
"""
    res = repl(script, "--world", "ellipse", cwd=tmp_path)
    assert res.returncode == 1
    assert "\x1b" not in res.stdout + res.stderr
    err = res.stderr
    assert "<repl>:1:19: error: `v` of `go` is a speed such as `0.3 m/s`" in err
    assert "unknown name `crep`" in err and "did you mean `creep`?" in err
    out = res.stdout
    assert "creep (level 0) ended by timer at 2.00 s" in out
    assert "COLLIDED with `ellipse`" in out
    poses = re.findall(r"^odometry x (-?[0-9.]+) m  y (-?[0-9.]+) m", out, re.MULTILINE)
    # stopped at the ellipse (world x -3.95), 5.05 m from the start; after `:reset X Y`
    # odometry starts again at 0
    assert float(poses[0][0]) == pytest.approx(5.05, abs=0.01)
    assert poses[1] == ("0.00", "0.00")
    assert "Traceback" not in err


def test_echo_prints_a_transcript_and_an_unfinished_input_fails(tmp_path: Path, repl: Repl) -> None:
    res = repl("(go(1 m/s),\n never, 1 s)\n:pose\n(go(1 m/s), never,\n", "--world", "ellipse",
               "--echo", cwd=tmp_path)
    assert res.returncode == 1
    lines = res.stdout.splitlines()
    assert lines[0] == "mdle> (go(1 m/s),"
    assert lines[1] == "  ...  never, 1 s)"
    assert lines[2].startswith("go (level 0) ended by timer at 1.00 s")
    assert "mdle> :pose" in lines
    assert "the input ended in the middle of an unfinished statement" in res.stderr


def test_quit_stops_reading_and_bad_options_are_usage_errors(tmp_path: Path, repl: Repl) -> None:
    res = repl(":quit\nnot-run\n", "--world", "ellipse", cwd=tmp_path)
    assert res.returncode == 0 and "not-run" not in res.stderr
    res = repl("", "--world", "atlantis", cwd=tmp_path)
    assert res.returncode == 1 and "unknown world `atlantis`" in res.stderr
    res = repl("", "--until", "0", cwd=tmp_path)
    assert res.returncode == 2
    res = repl("", "missing.mdle", cwd=tmp_path)
    assert res.returncode == 1 and "missing.mdle" in res.stderr


def test_until_seed_robot_and_sensing_options(tmp_path: Path, repl: Repl) -> None:
    res = repl("(turn(1 rad/s), never, inf)\n", "--world", "ellipse", "--until", "1.5",
               cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert "turn (level 0) was stopped from outside at 1.50 s (the run limit of 1.5 s" in res.stdout
    # the default world with the ideal unicycle (no acceleration limits) and an exact ladar
    res = repl("(go(1 m/s), never, 1 s)\n:pose\n:scan\n", "--seed", "4", "--robot", "ideal",
               "--sensing", "exact", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    # 1 m east of the default world's start (-4, -3): odometry (1, 0), the world's (-3, -3)
    assert pose_in(res.stdout) == pytest.approx((1.0, 0.0, 0.0))
    assert "true     x -3.00 m  y -3.00 m" in res.stdout
    assert "world `default`, seed 4" in res.stdout
    assert "max range 10 m (exact)" in res.stdout


def test_sigint_during_a_piped_run_stops_it_and_the_session_goes_on(
        tmp_path: Path, mdle_command: list[str]) -> None:
    env = {**os.environ, "XDG_DATA_HOME": str(tmp_path / "data")}
    proc = subprocess.Popen([*mdle_command, "repl", "--world", "ellipse", "--until", "inf"],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=tmp_path, env=env)
    assert proc.stdin is not None and proc.stdout is not None
    proc.stdin.write(":pose\n")
    proc.stdin.flush()
    assert proc.stdout.readline().startswith("odometry")  # the session is up
    for _ in range(3):
        proc.stdout.readline()
    proc.stdin.write("(turn(1 rad/s), never, inf)\n")
    proc.stdin.flush()
    time.sleep(1.0)  # the run is going (it never ends by itself)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(":pose\n", timeout=60)
    assert proc.returncode == 1, err  # the stopped run counts as failed
    assert "turn (level 0) was stopped from outside at" in out and "(Ctrl-C: robot stopped)" in out
    # turned in place, then the :pose after it ran (the first one was read above)
    assert out.count("odometry x 0.00 m  y 0.00 m") == 1


def test_bytes_that_are_not_utf8_are_reported_and_the_session_goes_on(
        mdle_command: list[str]) -> None:
    # a strict decoder (as under a UTF-8 locale other than C.UTF-8) must not end the session
    env = dict(os.environ, PYTHONIOENCODING="utf-8:strict")
    proc = subprocess.run([*mdle_command, "repl", "--world", "empty"], capture_output=True,
                          input=b"atom a = (go(0.1 m/s), never, 1 s)\n\xff\xfe bad\na\n",
                          timeout=120, env=env)
    err = proc.stderr.decode()
    assert proc.returncode == 1, err
    assert "input line 2 is not UTF-8 text (byte 0xff at column 1)" in err
    assert "internal error" not in err and "Traceback" not in err
    assert "a (level 0) ended by timer at 1.00 s" in proc.stdout.decode()


SESSION = "atom a = (go(0.3 m/s), never, 1 s)\n" + "a\n:where\n:reset\n" * 30


def test_standard_output_closed_from_the_start_is_quiet(tmp_path: Path,
                                                       mdle_command: list[str]) -> None:
    # Python makes sys.stdout None: every print was an "internal error"
    res = subprocess.run([*mdle_command, "repl"], input=SESSION, stdout=None,
                         stderr=subprocess.PIPE, text=True, cwd=tmp_path, timeout=120,
                         preexec_fn=lambda: os.close(1), check=False)
    assert res.returncode == 0, res.stderr
    assert res.stderr == ""


def test_standard_output_closed_by_its_reader_ends_the_session_quietly(
        tmp_path: Path, mdle_command: list[str]) -> None:
    # `mdle repl < inputs | head -1`: BrokenPipeError was "a bug in mdle"
    proc = subprocess.Popen([*mdle_command, "repl"], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=tmp_path)
    assert proc.stdout is not None and proc.stdin is not None
    proc.stdout.close()  # the reader goes away before the first line
    _, err = proc.communicate(SESSION, timeout=120)
    assert proc.returncode == 141, err
    assert "internal error" not in err and "Traceback" not in err


def test_a_full_disk_in_the_session_is_a_message_and_the_session_goes_on(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import errno
    import io

    from mdle.repl.commands import Repl as Session_
    from mdle.repl.session import Session

    out, err = io.StringIO(), io.StringIO()
    repl = Session_(Session("default"), out, err)
    assert repl.handle("atom a = (go(0.3 m/s), never, 1 s)") and repl.handle("a")

    def full(path: str) -> int:
        raise OSError(errno.ENOSPC, "No space left on device", path)

    monkeypatch.setattr(repl.session, "write_trace", full)
    assert not repl.handle(f":trace {tmp_path / 't.jsonl'}")
    assert "the disk is full" in err.getvalue() and "internal error" not in err.getvalue()
    assert repl.handle("a")
