"""Interpreter overhead per tick: interrupts, timers, dispatch and the trace record.

A plan ten levels deep (nine strings and an atom), each level with its own interrupt
and timer, so every tick tests ten interrupts and ten timers, runs against a trivial
backend whose observe/command/advance cost next to nothing. The backend replays a robot
driving an arc, so pose, velocity and time carry full-precision floats as a real run's
do (formatting 0.5 takes half the time of 0.4817366102...; a constant round pose would
flatter the trace writer). The figure is wall time per tick, the backend's own cost
subtracted; the target is at most 10 microseconds with the trace written.

Two plans of that shape are timed: one built by hand from :mod:`mdle.lang.program` nodes
whose interrupts are a single cheap function each, and one written in MDLe and compiled
by the checker, whose interrupts are the real closures (sensor calls, comparisons, ``and``
and ``or``) a user's plan gets.

Timings are noisy on a shared machine: each figure is the median and the minimum of
``--repeat`` runs, the two variants interleaved, with the load average printed.

Run: ``python benchmarks/runtime.py [--ticks N] [--repeat R]``.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import tempfile
import time

from mdle.atoms.registry import Context, LawSpec
from mdle.core.backend import ClockMode, Command, Observation, RobotLimits
from mdle.core.pose import Pose
from mdle.lang import AtomNode, Element, Interrupt, StringNode, load_text
from mdle.record.trace import TraceWriter
from mdle.runtime import Scheduler

LIMITS = RobotLimits(1.0, 1.0, 1.0)


class TrivialBackend:
    """Observations made in advance (a robot on an arc): observing costs a lookup."""

    clock = ClockMode.SIMULATED
    limits = LIMITS

    def __init__(self, ticks: int, dt: float = 0.1) -> None:
        v, omega = 0.3, 0.1
        obs = []
        for k in range(ticks + 2):
            t = k * dt
            theta = 0.3 + omega * t
            pose = Pose(1.0 + v / omega * (math.sin(theta) - math.sin(0.3)),
                        2.0 - v / omega * (math.cos(theta) - math.cos(0.3)),
                        math.remainder(theta, math.tau))
            obs.append(Observation(t, pose, v * (1.0 + 0.01 * math.sin(t)),
                                   omega * (1.0 + 0.01 * math.cos(t))))
        self._obs = obs
        self._k = 0

    def observe(self) -> Observation:
        """Return the next prepared observation."""
        return self._obs[self._k]

    def command(self, cmd: Command) -> None:
        """Ignore the command."""

    def advance(self, dt: float) -> float:
        """Move to the next observation."""
        self._k += 1
        return 0.0

    def stop(self) -> None:
        """Nothing to stop."""

    def close(self) -> None:
        """Nothing to close."""


def _false(ctx: Context) -> bool:
    return ctx.obs.v > 100.0


def _step(args: object, ctx: Context, state: object) -> Command:
    return Command(0.3 - 0.05 * ctx.obs.pose.y, 0.1 + 0.02 * ctx.obs.pose.theta)


def ten_interrupt_plan() -> Element:
    """Nine nested strings around an atom, each level with an interrupt and a timer."""
    xi = Interrupt(_false, "speed > 100 m/s")
    node: Element = AtomNode("leaf", LawSpec("go", (), _step), {}, xi, 1e9)
    for level in range(9):
        node = StringNode(f"s{level}", (node,), xi, 1e9 + level)
    return node


#: The ten interrupts of the compiled plan, innermost first; none fires in the benchmark.
CONDITIONS = ("speed > 100 m/s", "stalled", "t > 100000 s", "turn_rate > 50 rad/s",
              "x > 1000 m", "y < -1000 m", "speed > 100 m/s or stalled", "theta > 10 rad",
              "x > 1000 m and y > 1000 m", "t > 200000 s")


def compiled_plan() -> Element:
    """Compile the same ten-level shape, written in MDLe, with the checker."""
    text = f"(go(0.3 m/s), {CONDITIONS[0]}, 1000000 s)"
    for level, condition in enumerate(CONDITIONS[1:], 1):
        text = f"(({text}), {condition}, {1000000 + level} s)"
    return load_text(f"plan main = {text}\n", "<benchmark>").elements["main"]


def backend_only(ticks: int) -> float:
    """Seconds per tick spent in the trivial backend alone (observe, command, advance)."""
    backend = TrivialBackend(ticks)
    cmd = Command(0.3, 0.1)
    t0 = time.perf_counter()
    for _ in range(ticks):
        backend.observe()
        backend.command(cmd)
        backend.advance(0.1)
    return (time.perf_counter() - t0) / ticks


def measure(plan: Element, ticks: int, trace: bool) -> float:
    """Seconds per tick, backend included."""
    with tempfile.TemporaryDirectory() as tmp:
        observers = [TraceWriter(os.path.join(tmp, "t.jsonl"), {"bench": True})] if trace else []
        sch = Scheduler(plan, TrivialBackend(ticks), 10.0, observers, stall_timeout=None)
        sch.tick()  # starts every level
        t0 = time.perf_counter()
        for _ in range(ticks):
            sch.tick()
        elapsed = time.perf_counter() - t0
        # a run that ended early would time idle ticks: every level must still be running
        assert len(sch.path) == 10, f"the plan ended early: {sch.result}"
        sch.stop()
    return elapsed / ticks


def main() -> None:
    """Print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=100_000,
                        help="ticks per run (at most 1000000: the plan's timers end it then)")
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    print(f"plan: 10 levels, 10 interrupts + 10 timers tested per tick; {args.ticks} ticks, "
          f"{args.repeat} runs each; load average {os.getloadavg()[0]:.2f}")
    base = min(backend_only(args.ticks) for _ in range(args.repeat))
    print(f"  trivial backend alone: {base * 1e6:6.2f} us/tick (subtracted below)")
    plans = {"hand-built": ten_interrupt_plan(), "compiled": compiled_plan()}
    runs: dict[tuple[str, bool], list[float]] = {
        (name, trace): [] for name in plans for trace in (False, True)}
    for _ in range(args.repeat):  # interleaved, so a burst of load hits every variant alike
        for name, trace in runs:
            runs[name, trace].append(measure(plans[name], args.ticks, trace) - base)
    for (name, trace), times in runs.items():
        med, best = statistics.median(times), min(times)
        label = f"{name} plan, " + ("trace record written" if trace else "no observers")
        verdict = "ok" if med <= 10e-6 else "OVER the 10 us target"
        print(f"  {label:<42}: median {med * 1e6:6.2f}, min {best * 1e6:6.2f} us/tick  "
              f"({verdict})")
    print(f"load average afterwards {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
