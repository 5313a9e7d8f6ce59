"""`mdle repl --backend pioneer` on the fake ARCOS server over TCP.

The installed command runs in a subprocess with piped input, as a script would drive it;
each step checks the bytes the fake robot received: a stop at the end of a run, on
Ctrl-C, on ``:quit``, and keep-alives while the prompt is idle. Every wait has a deadline
and the process is killed whatever happens.
"""

from __future__ import annotations

import os
import queue
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO, TYPE_CHECKING

import pytest

from mdle.drivers.arcos import Cmd

if TYPE_CHECKING:
    from tests.drivers.conftest import FakeArcos

    FakeRobot = Callable[..., FakeArcos]


class ReplProcess:
    """An ``mdle repl`` child process: write lines, wait for output, with deadlines."""

    def __init__(self, argv: list[str], cwd: Path) -> None:
        env = {**os.environ, "XDG_DATA_HOME": str(cwd / "data")}
        self.proc = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True, cwd=cwd, env=env)
        self.out: list[str] = []
        self.err: list[str] = []
        self._lines: queue.Queue[tuple[str, str]] = queue.Queue()
        for name, stream in (("out", self.proc.stdout), ("err", self.proc.stderr)):
            assert stream is not None
            threading.Thread(target=self._pump, args=(name, stream), daemon=True).start()

    def _pump(self, name: str, stream: IO[str]) -> None:
        for line in stream:
            self._lines.put((name, line))

    def _collect(self, timeout: float) -> None:
        try:
            name, line = self._lines.get(timeout=timeout)
        except queue.Empty:
            return
        (self.out if name == "out" else self.err).append(line)

    def send(self, text: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(text)
        self.proc.stdin.flush()

    def expect(self, needle: str, timeout: float = 15.0) -> None:
        """Wait until ``needle`` appears on stdout or stderr."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if needle in "".join(self.out) or needle in "".join(self.err):
                return
            self._collect(0.05)
        raise AssertionError(f"never saw {needle!r}\nstdout:\n{''.join(self.out)}\n"
                             f"stderr:\n{''.join(self.err)}")

    def wait(self, timeout: float = 15.0) -> int:
        try:
            code = self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            raise AssertionError("the REPL did not exit:\n"
                                 + "".join(self.out + self.err)) from None
        while not self._lines.empty():
            self._collect(0.0)
        time.sleep(0.1)
        while not self._lines.empty():
            self._collect(0.0)
        return code

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(timeout=10)


@pytest.fixture
def repl_on(mdle_command: list[str], tmp_path: Path) -> Iterator[Callable[..., ReplProcess]]:
    """``repl_on(fake, *args)``: an ``mdle repl`` driving ``fake``, killed afterwards."""
    made: list[ReplProcess] = []

    def start(fake: FakeArcos, *args: str) -> ReplProcess:
        p = ReplProcess([*mdle_command, "repl", "--backend", "pioneer", "--connect",
                         fake.url, *args], tmp_path)
        made.append(p)
        return p

    yield start
    for p in made:
        p.kill()


def _moves(fake: FakeArcos) -> list[int]:
    return [a for a in fake.args(Cmd.VEL) if isinstance(a, int)]


def _stopped_after(fake: FakeArcos, t: float) -> bool:
    """A VEL 0 and an RVEL 0 arrived after time ``t`` (the fake's clock)."""
    return (any(r.arg == 0 and r.t > t for r in fake.commands(Cmd.VEL))
            and any(r.arg == 0 and r.t > t for r in fake.commands(Cmd.RVEL)))


def test_define_run_ctrl_c_quit_each_stop_the_robot(fake_robot: FakeRobot,
                                                    repl_on: Callable[..., ReplProcess]
                                                    ) -> None:
    fake = fake_robot(watchdog=0.5)
    repl = repl_on(fake, "--laser", "sim", "--yes")
    repl.send("atom fwd = (go(0.2 m/s), never, 0.6 s)\n")
    repl.expect("defined fwd", timeout=20.0)
    # run: it moves, ends by its timer, and the robot is stopped at the end
    repl.send("fwd\n")
    assert fake.wait_for(lambda: fake.v_mm == 200, timeout=10.0)
    moved = fake.commands(Cmd.VEL)[-1].t
    repl.expect("fwd (level 0) ended by timer")
    assert fake.wait_for(lambda: _stopped_after(fake, moved), timeout=2.0)
    assert fake.v_mm == 0 and fake.w_deg == 0
    # idle at the prompt for longer than the firmware's watchdog: keep-alives hold it
    idle_from = fake.received[-1].t
    time.sleep(1.2)
    assert fake.watchdog_trips == 0
    pulses = [r.t for r in fake.commands(Cmd.PULSE) if r.t > idle_from]
    assert len(pulses) >= 2
    # Ctrl-C during a long run: the robot stops, the session goes on
    repl.send("atom long = (go(0.3 m/s), never, 60 s)\nlong\n")
    assert fake.wait_for(lambda: fake.v_mm == 300, timeout=10.0)
    moved = fake.commands(Cmd.VEL)[-1].t
    repl.proc.send_signal(signal.SIGINT)
    repl.expect("(Ctrl-C: robot stopped)")
    assert fake.wait_for(lambda: _stopped_after(fake, moved), timeout=2.0)
    assert fake.v_mm == 0
    repl.send(":pose\n")
    repl.expect("odometry x")
    assert repl.proc.poll() is None
    # :quit: STOP, zero speeds, laser off, CLOSE on the wire; the process ends
    quit_at = fake.received[-1].t
    repl.send(":quit\n")
    code = repl.wait()
    assert code == 1  # the run stopped by Ctrl-C counts as a failed input
    tail = [(r.cmd, r.arg) for r in fake.received if r.t > quit_at
            and r.cmd != Cmd.PULSE]
    assert tail[:3] == [(Cmd.STOP, None), (Cmd.VEL, 0), (Cmd.RVEL, 0)]
    assert tail[-2:] == [(Cmd.SIM_LRF_ENABLE, 0), (Cmd.CLOSE, None)]
    assert "robot stopped; connection to tcp://127.0.0.1" in "".join(repl.err)
    assert "Traceback" not in "".join(repl.err)
    assert set(_moves(fake)) == {0, 200, 300}


def test_end_of_input_stops_and_closes(fake_robot: FakeRobot,
                                       repl_on: Callable[..., ReplProcess]) -> None:
    fake = fake_robot()
    repl = repl_on(fake, "--yes")
    assert repl.proc.stdin is not None
    repl.send("atom a = (go(0.1 m/s), never, 0.3 s)\na\n")
    repl.expect("a (level 0) ended by timer", timeout=20.0)
    repl.proc.stdin.close()  # Ctrl-D / the end of a script
    assert repl.wait() == 0
    assert fake.commands(Cmd.CLOSE) and fake.commands(Cmd.STOP)
    assert fake.v_mm == 0


def test_without_yes_a_script_may_not_move_the_robot(fake_robot: FakeRobot,
                                                     repl_on: Callable[..., ReplProcess]
                                                     ) -> None:
    fake = fake_robot()
    repl = repl_on(fake)
    repl.send("atom a = (go(0.1 m/s), never, 0.3 s)\na\n:pose\n:quit\n")
    assert repl.wait(timeout=20.0) == 1
    err = "".join(repl.err)
    assert "the robot may not move: nobody confirmed it" in err and "--yes" in err
    assert set(_moves(fake)) <= {0}
    assert "odometry x 0.00 m" in "".join(repl.out)


def test_a_lost_link_is_reported_and_the_session_goes_on(fake_robot: FakeRobot,
                                                         repl_on: Callable[..., ReplProcess]
                                                         ) -> None:
    fake = fake_robot()
    repl = repl_on(fake, "--laser", "sim", "--yes")
    repl.send("atom long = (go(0.2 m/s), never, 60 s)\nlong\n")
    assert fake.wait_for(lambda: fake.v_mm == 200, timeout=20.0)
    fake.drop()  # the robot switched off mid-run
    repl.expect("lost the robot on tcp://127.0.0.1")
    repl.send("long\n")
    repl.expect("no robot: the link to tcp://127.0.0.1")
    repl.send(":defs\n")
    repl.expect("atom long = (go(0.2 m/s), never, 60 s)")
    repl.send(":quit\n")
    assert repl.wait() == 1
    err = "".join(repl.err)
    assert "the link was already lost; connection to" in err
    assert "Traceback" not in err and "internal error" not in err


def test_sigterm_during_a_run_stops_and_closes(fake_robot: FakeRobot,
                                               repl_on: Callable[..., ReplProcess]) -> None:
    fake = fake_robot()
    repl = repl_on(fake, "--yes")
    repl.send("atom long = (go(0.25 m/s), never, 60 s)\nlong\n")
    assert fake.wait_for(lambda: fake.v_mm == 250, timeout=20.0)
    repl.proc.send_signal(signal.SIGTERM)
    assert repl.wait() == 143
    assert fake.wait_for(lambda: fake.commands(Cmd.CLOSE) != [], timeout=2.0)
    assert fake.v_mm == 0 and fake.commands(Cmd.STOP)


def test_robot_flags_without_the_backend_are_refused(mdle_command: list[str],
                                                     tmp_path: Path) -> None:
    proc = subprocess.run([*mdle_command, "repl", "--connect", "tcp://127.0.0.1:9"],
                          input="", capture_output=True, text=True, timeout=60, cwd=tmp_path)
    assert proc.returncode == 1
    assert "--connect drives a robot: it needs --backend pioneer" in proc.stderr
