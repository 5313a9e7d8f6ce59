"""`mdle run` when things go wrong around it: signals at any moment, a full disk, a closed
standard output. The installed command in a subprocess with a hard deadline; whatever
happens, the trace holds whole records, ends with its end record and shows the stop."""

from __future__ import annotations

import json
import os
import random
import resource
import shutil
import signal
import subprocess
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from mdle.record.load import read_trace

#: Moves (v and omega both non-zero) and changes atom often, forever.
CIRCLES = """\
atom left = (arc(0.3 m/s, 20 deg/s), never, 0.7 s)
atom right = (arc(0.3 m/s, 25 deg/s), never, 0.5 s)
plan main = ((left, right)..., never, inf)
run main
"""

DEADLINE = 60.0  # seconds any one mdle process may take before it is killed and fails


@pytest.fixture
def circles(tmp_path: Path) -> Path:
    p = tmp_path / "circles.mdle"
    p.write_text(CIRCLES)
    return p


def _env() -> dict[str, str]:
    return dict(os.environ, MPLBACKEND="Agg")


@contextmanager
def _signals_blocked() -> Iterator[None]:
    """Block SIGINT/SIGTERM in this thread while a child is spawned: the child starts with
    them held, and mdle unblocks them once its handlers are in place. A signal sent in the
    child's first milliseconds (while the Python interpreter itself starts, before any line
    of mdle runs) is then acted on by mdle instead of by the interpreter's defaults."""
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _default_dispositions() -> None:
    """In the child, before exec: SIGINT and SIGTERM to their defaults.

    A test run from a non-interactive shell's background job (`... &`) inherits SIGINT
    *ignored*; the child would inherit that too, and a SIGINT sent before mdle installs its
    handlers would be discarded by the kernel (an ignored signal is dropped even while
    blocked), so the run would never end. mdle started from a terminal has the defaults.
    """
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _finish(proc: subprocess.Popen[str], timeout: float = DEADLINE) -> tuple[str, str]:
    try:
        return proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
        pytest.fail(f"mdle did not end within {timeout} s; stderr:\n{err}")


def _records(path: Path) -> list[dict[str, Any]]:
    """Every line of the trace as strict JSON: a cut or broken line fails the test."""
    data = path.read_bytes()
    assert data.endswith(b"\n"), f"the last record of {path} was cut"
    records = [json.loads(line) for line in data.splitlines()]
    read_trace(path)  # and mdle's own reader accepts it
    return records


def _assert_complete_and_stopped(path: Path, what: str) -> dict[str, Any]:
    """The trace parses, ends with the end record, and its last sample is the stop."""
    assert path.exists(), f"{what}: no trace"
    records = _records(path)
    assert records[0]["type"] == "header", what
    assert records[-1]["type"] == "end", f"{what}: no end record"
    samples = [r for r in records if r["type"] == "sample"]
    if samples:  # the robot was commanded: the last command sent is the stop
        assert (samples[-1]["cmd_v"], samples[-1]["cmd_omega"]) == (0.0, 0.0), what
        assert samples[-1]["path"] == "", what
    return records[-1]


# ---------------------------------------------------------------------- signals


def test_signals_at_fifty_random_moments_leave_complete_traces(
        circles: Path, tmp_path: Path, mdle_command: list[str]) -> None:
    # From the first millisecond on: half the moments fall while mdle starts (imports,
    # parser, plan and world loading), half while it runs; with and without --realtime
    # (a signal in a sleep, or in the middle of a tick and its trace write), with and
    # without the live view on standard output.
    rng = random.Random(17)
    moments = [rng.uniform(0.001, 0.6) for _ in range(25)] + \
        [rng.uniform(0.6, 1.5) for _ in range(25)]
    rng.shuffle(moments)
    batch = 4
    for first in range(0, len(moments), batch):
        running = []
        for k in range(first, min(first + batch, len(moments))):
            sig = (signal.SIGINT, signal.SIGTERM)[k % 2]
            trace = tmp_path / f"t{k}.jsonl"
            argv = [*mdle_command, "run", str(circles), "--world", "empty",
                    "--trace", str(trace)]
            if k % 3 == 0:
                argv.append("--realtime")
            if k % 4 < 2:
                argv.append("--quiet")
            with _signals_blocked():
                proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                        text=True, env=_env(),
                                        preexec_fn=_default_dispositions)
            running.append((k, sig, trace, proc, time.monotonic() + moments[k]))
        for _, sig, _, proc, at in sorted(running, key=lambda r: r[4]):
            time.sleep(max(0.0, at - time.monotonic()))
            proc.send_signal(sig)
        for k, sig, trace, proc, _ in running:
            what = f"run {k}: {signal.Signals(sig).name} at {moments[k] * 1e3:.0f} ms"
            out, err = _finish(proc)
            assert proc.returncode == 128 + sig, f"{what}: exit {proc.returncode}\n{err}"
            assert "Traceback" not in err and "interrupted by" in err, f"{what}:\n{err}"
            end = _assert_complete_and_stopped(trace, what)
            assert end["cause"] == "stopped", what
            assert signal.Signals(sig).name in str(end["reason"]), what


def test_a_signal_before_the_run_starts_still_leaves_a_trace(
        circles: Path, tmp_path: Path, mdle_command: list[str]) -> None:
    trace = tmp_path / "t.jsonl"
    trace.write_text("an old trace that must not pass for this run\n")
    with _signals_blocked():
        proc = subprocess.Popen([*mdle_command, "run", str(circles), "--trace", str(trace)],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                env=_env(), preexec_fn=_default_dispositions)
        proc.send_signal(signal.SIGTERM)  # held until mdle's handlers are in place
    out, err = _finish(proc)
    assert proc.returncode == 143, err
    assert "Traceback" not in err and "interrupted by SIGTERM before the run started" in err
    end = _assert_complete_and_stopped(trace, "early SIGTERM")
    assert end["ticks"] == 0 and end["cause"] == "stopped"
    assert "before the run started" in end["reason"]
    assert read_trace(trace).header["program"]["file"] == str(circles)


def test_ctrl_c_while_the_command_line_is_read_is_no_traceback(
        mdle_command: list[str]) -> None:
    for argv in (["--version"], ["check", "--help"], ["worlds"]):
        with _signals_blocked():
            proc = subprocess.Popen([*mdle_command, *argv], stdout=subprocess.PIPE,
                                    stderr=subprocess.PIPE, text=True, env=_env(),
                                    preexec_fn=_default_dispositions)
            proc.send_signal(signal.SIGINT)
        out, err = _finish(proc)
        assert proc.returncode == 130, (argv, err)
        assert "Traceback" not in err and "KeyboardInterrupt" not in err, (argv, err)


# ---------------------------------------------------------------------- a full disk


def _limit_file_size(limit: int) -> Any:
    def apply() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return apply


def _check_disk_full(res: subprocess.CompletedProcess[str], trace: Path) -> None:
    assert res.returncode == 74, res.stderr
    assert "Traceback" not in res.stderr
    assert f"cannot write the trace `{trace}`" in res.stderr
    records = _records(trace)  # whole records only
    assert records[0]["type"] == "header" and len(records) > 3
    if records[-1]["type"] == "end":  # cutting the failed batch made room for it
        assert records[-1]["cause"] == "error" and "trace" in records[-1]["fault"]
    assert "elements run:" in res.stdout  # the run was ended, with its summary


def test_a_trace_over_the_file_size_limit_ends_the_run_cleanly(
        circles: Path, tmp_path: Path, mdle_command: list[str]) -> None:
    # RLIMIT_FSIZE: the kernel refuses writes past 40 kB (EFBIG), as a full disk
    # refuses them (ENOSPC); no privileges needed
    trace = tmp_path / "t.jsonl"
    res = subprocess.run([*mdle_command, "run", str(circles), "--world", "empty",
                          "--trace", str(trace)], capture_output=True, text=True,
                         env=_env(), timeout=DEADLINE, preexec_fn=_limit_file_size(40_000))
    _check_disk_full(res, trace)
    assert "File too large" in res.stderr
    assert trace.stat().st_size <= 40_000


@pytest.fixture
def full_disk(tmp_path: Path) -> Iterator[Path]:
    """A real 64 kB tmpfs (root only: skipped where it cannot be mounted)."""
    mount = shutil.which("mount")
    point = tmp_path / "small"
    point.mkdir()
    if mount is None or os.geteuid() != 0 or subprocess.run(
            [mount, "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(point)],
            capture_output=True, timeout=30).returncode != 0:
        pytest.skip("cannot mount a small tmpfs here (needs root); the file size limit "
                    "test covers the same path")
    try:
        yield point
    finally:
        subprocess.run(["umount", "-l", str(point)], capture_output=True, timeout=30)


def test_a_full_disk_ends_the_run_cleanly(
        circles: Path, full_disk: Path, mdle_command: list[str]) -> None:
    trace = full_disk / "t.jsonl"
    res = subprocess.run([*mdle_command, "run", str(circles), "--world", "empty",
                          "--trace", str(trace)], capture_output=True, text=True,
                         env=_env(), timeout=DEADLINE)
    _check_disk_full(res, trace)
    assert "No space left on device" in res.stderr


def test_trace_and_recording_on_one_full_disk_end_cleanly_with_the_end_record(
        circles: Path, full_disk: Path, mdle_command: list[str]) -> None:
    # 5 of 5 runs printed a traceback ("could not stop the robot cleanly after ...
    # TraceWriteError") and 1 of 5 traces had no end record
    pytest.importorskip("mcap", reason="the mcap extra is not installed")
    for attempt in range(3):
        for f in full_disk.iterdir():
            f.unlink()
        trace = full_disk / "t.jsonl"
        res = subprocess.run([*mdle_command, "run", str(circles), "--world", "empty",
                              "--trace", str(trace), "--record", str(full_disk / "r.mcap")],
                             capture_output=True, text=True, env=_env(), timeout=DEADLINE)
        assert res.returncode == 74, res.stderr
        assert "Traceback" not in res.stderr and "could not stop" not in res.stderr
        records = _records(trace)
        assert records[0]["type"] == "header", attempt
        assert records[-1]["type"] == "end", (attempt, records[-1])  # the reserve made room
        assert records[-1]["cause"] == "error"
        assert [f.name for f in full_disk.iterdir() if f.name.endswith(".reserve")] == []


# ---------------------------------------------------------------------- stdout closed


def test_a_closed_standard_output_ends_the_run_like_a_pipeline(
        circles: Path, tmp_path: Path, mdle_command: list[str]) -> None:
    # `mdle run ... | head -3`: read three lines, close the pipe
    trace = tmp_path / "t.jsonl"
    proc = subprocess.Popen([*mdle_command, "run", str(circles), "--world", "empty",
                             "--trace", str(trace)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=_env(),
                            preexec_fn=_default_dispositions)
    try:
        assert proc.stdout is not None
        lines = [proc.stdout.readline() for _ in range(3)]
        assert all("start" in line or "end" in line for line in lines), lines
        proc.stdout.close()
        proc.wait(timeout=DEADLINE)  # stderr is short: no pipe fills up meanwhile
        assert proc.stderr is not None
        err = proc.stderr.read()
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 141, err
    assert "Traceback" not in err and "Exception ignored" not in err, err
    assert "standard output closed" in err
    end = _assert_complete_and_stopped(trace, "stdout closed")
    assert end["cause"] == "stopped" and end["reason"] == "standard output closed"
