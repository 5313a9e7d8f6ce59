"""Ctrl-C in every long phase: how soon mdle exits after SIGINT (issue 26).

Run:  python benchmarks/interrupts.py [--repeat 5] [--phases check world ...]

Each phase is a command that spends seconds in one place: checking a plan of 200,000
lines, loading a world of 200,000 circles, of 20,000 rectangles or of a 3000 x 3000
pixel map, compiling a plan of 30,000 atoms in one string, a sweep, an experiment,
connecting to a robot that never answers, and writing a plot and an MCAP file of a
trace of 100,000 samples. The command is started in a fresh process, SIGINT is sent once
it is inside the phase (a delay after the start, phase by phase), and two times are
measured from the signal on the wall clock (the only clock a user at the keyboard has):
until mdle says ``interrupted`` (the answer: by then the robot is stopped and the
trace ended) and until the process has exited (Python then frees what the phase built,
a world of 200,000 circles takes a while). Prints, per phase, the exit codes and the
median and largest of each over the repeats. mdle answers within 100 ms when its main thread runs
Python (a signal is acted on between two bytecodes) or waits on a thread that does the
work; a long call into C that holds the interpreter (shapely's union of thousands of
polygons, matplotlib's drawing of a long path) is cut into pieces.

On a busy machine the latency includes waiting for a core: compare phases with each
other, and with the same run of ``--phases idle`` (a command that sleeps). ``--stalls``
measures what no load changes instead: each phase runs to its end in a process whose
SIGPROF timer fires every 5 ms of CPU, and the longest CPU stretch between two runs of
its Python handler is printed (a signal waits at most that long, in CPU time), with
where the interpreter resumed.
"""

from __future__ import annotations

import argparse
import os
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

PLAN = "atom a = (go(0.3 m/s), never, 1 s)\nrun a\n"


@dataclass(frozen=True)
class Phase:
    """A command whose long phase is interrupted ``delay`` s after its start."""

    name: str
    argv: list[str]
    delay: float


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
    """Write a trace of ``samples`` samples by running a plan (10 Hz) in this process."""
    plan = path.with_suffix(".mdle")
    plan.write_text("atom a = (arc(0.2 m/s, omega = 10 deg/s), never, 1000000 s)\nrun a\n")
    subprocess.run([sys.executable, "-m", "mdle", "run", str(plan), "--world", "empty",
                    "-q", "--until", f"{samples / 100:g}", "--rate", "100",
                    "--trace", str(path)], check=False, capture_output=True)


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


def phases(folder: Path, port: int) -> list[Phase]:
    """Write every phase's inputs into ``folder``; return the phases."""
    f = str(folder)
    (folder / "p.mdle").write_text(PLAN)
    big_plan(folder / "big.mdle", 200_000)
    long_string_plan(folder / "string.mdle", 30_000)
    circles_world(folder / "circles.yaml", 200_000)
    rectangles_world(folder / "rects.yaml", 20_000)
    mapped = map_world(folder, 3000)
    big_trace(folder / "t.jsonl", 100_000)
    (folder / "study.yaml").write_text(
        f"plan: {f}/p.mdle\nworlds: [default]\nseeds: {{count: 100000}}\nduration: 5\n")
    return [
        Phase("idle", [sys.executable, "-c", "import time; time.sleep(30)"], 1.0),
        Phase("check", ["check", f"{f}/big.mdle"], 2.5),
        Phase("world-circles", ["run", f"{f}/p.mdle", "--world", f"{f}/circles.yaml", "-q"],
              3.0),
        Phase("world-rectangles", ["run", f"{f}/p.mdle", "--world", f"{f}/rects.yaml", "-q"],
              2.5),
        Phase("world-map", ["run", f"{f}/p.mdle", "--world", str(mapped), "-q"], 2.5),
        Phase("compile", ["run", f"{f}/string.mdle", "--world", "empty", "-q"], 2.5),
        Phase("sweep", ["sweep", f"{f}/study.yaml", "--out", f"{f}/sweep-out", "--jobs", "1"],
              3.0),
        Phase("experiment", ["experiment", "random-starts", "--generated", "--shapes", "40",
                             "--jobs", "1"], 3.0),
        Phase("robot-connect", ["run", f"{f}/p.mdle", "--backend", "pioneer", "--connect",
                                f"tcp://127.0.0.1:{port}", "-q"], 2.0),
        Phase("write-plot", ["plot", f"{f}/t.jsonl", "-o", f"{f}/t.png"], 2.0),
        Phase("write-mcap", ["export", f"{f}/t.jsonl", "-o", f"{f}/t.mcap"], 2.0),
    ]


@dataclass(frozen=True)
class Outcome:
    """One interruption: exit code, seconds to the message and to the exit (-1: none)."""

    code: int
    answered: float
    exited: float
    stderr: str


def interrupt(argv: list[str], delay: float, cwd: Path) -> Outcome:
    """Start ``argv`` and send SIGINT after ``delay`` s; time the answer and the exit."""
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
    time.sleep(delay)
    if proc.poll() is not None:  # the phase was over before the signal
        reader.join(5)
        return Outcome(proc.returncode, -1.0, -1.0, "".join(lines))
    sent = time.monotonic()
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=120)
    exited = time.monotonic() - sent
    reader.join(5)
    return Outcome(proc.returncode, said[0] - sent if said else -1.0, exited, "".join(lines))


def _spread(times: list[float]) -> str:
    """Return ``median / max`` of the times measured (ms), or why there are none."""
    got = [t for t in times if t >= 0]
    if not got:
        return "-"
    return f"{1000 * statistics.median(got):.0f}/{1000 * max(got):.0f} ms"


def probe(argv: list[str]) -> None:
    """Run ``mdle argv`` in this process; print its longest CPU stretches without a handler."""
    import traceback

    # benchmarks/mcap.py would stand for the mcap package: mdle is imported without it
    here = Path(__file__).resolve().parent
    sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != here]
    stalls: list[tuple[float, str]] = []
    last = [time.process_time()]

    def tick(signum: int, frame: object) -> None:
        gap = time.process_time() - last[0]
        if gap > 0.02:
            where = traceback.format_stack(frame, limit=2)[-1].strip().splitlines()[0]  # type: ignore[arg-type]
            stalls.append((gap, where))
        last[0] = time.process_time()  # the handler's own time is not a stall

    signal.signal(signal.SIGPROF, tick)
    signal.setitimer(signal.ITIMER_PROF, 0.005, 0.005)
    from mdle.cli import main as mdle_main

    out = sys.stdout
    try:
        with open(os.devnull, "w") as sys.stdout:  # mdle's own output is not the point
            code = mdle_main(argv)
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0, 0)
        sys.stdout = out
    stalls.sort(reverse=True)
    worst = ", ".join(f"{1000 * g:.0f} ms ({w})" for g, w in stalls[:2]) or "none over 20 ms"
    print(f"exit {code}, {time.process_time():.2f} s CPU; longest: {worst}")


def main() -> None:
    """Measure every phase (or those named) ``--repeat`` times."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--phases", nargs="+", default=None)
    ap.add_argument("--stalls", action="store_true")
    ap.add_argument("--probe", nargs=argparse.REMAINDER, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.probe is not None:
        probe(a.probe)
        return
    srv, _ = silent_robot()
    with tempfile.TemporaryDirectory(prefix="mdle-interrupts-") as tmp:
        folder = Path(tmp)
        print("writing the inputs...", flush=True)
        chosen = [p for p in phases(folder, srv.getsockname()[1])
                  if a.phases is None or p.name in a.phases]
        for phase in chosen:
            if a.stalls:
                if phase.name in ("idle", "robot-connect", "sweep", "experiment"):
                    continue  # waits (on a robot, on workers), or runs for hours to its end
                print(f"{phase.name:17} ", end="", flush=True)
                subprocess.run([sys.executable, __file__, "--probe", *phase.argv], cwd=folder,
                               env=dict(os.environ, MPLBACKEND="Agg"), check=False,
                               stderr=subprocess.DEVNULL)
                continue
            runs = [interrupt(phase.argv, phase.delay, folder) for _ in range(a.repeat)]
            codes = sorted({r.code for r in runs})
            last = runs[-1].stderr.strip().splitlines()[-1] if runs[-1].stderr.strip() else ""
            print(f"{phase.name:17} exit {codes}  answered {_spread([r.answered for r in runs])}"
                  f"  exited {_spread([r.exited for r in runs])}  ({last[:60]})", flush=True)
    srv.close()


if __name__ == "__main__":
    main()
