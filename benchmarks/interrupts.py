"""Ctrl-C and SIGTERM in every long phase: how soon mdle answers and exits (issue 26).

Run:  python benchmarks/interrupts.py [--repeat 5] [--signals INT TERM] [--phases check ...]
      python benchmarks/interrupts.py --stalls [--phases check ...]

Each phase is a command that spends seconds in one place, at the largest inputs the
limits allow: checking a plan of 200,000 lines (10.7 MB), loading a world of 200,000
circles (12 MB), of 20,000 rectangles or of a 3000 x 3000 pixel map, compiling a plan
of 30,000 atoms in one string, a sweep, an experiment, connecting to a robot that never
answers, and writing a plot and an MCAP file of a trace of 100,000 samples. Only the
inputs of the phases asked for are written.

Without ``--stalls``, the command is started in a fresh process and the signal is sent
once it is inside the phase: once the process has used the phase's CPU seconds (read
from /proc, so a busy machine does not move the moment), or after a delay on the wall
clock for the phases that wait (on a robot, on workers). Two times are measured from
the signal on the wall clock (the only clock a user at the keyboard has): until mdle
says ``interrupted`` (the answer: by then the robot is stopped and the trace ended) and
until the process has exited; and the CPU time the process spent from the signal to
its exit, which the machine's load does not change. Prints, per phase and signal, the
exit codes and the median and largest of each over the repeats. On a busy machine the
wall times include waiting for a core: compare them with the same run of the ``idle``
phase (a command that sleeps).

``--stalls`` measures what no load changes instead: each phase runs to its end (the
command's own end included: what it frees, the garbage collector's passes) in a
process whose SIGPROF timer fires every 5 ms of CPU, and prints the longest CPU
stretches between two runs of the Python handler (a signal waits at most that long, in
CPU time), with where the interpreter resumed, and the longest pass of the cycle
collector. The process then ends as the console script does. A sweep and an
experiment, which would run for hours, get a SIGINT after 20 s of it (planning the
sweep's 600,000 runs, the first runs, and the interrupted end are measured).
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import FrameType

import numpy as np

PLAN = "atom a = (go(0.3 m/s), never, 1 s)\nrun a\n"


@dataclass(frozen=True)
class Phase:
    """A command whose long phase is interrupted once it has used ``cpu`` s of CPU.

    ``cpu`` None: the phase waits (on a robot, on workers) and is interrupted ``delay``
    s after its start instead. ``inputs`` writes what the command reads.
    """

    name: str
    argv: list[str]
    cpu: float | None
    delay: float = 0.0
    inputs: Callable[[Path], object] = lambda folder: None


def big_plan(path: Path, lines: int) -> None:
    """Write a plan of ``lines`` atom definitions and a run of the first."""
    body = "".join(f"atom a{i} = (go(0.3 m/s), range(0 deg) < {1 + i % 7} m, {1 + i % 5} s)\n"
                   for i in range(lines))
    path.write_text(body + "run a0\n")


def long_string_plan(path: Path, atoms: int) -> None:
    """Write a plan whose one string holds ``atoms`` distinct atoms (compiled at run)."""
    parts = ", ".join(f"(go({0.1 + (i % 9) / 100:.2f} m/s), never, 0.01 s)"
                      for i in range(atoms))
    path.write_text(f"plan main = (({parts}), never, 1 s)\nrun main\n")


def circles_world(path: Path, n: int) -> None:
    """Write a world of ``n`` circles around an empty start."""
    rng = np.random.default_rng(0)
    side = 2.0 * np.sqrt(n)
    xy = rng.uniform(-side, side, size=(2 * n + 16, 2))
    xy = xy[np.hypot(xy[:, 0], xy[:, 1]) > 2.0][:n]
    lines = ["name: circles", "start: {x: 0, y: 0, theta: 0}", "obstacles:"]
    lines += [f"  - {{type: circle, center: [{x:.3f}, {y:.3f}], radius: 0.2}}" for x, y in xy]
    path.write_text("\n".join(lines) + "\n")


def rectangles_world(path: Path, n: int) -> None:
    """Write a world of ``n`` small rectangles on a grid around an empty start."""
    side = int(np.ceil(np.sqrt(n + 9)))
    lines = ["name: rectangles", "start: {x: 0.5, y: 0.5, theta: 0}", "obstacles:"]
    k = 0
    for i in range(side):
        for j in range(side):
            if k == n:
                break
            if abs(i - side // 2) <= 1 and abs(j - side // 2) <= 1:
                continue
            x, y = 2.0 * (i - side // 2), 2.0 * (j - side // 2)
            lines.append(f"  - {{type: rectangle, center: [{x}, {y}], size: [0.7, 0.4]}}")
            k += 1
    path.write_text("\n".join(lines) + "\n")


def map_world(folder: Path, pixels: int) -> Path:
    """Write a map of ``pixels`` x ``pixels`` cells (random walls) and a world using it."""
    rng = np.random.default_rng(1)
    img = np.full((pixels, pixels), 254, dtype=np.uint8)
    for _ in range(pixels // 2):
        r, c = rng.integers(0, pixels, 2)
        length = int(rng.integers(5, 60))
        if rng.random() < 0.5:
            img[r, c:c + length] = 0
        else:
            img[r:r + length, c] = 0
    mid = pixels // 2
    img[mid - 20:mid + 20, mid - 20:mid + 20] = 254
    header = f"P5\n{pixels} {pixels}\n255\n".encode()
    (folder / "big.pgm").write_bytes(header + img.tobytes())
    (folder / "big.map.yaml").write_text(
        "image: big.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
    world = folder / "map.world.yaml"
    centre = mid * 0.05
    world.write_text(f"name: mapped\nstart: {{x: {centre}, y: {centre}, theta: 0}}\n"
                     "map: big.map.yaml\n")
    return world


def big_trace(path: Path, samples: int) -> None:
    """Write a trace of ``samples`` samples at 100 Hz, a slow arc (once per folder)."""
    if path.exists():
        return
    head = [{"type": "header", "format": "mdle-trace", "version": 1,
             "program": {"file": "p.mdle", "element": "a", "entry": "a"}, "rate": 100.0,
             "backend": "sim", "world": "empty"},
            {"type": "start", "element": "a", "rate": 100.0}]
    sample = {"type": "sample", "path": "a", "v": 0.2, "omega": 0.17, "cmd_v": 0.2,
              "cmd_omega": 0.17, "lateness": 0, "stalled": False, "scan_age": 0,
              "clearance": 1.0, "collided": False}
    with path.open("w") as f:
        for h in head:
            f.write(json.dumps(h) + "\n")
        for i in range(samples):
            t = i * 0.01
            f.write(json.dumps({**sample, "t": t, "x": 1.15 * np.sin(0.17 * t),
                                "y": 1.15 * (1 - np.cos(0.17 * t)), "theta": 0.17 * t})
                    + "\n")
        f.write(json.dumps({"type": "end", "path": "a", "cause": "completed",
                            "t": samples / 100, "ticks": samples, "duration": samples / 100,
                            "distance": 0.002 * samples, "collided": False, "fault": None})
                + "\n")


def silent_robot() -> tuple[socket.socket, threading.Thread]:
    """Listen on 127.0.0.1: accept connections and never answer (a robot that hangs)."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(8)
    held: list[socket.socket] = []

    def serve() -> None:
        while True:
            try:
                conn, _ = srv.accept()
            except OSError:
                return
            held.append(conn)

    th = threading.Thread(target=serve, daemon=True)
    th.start()
    return srv, th


def phases(port: int) -> list[Phase]:
    """Return the phases; each writes its inputs into the folder it is given."""
    # 600,000 runs to plan: every axis at most 100,000 (docs/limits.md)
    study = ("plan: p.mdle\nworlds: [default, empty]\nrates: [10, 20, 50]\n"
             "seeds: {count: 100000}\nduration: 5\n")
    return [
        Phase("idle", [sys.executable, "-c", "import time; time.sleep(30)"], None, 1.0),
        # while Python starts and mdle is imported: the signal is held to the command's start
        Phase("start-up", ["check", "p.mdle"], 0.08),
        Phase("check", ["check", "big.mdle"], 2.5,
              inputs=lambda f: big_plan(f / "big.mdle", 200_000)),
        Phase("world-circles", ["run", "p.mdle", "--world", "circles.yaml", "-q", "--trace",
                                "t-circles.jsonl"], 3.0,
              inputs=lambda f: circles_world(f / "circles.yaml", 200_000)),
        Phase("world-rectangles", ["run", "p.mdle", "--world", "rects.yaml", "-q"], 1.5,
              inputs=lambda f: rectangles_world(f / "rects.yaml", 20_000)),
        Phase("world-map", ["run", "p.mdle", "--world", "map.world.yaml", "-q"], 0.35,
              inputs=lambda f: map_world(f, 3000)),
        Phase("compile", ["run", "string.mdle", "--world", "empty", "-q", "--trace",
                          "t-string.jsonl"], 2.0,
              inputs=lambda f: long_string_plan(f / "string.mdle", 30_000)),
        Phase("sweep", ["sweep", "study.yaml", "--out", "sweep-out", "--jobs", "1"], None, 5.0,
              inputs=lambda f: (f / "study.yaml").write_text(study)),
        Phase("experiment", ["experiment", "random-starts", "--generated", "--shapes", "40",
                             "--jobs", "1"], 1.5),
        Phase("robot-connect", ["run", "p.mdle", "--backend", "pioneer", "--connect",
                                f"tcp://127.0.0.1:{port}", "-q"], None, 2.0),
        Phase("write-plot", ["plot", "t.jsonl", "-o", "t.png"], 1.5,
              inputs=lambda f: big_trace(f / "t.jsonl", 100_000)),
        Phase("write-mcap", ["export", "t.jsonl", "-o", "t.mcap"], 0.8,
              inputs=lambda f: big_trace(f / "t.jsonl", 100_000)),
    ]


@dataclass(frozen=True)
class Outcome:
    """One interruption: exit code, seconds to the message and to the exit (-1: none).

    ``cpu``: the CPU seconds the process spent from the signal to its exit (the
    signal-to-exit delay on a machine with a core to spare).
    """

    code: int
    answered: float
    exited: float
    stderr: str
    cpu: float = -1.0


_TICK = os.sysconf("SC_CLK_TCK")


def cpu_of(pid: int) -> float:
    """Return the CPU seconds (user + system) process ``pid`` has used so far."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / _TICK


def interrupt(phase: Phase, signum: int, cwd: Path) -> Outcome:
    """Start the phase's command, send ``signum`` inside the phase; time answer and exit."""
    argv = phase.argv
    cmd = argv if argv[0] == sys.executable else [sys.executable, "-m", "mdle", *argv]
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)
    lines: list[str] = []
    said: list[float] = []

    def read() -> None:
        assert proc.stderr is not None
        for line in proc.stderr:
            if not said and "nterrupt" in line:
                said.append(time.monotonic())
            lines.append(line)

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    started = time.monotonic()
    while proc.poll() is None and time.monotonic() - started < 120:
        if (cpu_of(proc.pid) >= phase.cpu if phase.cpu is not None
                else time.monotonic() - started >= phase.delay):
            break
        time.sleep(0.005)
    if proc.poll() is not None:  # the phase was over before the signal
        reader.join(5)
        return Outcome(proc.returncode, -1.0, -1.0, "".join(lines))
    before = cpu_of(proc.pid)
    sent = time.monotonic()
    proc.send_signal(signum)
    hang = threading.Timer(120.0, proc.kill)
    hang.start()
    _, status, usage = os.wait4(proc.pid, 0)  # reaped here, for its CPU time
    hang.cancel()
    exited = time.monotonic() - sent
    proc.returncode = os.waitstatus_to_exitcode(status)
    reader.join(5)
    return Outcome(proc.returncode, said[0] - sent if said else -1.0, exited, "".join(lines),
                   usage.ru_utime + usage.ru_stime - before)


def _spread(times: list[float]) -> str:
    """Return ``median / max`` of the times measured (ms), or why there are none."""
    got = [t for t in times if t >= 0]
    if not got:
        return "-"
    return f"{1000 * statistics.median(got):.0f}/{1000 * max(got):.0f} ms"


def _where(frame: FrameType | None) -> str:
    """Name the innermost frames of the stack (files and lines only: no source is read)."""
    out: list[str] = []
    while frame is not None and len(out) < 3:
        out.append(f"{Path(frame.f_code.co_filename).name}:{frame.f_lineno} "
                   f"{frame.f_code.co_name}")
        frame = frame.f_back
    return " < ".join(out)


def probe(argv: list[str], stop: float | None = None) -> None:
    """Run ``mdle argv`` as the console script; print its longest CPU stretches without a handler.

    The report is printed when the command has returned, before the process ends the
    way the console script ends it. ``stop``: seconds after which the command gets a
    SIGINT (a sweep would run for hours); its interrupted end is measured too.
    """
    # benchmarks/mcap.py would stand for the mcap package: mdle is imported without it
    here = Path(__file__).resolve().parent
    sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != here]
    stalls: list[tuple[float, str]] = []
    last = [time.process_time()]
    passes: list[tuple[float, int]] = []  # (CPU seconds, generation) of each collection
    began = [0.0]

    def tick(signum: int, frame: FrameType | None) -> None:
        gap = time.process_time() - last[0]
        if gap > 0.02:
            stalls.append((gap, _where(frame)))
        last[0] = time.process_time()  # the handler's own time is not a stall

    def collection(phase: str, info: dict[str, int]) -> None:
        if phase == "start":
            began[0] = time.process_time()
        else:
            passes.append((time.process_time() - began[0], info["generation"]))

    gc.callbacks.append(collection)
    signal.signal(signal.SIGPROF, tick)
    signal.setitimer(signal.ITIMER_PROF, 0.005, 0.005)
    from mdle.cli import main as mdle_main

    out = sys.stdout
    sys.argv = ["mdle", *argv]
    if stop is not None:
        threading.Timer(stop, os.kill, (os.getpid(), signal.SIGINT)).start()
    try:
        with open(os.devnull, "w") as sys.stdout:  # mdle's own output is not the point
            code = mdle_main()
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0, 0)
        sys.stdout = out
    stalls.sort(reverse=True)
    worst = "; ".join(f"{1000 * g:.0f} ms ({w})" for g, w in stalls[:3]) or "none over 20 ms"
    gc_worst = max(passes, default=(0.0, 0))
    print(f"exit {code}, {time.process_time():.2f} s CPU; longest collection "
          f"{1000 * gc_worst[0]:.0f} ms (generation {gc_worst[1]}); longest: {worst}",
          flush=True)
    sys.exit(code)


def main() -> None:
    """Measure every phase (or those named) ``--repeat`` times, with each signal."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--phases", nargs="+", default=None)
    ap.add_argument("--signals", nargs="+", default=["INT", "TERM"],
                    choices=["INT", "TERM", "HUP"])
    ap.add_argument("--stalls", action="store_true")
    ap.add_argument("--stop", type=float, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--probe", nargs=argparse.REMAINDER, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.probe is not None:
        probe(a.probe, a.stop)
        return
    srv, _ = silent_robot()
    with tempfile.TemporaryDirectory(prefix="mdle-interrupts-") as tmp:
        folder = Path(tmp)
        (folder / "p.mdle").write_text(PLAN)
        chosen = [p for p in phases(srv.getsockname()[1])
                  if a.phases is None or p.name in a.phases]
        print("writing the inputs...", flush=True)
        for phase in chosen:
            phase.inputs(folder)
        for phase in chosen:
            if a.stalls:
                if phase.name in ("idle", "robot-connect", "start-up"):
                    continue  # waits (on the clock, on a robot), or is over at once
                # a sweep and an experiment run for hours: stopped by a SIGINT after 20 s
                stop = ["--stop", "20"] if phase.name in ("sweep", "experiment") else []
                print(f"{phase.name:17} ", end="", flush=True)
                subprocess.run([sys.executable, __file__, *stop, "--probe", *phase.argv],
                               cwd=folder, env=dict(os.environ, MPLBACKEND="Agg"), check=False,
                               stderr=subprocess.DEVNULL)
                continue
            for name in a.signals:
                signum = signal.Signals[f"SIG{name}"]
                runs = [interrupt(phase, signum, folder) for _ in range(a.repeat)]
                codes = sorted({r.code for r in runs})
                last = (runs[-1].stderr.strip().splitlines()[-1]
                        if runs[-1].stderr.strip() else "")
                print(f"{phase.name:17} SIG{name:4} exit {codes}  answered "
                      f"{_spread([r.answered for r in runs])}  exited "
                      f"{_spread([r.exited for r in runs])}  CPU to exit "
                      f"{_spread([r.cpu for r in runs if r.exited >= 0])}  ({last[:50]})",
                      flush=True)
    srv.close()


if __name__ == "__main__":
    main()
