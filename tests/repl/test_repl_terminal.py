"""`mdle repl` on a real (pseudo-)terminal: the interactive front end of the installed
command, as a user meets it: the prompt, Tab, a progress line during a run, Ctrl-C
stopping the run, Ctrl-D leaving, the history file."""

from __future__ import annotations

import os
import pty
import re
import select
import sys
import time
from pathlib import Path

_ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]|\x1b[()][A-Z0-9]|\r")


class Terminal:
    """A child process on a pseudo-terminal, read expect-style."""

    def __init__(self, argv: list[str], env: dict[str, str], cwd: Path) -> None:
        self.pid, self.fd = pty.fork()
        if self.pid == 0:  # the child: become the REPL
            os.chdir(cwd)
            os.execve(argv[0], argv, env)
        self.raw = b""

    def text(self) -> str:
        return _ANSI.sub("", self.raw.decode(errors="replace"))

    def _read(self) -> bool:
        """Add what the terminal shows within 0.1 s to ``raw``; False once it has closed."""
        ready, _, _ = select.select([self.fd], [], [], 0.1)
        if ready:
            try:
                self.raw += os.read(self.fd, 65536)
            except OSError:
                return False
        return True

    def expect(self, pattern: str, timeout: float = 60.0) -> str:
        """Read until ``pattern`` (a regex) appears in the text since the start."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            m = re.search(pattern, self.text())
            if m:
                return m.group(0)
            if not self._read():
                break
        raise AssertionError(f"never saw {pattern!r}; the terminal shows:\n{self.text()}")

    def prompt(self, n: int, timeout: float = 60.0) -> None:
        """Wait for the ``n``-th prompt: each one switches bracketed paste on as it starts.
        Keys typed before it would reach a terminal in cooked mode (Ctrl-D would be eaten
        by the line discipline); a user, too, types at the prompt."""
        end = time.monotonic() + timeout
        while self.raw.count(b"\x1b[?2004h") < n:
            if time.monotonic() > end:
                raise AssertionError(f"no prompt #{n}; the terminal shows:\n{self.text()}")
            if not self._read():
                break

    def send(self, keys: str) -> None:
        os.write(self.fd, keys.encode())

    def wait(self, timeout: float = 30.0) -> int:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            pid, status = os.waitpid(self.pid, os.WNOHANG)
            if pid:
                return os.waitstatus_to_exitcode(status)
            self._read()
        os.kill(self.pid, 9)
        raise AssertionError(f"the REPL did not exit; the terminal shows:\n{self.text()}")


def test_interactive_session_on_a_terminal(tmp_path: Path) -> None:
    exe = Path(sys.executable).with_name("mdle")
    assert exe.exists(), "the `mdle` command is not installed beside this Python"
    # PROMPT_TOOLKIT_NO_CPR: this pseudo-terminal answers no cursor-position requests
    env = {**os.environ, "XDG_DATA_HOME": str(tmp_path / "data"), "TERM": "xterm",
           "PROMPT_TOOLKIT_NO_CPR": "1",
           "COLUMNS": "120", "LINES": "40"}
    term = Terminal([str(exe), "repl", "--world", "ellipse", "--until", "inf"], env, tmp_path)
    term.expect(r"mdle repl: world `ellipse`, seed 0")
    term.prompt(1)
    # Tab completes the law and its parameter; Enter on open brackets continues the input
    term.send("atom spin = (tu\t(rate = 1 rad/s),\r")
    term.expect(r"\.\.\.")
    term.send("never, inf)\r")
    term.expect(r"defined spin")
    term.prompt(2)
    # a run that never ends by itself: the progress line shows, Ctrl-C stops it
    term.send("spin\r")
    term.expect(r"running spin: t [0-9.]+ s")
    term.send("\x03")
    term.expect(r"spin \(level 0\) ended by stopped at [0-9.]+ s \(Ctrl-C: robot stopped\)")
    term.prompt(3)
    term.send(":po\t\r")
    term.expect(r"odometry x 0\.00 m  y 0\.00 m")
    term.prompt(4)
    term.send("\x04")
    assert term.wait() == 0
    history = (tmp_path / "data" / "mdle" / "repl_history").read_text()
    # one entry for the two lines; the continuation line was indented for the user
    assert "+atom spin = (turn(rate = 1 rad/s),\n+    never, inf)" in history
    assert "+spin" in history and "+:pose" in history
