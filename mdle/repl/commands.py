"""What the REPL does with one input: a definition, an element to run, or a ``:`` command.

Over 500 lines: one dispatch table of the ``:`` commands and the :class:`Repl` methods
that carry them out, which share the session, the output streams and the failure count.

:class:`Repl` is the interpreter both front ends share (:mod:`mdle.repl.prompt` on a
terminal, :mod:`mdle.repl.plain` for piped input). :meth:`Repl.handle` never raises for
a user's mistake: a bad definition, an unknown name, a world that does not load or a run
that collides prints a message and returns False, and the session stays as it was.

>>> import io
>>> out, err = io.StringIO(), io.StringIO()
>>> repl = Repl(Session("empty"), out, err)
>>> repl.handle("atom creep = (go(0.5 m/s), never, 2 s)"), repl.handle("creep")
(True, True)
>>> print(out.getvalue().splitlines()[1])
creep (level 0) ended by timer at 2.00 s
>>> repl.handle("crep")
False
"""

from __future__ import annotations

import difflib
import math
import os
import re
import shlex
import sys
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from typing import IO

from mdle.console.output import print_diagnostics
from mdle.console.signals import ends_session
from mdle.core.errors import Diagnostic, MdleError
from mdle.core.pose import Pose
from mdle.core.ranges import COORDINATE, HEADING, MAX_SEED
from mdle.core.userfile import file_fault, file_fault_words
from mdle.lang import keywords, statement_keywords, yaml_as_plan
from mdle.repl import views
from mdle.repl.reports import RunReport
from mdle.repl.session import ReplError, Session
from mdle.runtime import Observer
from mdle.runtime.events import ended_how

__all__ = ["COMMANDS", "DEFINITION_KEYWORDS", "KEYWORDS", "Command", "Repl", "classify"]

#: First words of an input that defines something (rather than running an element): the
#: grammar's statement keywords.
DEFINITION_KEYWORDS = statement_keywords()
#: Every MDLe keyword (completion, highlighting), as the grammar has them.
KEYWORDS = tuple(keywords())


@dataclass(frozen=True)
class Command:
    """A ``:`` command.

    Its name, argument synopsis, one line of help, and the method of :class:`Repl` that
    does it (``handler(repl, args) -> bool``).
    """

    name: str
    synopsis: str
    help: str
    handler: Callable[[Repl, list[str]], bool]
    #: What the completer offers for the first argument: "file", "world" or "".
    completes: str = ""


def classify(text: str) -> str:
    """``"command"``, ``"definition"``, ``"element"`` or ``"empty"`` (blank or a comment)."""
    code = _uncommented(text).strip()
    if not code:
        return "empty"
    if code.startswith(":"):
        return "command"
    if _DEFINITION.match(code):
        return "definition"
    return "element"


#: A statement starts with one of these keywords (the grammar keeps `atomic` a name).
_DEFINITION = re.compile("(?:" + "|".join(DEFINITION_KEYWORDS) + ")(?![A-Za-z0-9_])")


def _uncommented(text: str) -> str:
    """``text`` without its comments (``#`` to the end of a line, outside strings)."""
    return re.sub(r'"[^"\n]*"|#[^\n]*', lambda m: m.group(0) if m.group(0)[0] == '"' else "",
                  text)


class Repl:
    """The interpreter of REPL inputs, writing results to ``out`` and problems to ``err``.

    Parameters
    ----------
    session : Session
    out, err : text streams, optional
        Default: standard output and standard error.
    debug : bool
        Show the traceback of an internal error (a bug in mdle) instead of one line.
    """

    def __init__(self, session: Session, out: IO[str] | None = None,
                 err: IO[str] | None = None, *, debug: bool = False) -> None:
        self.session = session
        self._unfinished = ""  # the last input is_complete found unfinished
        self.out = out or sys.stdout
        self.err = err or sys.stderr
        self.debug = debug
        self.quit_requested = False
        self.failures = 0
        #: Extra observers of every run (the prompt adds a progress line).
        self.run_observers: list[Observer] = []
        #: Colour maps and run reports (rich markup; the prompt sets it on a terminal).
        self.color = False

    # ------------------------------------------------------------------ output

    def say(self, *lines: str) -> None:
        """Print lines on the output stream."""
        for line in lines:
            print(line, file=self.out)
        self.out.flush()

    def say_styled(self, lines: list[str], styles: dict[str, str], first: str | None = None
                   ) -> None:
        """Print lines, in colour when :attr:`color` is on, plain otherwise.

        The characters in ``styles`` (character -> rich style) and the first line (style
        ``first``) are coloured.
        """
        if not self.color:
            self.say(*lines)
            return
        from rich.console import Console
        from rich.text import Text

        console = Console(file=self.out, highlight=False, soft_wrap=True, force_terminal=True,
                          color_system="standard")
        for n, line in enumerate(lines):
            text = Text(line)
            if n == 0 and first:
                text.stylize(first)
            for i, ch in enumerate(line):
                style = styles.get(ch)
                if style:
                    text.stylize(style, i, i + 1)
            console.print(text)
        self.out.flush()

    def _say_report(self, report: RunReport) -> None:
        style = "bold green" if report.ok else (
            "bold yellow" if report.interrupted else "bold red")
        self.say_styled(views.format_report(report), {}, style)

    def complain(self, message: str, hint: str | None = None) -> None:
        """Print an error message (as ``mdle check`` prints one) on the error stream."""
        print_diagnostics([Diagnostic(None, message, hint=hint)], None, self.err)

    # ------------------------------------------------------------------ input

    def is_complete(self, text: str) -> bool:
        """Whether ``text`` is a whole input.

        A command always is; MDLe text is when its brackets balance and it does not end in
        the middle of a statement.
        """
        # an unfinished input stays MDLe as lines are added: classify it once
        if not (self._unfinished and text.startswith(self._unfinished)) and \
                classify(text) in ("command", "empty"):
            return True
        complete = self.session.workspace.is_complete(text)
        self._unfinished = "" if complete else text
        return complete

    def handle(self, text: str) -> bool:
        """Do one input; True when it succeeded.

        Never raises for the user's mistakes (KeyboardInterrupt outside a run is reported as
        an interruption).
        """
        for notice in self.session.notices():
            self.complain(notice)
        try:
            ok = self._dispatch(text)
        except MdleError as exc:
            print_diagnostics(exc.diagnostics, exc.sources, self.err)
            ok = False
        except KeyboardInterrupt as exc:
            if ends_session(exc):  # SIGTERM, SIGHUP: the session ends (robot stopped)
                raise
            self.complain("interrupted")
            ok = False
        except BrokenPipeError:
            raise  # standard output is gone: the front end ends the session quietly
        except Exception as exc:  # noqa: BLE001 (an mdle bug: report it, keep the session)
            if isinstance(exc, OSError) and file_fault(exc):  # a full disk, a read-only folder
                self.complain(file_fault_words(exc))
                return self._failed()
            if self.debug:
                traceback.print_exc(file=self.err)
            self.complain(f"internal error: {type(exc).__name__}: {exc}",
                          hint="this is a bug in mdle; the session is intact")
            ok = False
        if not ok:
            return self._failed()
        return ok

    def _failed(self) -> bool:
        self.failures += 1
        return False

    def _dispatch(self, text: str) -> bool:
        kind = classify(text)
        if kind == "empty":
            return True
        if kind == "command":
            return self._command(text.strip()[1:])
        if kind == "definition":
            return self._define(text)
        return self._run(text)

    def _define(self, text: str) -> bool:
        added, replaced, warnings = self.session.define(text)
        if warnings:
            print_diagnostics(warnings, self.session.sources, self.err)
        parts = []
        if added:
            parts.append("defined " + ", ".join(added))
        if replaced:
            parts.append("redefined " + ", ".join(replaced))
        if not parts and text.split()[0] == "run":
            entry = self.session.workspace.program().entry
            parts.append(f"entry is now `{entry}` (`:save` writes `run {entry}`; type "
                         f"`{entry}` to run it)")
        self.say("; ".join(parts) if parts else "no change")
        return True

    def _run(self, text: str) -> bool:
        report = self.session.run(text, self.run_observers)
        warnings = self.session.workspace.element_warnings
        if warnings:
            print_diagnostics(warnings, {**self.session.sources, "<repl>": text}, self.err)
        if report.error is not None:
            print_diagnostics(report.error.diagnostics, report.error.sources, self.err)
        self._say_report(report)
        return report.ok

    # ------------------------------------------------------------------ commands

    def _command(self, line: str) -> bool:
        try:
            words = shlex.split(line)
        except ValueError as exc:
            raise ReplError(f"cannot read the command: {exc}") from None
        if not words:
            return self._help([])
        name, args = words[0], words[1:]
        cmd = COMMANDS.get(name)
        if cmd is None:

            close = difflib.get_close_matches(name, list(COMMANDS), n=1)
            raise ReplError(Diagnostic(None, f"unknown command `:{name}`",
                                       hint=f"did you mean `:{close[0]}`?" if close
                                       else "`:help` lists the commands"))
        return cmd.handler(self, args)

    def _help(self, args: list[str]) -> bool:
        if args:
            cmd = COMMANDS.get(args[0].lstrip(":"))
            if cmd is None:
                raise ReplError(f"no command `:{args[0].lstrip(':')}`; `:help` lists them")
            self.say(f":{cmd.name} {cmd.synopsis}".rstrip(), f"    {cmd.help}")
            return True
        self.say("Type a definition (atom, interrupt, behavior, plan) to add it, or an element "
                 "to run it",
                 "from where the robot is: `cruise`, `(go(0.3 m/s), range(0 deg) < 1 m, 10 s)`. "
                 "Input continues",
                 "over several lines until the brackets balance. Ctrl-C stops a run, Ctrl-D "
                 "leaves.", "")
        width = max(len(f":{c.name} {c.synopsis}") for c in COMMANDS.values())
        for c in COMMANDS.values():
            self.say(f"  {(':' + c.name + ' ' + c.synopsis).ljust(width)}  {c.help}")
        return True

    def _pose(self, args: list[str]) -> bool:
        _no_args(":pose", args)
        obs = self.session.observe()
        s = self.session
        truth = s.true_pose
        if truth is None:  # a real robot: odometry and what the robot reports
            flags = "".join(w for w, on in (("; STALLED", obs.stalled),
                                            ("; MOTORS OFF", not obs.motors_enabled)) if on)
            battery = f"; battery {obs.battery:.1f} V" if obs.battery is not None else ""
            self.say(f"odometry {views.format_pose(obs.pose)}",
                     f"v {obs.v:.2f} m/s  omega {math.degrees(obs.omega):.1f} deg/s; "
                     f"t = {obs.time:.2f} s since connecting{battery}{flags}",
                     s.describe())
            return True
        self.say(f"odometry {views.format_pose(obs.pose)}",
                 f"true     {views.format_pose(truth)}",
                 f"t = {obs.time:.2f} s since the last reset"
                 + (f"; clearance {obs.truth['clearance']:.2f} m" if obs.truth else "")
                 + ("; STALLED" if obs.stalled else ""),
                 f"world `{s.world.name}`, seed {s.seed}")
        return True

    def _scan(self, args: list[str]) -> bool:
        _no_args(":scan", args)
        s = self.session
        self.say(*views.format_scan(s.observe(), s.workspace.registry, s.limits,
                                    s.rate))
        return True

    def _where(self, args: list[str]) -> bool:
        width = 72
        if args:
            width = _int(args[0], "the map width")
            if not 20 <= width <= 400:
                raise ReplError(f":where takes a width of 20 to 400 columns, got {width}")
        s = self.session
        _simulated(s, ":where", "there is no map of a real robot's surroundings; `:pose` "
                   "shows the odometry and `:plot FILE` draws the path")
        lines = views.render_map(s.world, s.path_xy(), s.backend.true_pose, width)
        grid, legend = lines[:-1], lines[-1]
        robot = {a: "bold yellow" for a in "<>^v"}
        self.say_styled(grid, {"#": "grey50", ".": "cyan", "o": "bold cyan", **robot})
        self.say(legend)
        return True

    def _plot(self, args: list[str]) -> bool:
        path = _one(":plot", args, "FILE")
        out = self.session.plot(path)
        self.say(f"plot written to {out}")
        return True

    def _trace(self, args: list[str]) -> bool:
        path = _one(":trace", args, "FILE")
        n = self.session.write_trace(path)
        self.say(f"trace written to {path} ({n} samples)")
        return True

    def _reset(self, args: list[str]) -> bool:
        pose = None
        if args:
            if len(args) not in (2, 3):
                raise ReplError(":reset takes no argument (the world's start) or X Y [THETA] "
                                "(metres, metres, degrees)")
            x = _coordinate(args[0], "x")
            y = _coordinate(args[1], "y")
            th = _heading(args[2], "theta") if len(args) == 3 else 0.0
            pose = Pose(x, y, th)
        here = self.session.reset(pose)
        if not self.session.simulated:
            self.say(f"path and trace cleared; the robot stays at {views.format_pose(here)} "
                     f"(odometry)")
            return True
        self.say(f"robot at {views.format_pose(here)}, t = 0; path cleared")
        return True

    def _world(self, args: list[str]) -> bool:
        _simulated(self.session, ":world", "the session drives a real robot; a simulated "
                   "world needs another session (`mdle repl --world NAME`)")
        if not args:
            from mdle import sim

            self.say(f"world `{self.session.world.name}`; reference worlds: "
                     + ", ".join(sim.list_worlds()))
            return True
        spec = _one(":world", args, "NAME|FILE")
        self.session.set_world(spec)
        w = self.session.world
        self.say(f"world `{w.name}`" + (f": {w.description}" if w.description else ""),
                 f"robot at {views.format_pose(self.session.backend.true_pose)}, t = 0")
        return True

    def _defs(self, args: list[str]) -> bool:
        _no_args(":defs", args)
        text = self.session.save_text()
        self.say(text.rstrip("\n") if text.strip() else "nothing defined yet")
        return True

    def _save(self, args: list[str]) -> bool:
        path = _one(":save", args, "FILE")
        text = self.session.save(path)
        n = len(self.session.workspace.names())
        lines = len(text.splitlines())
        last = text.splitlines()[-1]
        ending = (f", ending `{last}`: `mdle run {shlex.quote(path)}` runs it"
                  if last.startswith("run ")
                  else "; no `run` line: nothing here runs without arguments")
        world = (f", and world `{self.session.world.name}` to "
                 f"{self.session.world_path(path)}" if self.session.simulated else "")
        self.say(f"saved {n} definition{'s' if n != 1 else ''} to {path} "
                 f"({lines} line{'s' if lines != 1 else ''}{ending}){world}")
        return True

    def _load(self, args: list[str]) -> bool:
        path = _one(":load", args, "FILE")
        if _is_recording(path):
            _simulated(self.session, ":load of a recorded run",
                       "a recorded run is replayed into a simulated world; `:load FILE.mdle` "
                       "adds definitions on a robot too")
            run = self.session.load_run(path)
            r = run.result
            pose = self.session.backend.true_pose
            self.say(f"loaded {path}: a run of `{run.label}` in world `{run.world}`, "
                     f"{run.ticks} ticks, {r.duration:.1f} s, "
                     + ("cut short (no end record)" if run.cut
                        else ended_how(r.cause))
                     + (", COLLIDED" if r.collided else ""),
                     f"robot at {views.format_pose(pose)}; :where and :plot show the run's "
                     "path, :trace writes it")
            if run.note:
                self.say(f"note: {run.note}")
            return True
        try:
            names, warnings = self.session.load(path)
        except MdleError as err:

            raise yaml_as_plan(path, err, "to make it the session's world: "
                               f"`:world {path}`") from None
        if warnings:
            print_diagnostics(warnings, self.session.sources, self.err)
        self.say(f"loaded {path}: " + (", ".join(names) if names else "nothing new"))
        return True

    def _step(self, args: list[str]) -> bool:
        n = _int(args[0], "the number of ticks") if args else 1
        if len(args) > 1:
            raise ReplError(":step takes one argument: the number of ticks")
        outcome = self.session.step(n)
        if outcome.started:
            self.say(f"stepping `{self.session.last_element}` from the robot's current state")
        reports = views.law_reports(self.session.workspace.registry)
        self.say(*views.format_step_rows(outcome.rows, outcome.t0, reports))
        if outcome.report is not None:
            self._say_report(outcome.report)
            return outcome.report.ok
        return True

    def _set(self, args: list[str]) -> bool:
        if len(args) != 2:
            raise ReplError(":set takes a setting and a value: `:set seed N`, "
                            "`:set until SECONDS` (`inf` for no limit) or "
                            "`:set realtime on|off`")
        what, value = args
        if what in ("seed", "realtime"):
            _simulated(self.session, f":set {what}",
                       "a real robot has no random seed and always runs at the pace of the "
                       "wall clock")
        if what == "seed":
            seed = _int(value, "the seed")
            if not 0 <= seed <= MAX_SEED:
                raise ReplError(f"a seed is a whole number from 0 to {MAX_SEED}, got {value}")
            self.session.set_seed(seed)
            self.say(f"seed {self.session.seed}; robot where it was, t = 0, path cleared")
            return True
        if what == "until":
            limit = _number(value, "the run limit")
            if not limit > 0:
                raise ReplError(f"the run limit must be positive seconds (or inf), got {value}")
            self.session.until = None if math.isinf(limit) else limit
            self.say("runs have no time limit (Ctrl-C stops one)" if math.isinf(limit)
                     else f"a run stops after {limit:g} s")
            return True
        if what == "realtime":
            if value not in ("on", "off"):
                raise ReplError(f":set realtime takes `on` or `off`, got `{value}`")
            self.session.realtime = value == "on"
            self.say("runs go at the pace of the wall clock" if self.session.realtime
                     else "runs go as fast as the simulator can")
            return True
        raise ReplError(f"no setting `{what}`: `:set seed N`, `:set until SECONDS` or "
                        "`:set realtime on|off`")

    def _quit(self, args: list[str]) -> bool:
        _no_args(":quit", args)
        self.quit_requested = True
        return True


def _is_recording(path: str) -> bool:
    """Return True for a run's trace (.jsonl), an MCAP recording or a rosbag2 folder."""
    if path.endswith((".jsonl", ".mcap")):
        return True
    return os.path.isdir(path) and os.path.isfile(os.path.join(path, "metadata.yaml"))


def _simulated(session: Session, cmd: str, why: str) -> None:
    """Refuse a simulator-only command in a session on a real robot."""
    if not session.simulated:
        raise ReplError(Diagnostic(None, f"{cmd} works in simulation only", hint=why))


def _no_args(cmd: str, args: list[str]) -> None:
    if args:
        raise ReplError(f"{cmd} takes no arguments")


def _one(cmd: str, args: list[str], what: str) -> str:
    if len(args) != 1:
        raise ReplError(f"{cmd} takes one argument: {what}")
    return args[0]


def _number(text: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ReplError(f"{what} must be a number, got `{text}`") from None
    if math.isnan(value):
        raise ReplError(f"{what} must be a number, got `{text}`")
    return value


def _coordinate(text: str, what: str) -> float:
    value = _finite(text, what)
    problem = COORDINATE.problem(value, text)
    if problem is not None:
        raise ReplError(f"{what}: {problem}")
    return value


def _heading(text: str, what: str) -> float:
    """Read a heading in degrees, returned in radians."""
    value = math.radians(_finite(text, what))
    problem = HEADING.problem(value, text)
    if problem is not None:
        raise ReplError(f"{what}: {problem}")
    return value


def _finite(text: str, what: str) -> float:
    value = _number(text, what)
    if not math.isfinite(value):
        raise ReplError(f"{what} must be a finite number, got `{text}`")
    return value


def _int(text: str, what: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise ReplError(f"{what} must be a whole number, got `{text}`") from None


#: Every ``:`` command, in the order ``:help`` lists them.
COMMANDS: dict[str, Command] = {c.name: c for c in (
    Command("help", "[COMMAND]", "this list, or one command's help", Repl._help),
    Command("pose", "", "the robot's pose (odometry and true), time, speed, clearance",
            Repl._pose),
    Command("scan", "", "the current scan by sector and the boundary estimates on both sides",
            Repl._scan),
    Command("where", "[WIDTH]", "a map of the world with the robot and its path since the "
            "last reset", Repl._where),
    Command("plot", "FILE", "draw the path since the last reset as `mdle plot` does "
            "(.png, .svg, .pdf)", Repl._plot, "file"),
    Command("trace", "FILE", "write the runs since the last reset as a JSON lines trace",
            Repl._trace, "file"),
    Command("reset", "[X Y [THETA]]", "put the robot at the world's start, or at X Y (m) "
            "heading THETA (deg); clears the path", Repl._reset),
    Command("world", "[NAME|FILE]", "switch to another world (a reference name or a YAML "
            "file); without one, list them", Repl._world, "world"),
    Command("defs", "", "the definitions so far, as `mdle fmt` prints them", Repl._defs),
    Command("save", "FILE", "write the definitions so far to FILE (formatted) and a `run` line "
            "(the `run` entry, else the element last run, else the plan defined last)",
            Repl._save, "file"),
    Command("load", "FILE", "add the definitions of an .mdle file; or bring in a recorded "
            "run (.jsonl trace, .mcap recording): its world, path and final pose",
            Repl._load, "file"),
    Command("step", "[N]", "advance the last element N ticks (default 1), showing each "
            "tick's control and sensor values", Repl._step),
    Command("set", "seed N | until SECONDS | realtime on|off", "reseed the simulation; "
            "limit how long a run may go on (default 600 s); pace runs to the wall clock",
            Repl._set),
    Command("quit", "", "leave (Ctrl-D too)", Repl._quit),
)}
