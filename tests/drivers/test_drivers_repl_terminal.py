"""`mdle repl --backend pioneer` on a pseudo-terminal, as a user at the robot meets it:
the banner names the robot, the first run asks (answered at the prompt), Ctrl-C stops the
robot mid-run, Ctrl-D leaves; each with the bytes the fake robot received. Every wait has
a deadline and the child is killed whatever happens."""

from __future__ import annotations

import os
import pty
import re
import select
import signal
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from mdle.drivers.arcos import Cmd

if TYPE_CHECKING:
    from tests.drivers.conftest import FakeArcos

    FakeRobot = Callable[..., FakeArcos]

_ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]|\x1b[()][A-Z0-9]|\r")


class Terminal:
    """A child process on a pseudo-terminal; reads only what is new on each wait."""

    def __init__(self, argv: list[str], env: dict[str, str], cwd: Path) -> None:
        self.pid, self.fd = pty.fork()
        if self.pid == 0:  # the child: become the REPL
            os.chdir(cwd)
            os.execve(argv[0], argv, env)
        self.raw = b""

    def text(self) -> str:
        return _ANSI.sub("", self.raw.decode(errors="replace"))

    def _read(self, timeout: float) -> bool:
        ready, _, _ = select.select([self.fd], [], [], timeout)
        if ready:
            try:
                self.raw += os.read(self.fd, 65536)
            except OSError:
                return False
        return True

    def expect(self, pattern: str, timeout: float = 20.0) -> None:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if re.search(pattern, self.text()):
                return
            if not self._read(0.1):
                break
        raise AssertionError(f"never saw {pattern!r}; the terminal shows:\n{self.text()}")

    def prompts(self, n: int, timeout: float = 20.0) -> None:
        """Wait for the n-th prompt (each switches bracketed paste on as it starts)."""
        end = time.monotonic() + timeout
        while self.raw.count(b"\x1b[?2004h") < n:
            if time.monotonic() > end or not self._read(0.1):
                raise AssertionError(f"no prompt #{n}; the terminal shows:\n{self.text()}")

    def send(self, keys: str) -> None:
        os.write(self.fd, keys.encode())

    def wait(self, timeout: float = 20.0) -> int:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            pid, status = os.waitpid(self.pid, os.WNOHANG)
            if pid:
                return os.waitstatus_to_exitcode(status)
            self._read(0.1)
        self.kill()
        raise AssertionError(f"the REPL did not exit; the terminal shows:\n{self.text()}")

    def kill(self) -> None:
        try:
            os.kill(self.pid, signal.SIGKILL)
            os.waitpid(self.pid, 0)
        except (ProcessLookupError, ChildProcessError):
            pass
        os.close(self.fd)


def test_a_user_at_the_robot(fake_robot: FakeRobot, tmp_path: Path) -> None:
    exe = Path(sys.executable).with_name("mdle")
    assert exe.exists(), "the `mdle` command is not installed beside this Python"
    fake = fake_robot()
    env = {**os.environ, "XDG_DATA_HOME": str(tmp_path / "data"), "TERM": "xterm",
           "PROMPT_TOOLKIT_NO_CPR": "1", "COLUMNS": "120", "LINES": "40"}
    term = Terminal([str(exe), "repl", "--backend", "pioneer", "--connect", fake.url,
                     "--laser", "sim"], env, tmp_path)
    try:
        term.expect(r"mdle repl: `FakeSim` \(p3dx-sh\) on tcp://127\.0\.0\.1:\d+, laser sim")
        term.prompts(1)
        term.send("atom creep = (go(0.3 m/s), never, 60 s)\r")
        term.expect(r"defined creep")
        term.prompts(2)
        term.send("creep\r")
        term.expect(r"will move\. Is the space around it clear")
        assert set(fake.args(Cmd.VEL)) <= {0}  # nothing moves before the answer
        term.expect(r"\[y/N\]")
        time.sleep(0.5)  # let prompt_toolkit take the terminal before answering
        term.send("y\r")
        assert fake.wait_for(lambda: fake.v_mm == 300, timeout=10.0)
        moved = fake.commands(Cmd.VEL)[-1].t
        term._read(0.2)
        shown = term.raw.count(b"\x1b[?2004h")  # prompts so far (the run shows none)
        term.send("\x03")  # Ctrl-C mid-run
        term.expect(r"creep \(level 0\) was stopped from outside at [0-9.]+ s \(Ctrl-C: robot "
                    r"stopped\)")
        assert fake.wait_for(lambda: any(r.arg == 0 and r.t > moved
                                         for r in fake.commands(Cmd.VEL)), timeout=2.0)
        assert fake.v_mm == 0
        term.prompts(shown + 1)
        term.send("\x04")  # Ctrl-D leaves: the goodbye
        assert term.wait() == 0
        term.expect(r"robot stopped; connection to tcp://127\.0\.0\.1:\d+ closed")
    finally:
        term.kill()
    assert fake.wait_for(lambda: fake.commands(Cmd.CLOSE) != [], timeout=2.0)
    assert [c for c, _ in [(r.cmd, r.arg) for r in fake.received][-2:]] == [
        Cmd.SIM_LRF_ENABLE, Cmd.CLOSE]
