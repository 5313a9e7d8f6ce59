"""What ``mdle run`` shows while a plan runs, and the summary after it.

On a terminal, a rich live panel: the running path (plan > behavior > atom) with each
level's elapsed time and remaining timer, the pose, speed and turn rate, and the last
events; then a summary table. Off a terminal (a pipe, a log file, CI), plain lines with
no control codes: one per event, then the summary. The view is an observer of the
scheduler and only reads what the scheduler hands it, except in one case: when its
stream can no longer be written (``mdle run ... | head`` closed the pipe), it stops
printing and asks the scheduler to stop the run (robot stopped, the trace's end record
gives the reason), as a program in a pipeline ends when its reader goes away;
:attr:`LiveView.output_lost` then holds the error.
"""

from __future__ import annotations

import math
import sys
import time
from collections import Counter, deque
from typing import IO, TYPE_CHECKING, Any

from mdle.runtime.events import Cause, Event, EventKind, RunResult, Sample, ended_how
from mdle.runtime.observer import BaseObserver
from mdle.view.run_report import FollowingStats, MapPoints, path_map

if TYPE_CHECKING:
    from mdle.runtime.scheduler import ActiveElement, Scheduler

__all__ = ["LiveView", "summary_rows", "format_event"]

#: Live panel refreshes per second of wall time (the run itself may go much faster).
REFRESH_HZ = 10.0
#: Events the final frame's timeline keeps on a terminal (the last ones).
TIMELINE = 40


def _secs(t: float) -> str:
    if math.isinf(t):
        return "inf"
    return f"{t:.1f} s" if abs(t) < 120 else f"{t / 60:.1f} min"


def format_event(e: Event, t0: float = 0.0) -> str:
    """One plain line for an event: time, start/end, path, cause, pose."""
    p = e.pose
    what = "start" if e.kind is EventKind.START else "end  "
    cause = f"  {e.cause.value}" if e.cause is not None else ""
    if e.fired:
        cause += f" ({e.fired})"
    return (f"{e.time - t0:8.2f} s  {what} {e.path}{cause}  "
            f"(x {p.x:.2f} m, y {p.y:.2f} m, heading {math.degrees(p.theta):.0f} deg)")


def summary_rows(result: RunResult, wall_seconds: float | None = None) -> list[tuple[str, str]]:
    """Return the summary as (label, value) rows, shared by the rich table and the plain lines."""
    t = result.termination
    fired = f" ({t.fired})" if t.fired else ""
    rows = [("ended", f"{t.path} {ended_how(t.cause)}{fired} at {_secs(result.duration)}")]
    if result.fault:
        rows.append(("fault", result.fault))
    rows.append(("distance travelled", f"{result.distance:.2f} m"))
    if result.min_clearance is not None:
        rows.append(("minimum clearance", f"{result.min_clearance:.3f} m"))
    t0 = result.events[0].time if result.events else 0.0
    rows.append(("collided", ("YES: " + result.collision.describe(t0)) if result.collision
                 else "YES" if result.collided else "no"))
    rows.append(("ticks", str(result.ticks)))
    if result.max_lateness > 0:
        rows.append(("worst tick lateness", f"{result.max_lateness * 1e3:.1f} ms"))
    if wall_seconds is not None and wall_seconds > 0:
        rows.append(("real-time factor", f"{result.duration / wall_seconds:.1f}x"))
    return rows


def _element_rows(result: RunResult) -> list[tuple[str, str, str]]:
    """Each element path that ran, how many times it ran and how those runs ended."""
    ends: dict[str, Counter[Cause]] = {}
    fired: dict[str, Counter[str]] = {}  # the conditions that fired, by element
    for term in result.terminations:
        ends.setdefault(term.path, Counter())[term.cause] += 1
        if term.fired:
            fired.setdefault(term.path, Counter())[term.fired] += 1
    # in the order they first started: outermost first, then depth first
    order = list(dict.fromkeys(e.path for e in result.events
                               if e.kind is EventKind.START and e.path in ends))
    rows = []
    for path in order:
        counts = ends[path]
        n = sum(counts.values())
        how = ", ".join(ended_how(c) + (f" x{k}" if k > 1 else "") + (
            " (" + ", ".join(f"{w}" + (f" x{m}" if m > 1 else "")
                             for w, m in fired[path].items()) + ")"
            if c is Cause.INTERRUPT and path in fired else "")
            for c, k in counts.items())
        rows.append((path, str(n), how))
    return rows


class LiveView(BaseObserver):
    """A live view of a run on a terminal, plain event lines elsewhere.

    Parameters
    ----------
    stream : text stream
        Where to write (standard output by default).
    plain : bool or None
        Force plain lines (True) or the rich panel (False); None picks the panel only
        when ``stream`` is a terminal.
    events : int
        How many recent events the panel keeps.
    """

    def __init__(self, stream: IO[str] | None = None, plain: bool | None = None,
                 events: int = 8) -> None:
        self.stream = stream or sys.stdout
        self.plain = (not self.stream.isatty()) if plain is None else plain
        self._events: deque[str] = deque(maxlen=events)
        self._scheduler: Scheduler | None = None
        self._live: Any = None
        self._sample: Sample | None = None
        self._t0: float | None = None
        self._wall0 = 0.0
        self._next_refresh = 0.0
        self.wall_seconds: float | None = None
        self._timeline: deque[str] = deque(maxlen=TIMELINE)
        self._event_count = 0
        self._following = FollowingStats(0.0)
        self._map = MapPoints()
        #: The error that made the stream unusable (EPIPE...), None while it works.
        self.output_lost: OSError | None = None

    def _lost(self, exc: OSError) -> None:
        """Stop printing for good, and stop the run: no one sees it any more."""
        self.output_lost = exc
        self._live = None
        if self._scheduler is not None:
            what = "closed" if isinstance(exc, BrokenPipeError) else \
                f"unwritable ({exc.strerror or exc})"
            self._scheduler.request_stop(f"standard output {what}")

    # ------------------------------------------------------------------ observer hooks

    def on_start(self, scheduler: "Scheduler") -> None:
        """Open the live panel (terminal only)."""
        self._scheduler = scheduler
        self._wall0 = time.monotonic()
        limits = getattr(getattr(scheduler, "backend", None), "limits", None)
        self._following = FollowingStats(float(getattr(limits, "radius", 0.0) or 0.0))
        if not self.plain and self.output_lost is None:
            from rich.console import Console
            from rich.live import Live

            console = Console(file=self.stream)
            self._live = Live(self._panel(), console=console, auto_refresh=False,
                              transient=True)
            try:
                self._live.start()
            except OSError as exc:
                self._lost(exc)

    def on_event(self, event: Event) -> None:
        """Print (plain) or remember (panel) the event."""
        if self._t0 is None:
            self._t0 = event.time
        line = format_event(event, self._t0)
        self._timeline.append(line)
        self._event_count += 1
        if self.output_lost is not None:
            return
        if self.plain:
            try:
                print(line, file=self.stream)
                self.stream.flush()  # a reader down a pipe sees each event as it happens
            except OSError as exc:
                self._lost(exc)
        else:
            self._events.append(line)

    def on_tick(self, sample: Sample) -> None:
        """Refresh the panel at most :data:`REFRESH_HZ` times a second."""
        self._sample = sample
        self._following.add(sample)
        self._map.add(sample)
        if self._live is None:
            return
        now = time.monotonic()
        if now >= self._next_refresh:
            self._next_refresh = now + 1.0 / REFRESH_HZ
            try:
                self._live.update(self._panel(), refresh=True)
            except OSError as exc:
                self._lost(exc)

    def on_end(self, result: RunResult) -> None:
        """Close the panel and print the summary."""
        self.wall_seconds = time.monotonic() - self._wall0
        if self.output_lost is not None:
            return
        try:
            if self._live is not None:
                live, self._live = self._live, None
                live.stop()
            self.print_summary(result)
        except OSError as exc:
            self.output_lost = exc

    # ------------------------------------------------------------------ rendering

    def following_lines(self) -> list[str]:
        """One line per boundary-following atom: its rc, mean/max |d - rc|, closest approach."""
        lines = []
        for r in self._following.rows():
            closest = f", closest approach {r.closest:.3f} m" if r.closest is not None else ""
            source = "" if r.truth else " (d measured: no ground truth)"
            lines.append(f"{r.path} (rc {r.rc:g} m): mean |d - rc| {r.mean_err:.3f} m, "
                         f"max {r.max_err:.3f} m{closest}{source}")
        return lines

    def print_summary(self, result: RunResult) -> None:
        """Print the final frame: timeline (terminal), elements, following, map, summary."""
        rows = summary_rows(result, self.wall_seconds)
        elements = _element_rows(result)
        following = self.following_lines()
        drawing = path_map(self._map)
        if self.plain:
            out = self.stream
            print("elements run:", file=out)
            for path, n, how in elements:
                print(f"  {path}  ran {n}x  {how}", file=out)
            if following:
                print("boundary following (d: distance from the robot's centre to the "
                      "boundary; |d - rc| over the second half of each atom's run):", file=out)
                for line in following:
                    print(f"  {line}", file=out)
            if drawing:
                print("path (S start, E end, # boundary seen beside the robot):", file=out)
                for line in drawing:
                    print(f"  {line}", file=out)
            for label, value in rows:
                print(f"{label}: {value}", file=out)
            out.flush()
            return
        from rich.console import Console
        from rich.table import Table
        from rich.text import Text

        console = Console(file=self.stream, highlight=False)
        # the live panel is gone: the events it showed stay on the screen as a timeline
        skipped = self._event_count - len(self._timeline)
        timeline = Text("\n".join(self._timeline), style="dim")
        if skipped > 0:
            timeline = Text(f"... {skipped} earlier events (`--trace` keeps them all)\n",
                            style="dim") + timeline
        console.print(Text("timeline", style="bold"))
        console.print(timeline)
        table = Table(title="elements run", title_justify="left")
        table.add_column("element")
        table.add_column("runs", justify="right")
        table.add_column("how it ended")
        for path, n, how in elements:
            table.add_row(path, n, how)
        console.print(table)
        if following:
            console.print(Text("boundary following", style="bold")
                          + Text(" (d: distance from the robot's centre to the boundary; "
                                 "|d - rc| over the second half of each atom's run)"))
            for line in following:
                console.print("  " + line, soft_wrap=True)
        if drawing:
            console.print(Text("path", style="bold")
                          + Text(" (S start, E end, # boundary seen beside the robot)"))
            console.print(Text("\n".join("  " + line for line in drawing)))
        facts = Table(show_header=False, box=None)
        facts.add_column(style="bold")
        facts.add_column()
        for label, value in rows:
            style = "bold red" if (label == "collided" and value.startswith("YES")) or \
                label == "fault" else ""
            facts.add_row(label, value, style=style)
        console.print(facts)

    def _levels(self) -> "tuple[ActiveElement, ...]":
        return self._scheduler.active if self._scheduler is not None else ()

    def _panel(self) -> Any:
        from rich.console import Group
        from rich.panel import Panel
        from rich.table import Table
        from rich.text import Text

        levels = Table(show_header=True, box=None, pad_edge=False)
        levels.add_column("running")
        levels.add_column("kind", style="dim")
        levels.add_column("elapsed", justify="right")
        levels.add_column("timer left", justify="right")
        for a in self._levels():
            levels.add_row("  " * a.level + a.label, a.element, _secs(a.elapsed),
                           _secs(max(a.remaining, 0.0)))
        s = self._sample
        if s is None:
            state = Text("waiting for the first tick")
        else:
            t = s.time - (self._t0 if self._t0 is not None else s.time)
            state = Text(f"t {t:7.2f} s   x {s.x:6.2f} m   y {s.y:6.2f} m   heading "
                         f"{math.degrees(s.theta):6.1f} deg   v {s.v:5.2f} m/s   "
                         f"omega {math.degrees(s.omega):6.1f} deg/s")
            if s.clearance is not None:
                state.append(f"   clearance {s.clearance:.2f} m")
            if s.collided:
                state.append("   COLLIDED", style="bold red")
            if s.lateness > 0.0:
                state.append(f"   tick late {s.lateness * 1e3:.0f} ms", style="yellow")
        events = Text("\n".join(self._events) or "(no events yet)", style="dim")
        return Panel(Group(levels, state, events), title="mdle run", title_align="left")
