"""`mdle repl` on a real (pseudo-)terminal: the interactive front end of the installed
command, as a user meets it: the prompt, Tab, a progress line during a run, Ctrl-C
stopping the run, Ctrl-D leaving, the history file."""

from __future__ import annotations

import codecs
import os
import pty
import re
import select
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

_ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]|\x1b[()][A-Z0-9]|\r")


class Terminal:
    """A child process on a pseudo-terminal, read expect-style.

    What the terminal shows is decoded once, as it arrives (an incremental decoder, the
    control codes stripped once), and ``expect`` searches only what came since its last
    match (with a small overlap), so a long session costs no more per read than a short
    one. ``close`` kills the child if it is still there: use it in a ``finally``.
    """

    #: Characters before the unsearched part that a match may still start in.
    OVERLAP = 4096

    def __init__(self, argv: list[str], env: dict[str, str], cwd: Path,
                 raw: bool = False) -> None:
        self.pid, self.fd = pty.fork()
        if self.pid == 0:  # the child: become the REPL
            if raw:  # a terminal left in raw mode: Ctrl-C is a plain byte, no SIGINT
                import tty

                tty.setraw(0)
            os.chdir(cwd)
            os.execve(argv[0], argv, env)
        self.raw = b""
        self._decoder = codecs.getincrementaldecoder("utf-8")(errors="replace")
        self._pending = ""  # decoded text whose last control code may be incomplete
        self._shown = ""  # decoded text without control codes
        self._mark = 0  # where the next expect starts searching
        self._searched = 0  # how far the current expect has searched
        self.prompts = 0  # prompts started (each switches bracketed paste on)

    def text(self) -> str:
        return self._shown + self._pending

    def _read(self) -> bool:
        """Add what the terminal shows within 0.1 s; False once it has closed."""
        ready, _, _ = select.select([self.fd], [], [], 0.1)
        if ready:
            try:
                chunk = os.read(self.fd, 65536)
            except OSError:
                return False
            if not chunk:
                return False
            tail = self.raw[-16:]
            self.raw += chunk
            self.prompts += (tail + chunk).count(b"\x1b[?2004h") - tail.count(b"\x1b[?2004h")
            text = self._pending + self._decoder.decode(chunk)
            # keep back a control code that may continue in the next chunk
            cut = text.rfind("\x1b")
            if cut >= 0 and len(text) - cut < 16 and not _ANSI.match(text, cut):
                text, self._pending = text[:cut], text[cut:]
            else:
                self._pending = ""
            self._shown += _ANSI.sub("", text)
        return True

    def expect(self, pattern: str, timeout: float = 60.0) -> str:
        """Read until ``pattern`` (a regex) appears in what came since the last match."""
        end = time.monotonic() + timeout
        regex = re.compile(pattern)
        self._searched = self._mark
        while time.monotonic() < end:
            start = max(self._mark, self._searched - self.OVERLAP)
            m = regex.search(self._shown, start)
            self._searched = len(self._shown)
            if m:
                self._mark = m.end()
                return m.group(0)
            if not self._read():
                break
        raise AssertionError(f"never saw {pattern!r}; the terminal shows:\n{self.text()}")

    def prompt(self, n: int, timeout: float = 60.0) -> None:
        """Wait for the ``n``-th prompt: each one switches bracketed paste on as it starts.
        Keys typed before it would reach a terminal in cooked mode (Ctrl-D would be eaten
        by the line discipline); a user, too, types at the prompt."""
        end = time.monotonic() + timeout
        while self.prompts < n:
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
                self.pid = 0
                return os.waitstatus_to_exitcode(status)
            self._read()
        raise AssertionError(f"the REPL did not exit; the terminal shows:\n{self.text()}")

    def close(self) -> None:
        """Kill the child if it still runs, and close the terminal."""
        if self.pid:
            try:
                os.kill(self.pid, 9)
                os.waitpid(self.pid, 0)
            except OSError:
                pass
            self.pid = 0
        try:
            os.close(self.fd)
        except OSError:
            pass


@pytest.fixture
def terminal(tmp_path: Path) -> Iterator[Callable[..., Terminal]]:
    """Start ``mdle repl ARGS`` on a pseudo-terminal; killed at the end whatever happens."""
    exe = Path(sys.executable).with_name("mdle")
    assert exe.exists(), "the `mdle` command is not installed beside this Python"
    # PROMPT_TOOLKIT_NO_CPR: this pseudo-terminal answers no cursor-position requests
    env = {**os.environ, "XDG_DATA_HOME": str(tmp_path / "data"), "TERM": "xterm",
           "PROMPT_TOOLKIT_NO_CPR": "1",
           "COLUMNS": "120", "LINES": "40"}
    started: list[Terminal] = []

    def start(*args: str, raw: bool = False) -> Terminal:
        term = Terminal([str(exe), "repl", *args], env, tmp_path, raw=raw)
        started.append(term)
        return term

    try:
        yield start
    finally:
        for term in started:
            term.close()


def test_interactive_session_on_a_terminal(
        tmp_path: Path, terminal: Callable[..., Terminal]) -> None:
    term = terminal("--world", "ellipse", "--until", "inf")
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
    term.expect(r"spin \(level 0\) was stopped from outside at [0-9.]+ s \(Ctrl-C: robot stopped\)")
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


def test_ctrl_c_stops_a_run_on_a_terminal_left_in_raw_mode(
        terminal: Callable[..., Terminal]) -> None:
    # Raw mode (no ISIG): the kernel turns Ctrl-C into no signal at all. The REPL switches
    # ISIG on for the length of each run, so the key still stops it.
    term = terminal("--world", "ellipse", "--until", "inf", raw=True)
    term.prompt(1)
    term.send("(turn(1 rad/s), never, inf)\r")
    term.expect(r"running \S+: t [0-9.]+ s")
    term.send("\x03")
    term.expect(r"was stopped from outside at [0-9.]+ s \(Ctrl-C: robot stopped\)")
    term.prompt(2)
    term.send("\x04")
    assert term.wait() == 0


def test_sigterm_ends_a_session_with_the_robot_stopped(
        terminal: Callable[..., Terminal]) -> None:
    term = terminal("--world", "ellipse", "--until", "inf")
    term.prompt(1)
    term.send("(turn(1 rad/s), never, inf)\r")
    term.expect(r"running \S+: t [0-9.]+ s")
    os.kill(term.pid, 15)
    term.expect(r"interrupted by SIGTERM")
    assert term.wait() == 143
