"""Fixtures of the ROS 2 tests: DDS kept on loopback, in a domain of each test's own."""

from __future__ import annotations

import itertools
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from mdle.ros2.dds import MAX_DOMAIN_ID, loopback_config

_COUNTER = itertools.count()


@pytest.fixture
def dds_env(monkeypatch: pytest.MonkeyPatch) -> dict[str, str]:
    """An environment whose DDS traffic stays on 127.0.0.1, in a domain unique to the test.

    The domain comes from the worker's process id and a counter, so parallel workers
    (and tests in one worker) never meet; this process uses it too.
    """
    domain = 1 + (os.getpid() * 17 + next(_COUNTER)) % (MAX_DOMAIN_ID - 1)
    config = loopback_config()
    env = {**os.environ, "CYCLONEDDS_URI": config, "ROS_DOMAIN_ID": str(domain),
           "PYTHONUNBUFFERED": "1"}
    monkeypatch.setenv("CYCLONEDDS_URI", config)
    monkeypatch.setenv("ROS_DOMAIN_ID", str(domain))
    return env


class Procs:
    """Subprocesses a test starts; every one still running at the end is killed."""

    def __init__(self, env: dict[str, str]) -> None:
        self.env = env
        self.started: list[subprocess.Popen[str]] = []

    def start(self, argv: list[str], out: Path, cwd: Path | None = None
              ) -> subprocess.Popen[str]:
        f = open(out, "w", encoding="utf-8")  # noqa: SIM115 - closed with the process
        p = subprocess.Popen(argv, stdout=f, stderr=subprocess.STDOUT, text=True,
                             env=self.env, cwd=cwd, stdin=subprocess.DEVNULL)
        f.close()
        self.started.append(p)
        return p

    def close(self) -> None:
        for p in self.started:
            if p.poll() is None:
                p.kill()
                p.wait(timeout=10)


@pytest.fixture
def procs(dds_env: dict[str, str]) -> Iterator[Procs]:
    """Start subprocesses in :func:`dds_env`'s environment; kills what is left."""
    p = Procs(dds_env)
    try:
        yield p
    finally:
        p.close()


def mdle_argv(*args: str) -> list[str]:
    """``mdle ARGS`` with this Python."""
    return [sys.executable, "-m", "mdle", *args]


def cyclonedds_argv(*args: str) -> list[str]:
    """The ``cyclonedds`` package's own command line, beside this Python."""
    return [str(Path(sys.executable).with_name("cyclonedds")), *args]


def wait_for_text(path: Path, text: str, timeout: float, proc: subprocess.Popen[str]
                  ) -> None:
    """Wait until ``text`` appears in the file ``path`` (fail if ``proc`` ends first)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if text in path.read_text(encoding="utf-8", errors="replace"):
            return
        if proc.poll() is not None:
            break
        time.sleep(0.1)
    pytest.fail(f"`{text}` not seen in {path.name} within {timeout} s: "
                f"{path.read_text(encoding='utf-8', errors='replace')[-2000:]}")


def element_sequence(trace: Path) -> list[tuple[str, str]]:
    """The (path, kind) of every event of a trace, in order."""
    out = []
    for line in trace.read_text(encoding="utf-8").splitlines():
        rec = json.loads(line)
        if rec.get("type") == "event":
            out.append((rec["path"], rec["kind"]))
    return out


def interrupt(proc: subprocess.Popen[str], signum: int = signal.SIGINT) -> None:
    """Send ``signum`` to ``proc``."""
    proc.send_signal(signum)
