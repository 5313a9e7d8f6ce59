"""The REPL on a terminal: prompt_toolkit with history, completion and highlighting.

* History is kept across sessions in ``$XDG_DATA_HOME/mdle/repl_history``
  (``~/.local/share/mdle/repl_history`` when the variable is unset).
* Tab completes keywords, defined names, control laws and sensor functions, a law's or
  sensor's parameter names inside its call (``follow_boundary(r`` -> ``rc = ``), a symbol
  parameter's choices (``side = `` -> ``right``, ``left``), units after a number, the
  ``:`` commands and their arguments (world names, file paths).
* MDLe input is highlighted by :class:`MdleLexer`, a small pygments lexer
  (:mod:`mdle.repl.highlight`); completion is :mod:`mdle.repl.completion`.
* Enter on an unfinished input (brackets still open, or ending in ``=``, an operator or a
  comma) starts a new line instead of submitting it.
* Ctrl-C at the prompt discards the line; during a run it stops the robot and gives the
  prompt back; Ctrl-D on an empty line leaves.
"""

from __future__ import annotations

import os
import signal
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from prompt_toolkit import PromptSession
from prompt_toolkit.completion import CompleteEvent

from mdle.console.signals import ends_session
from mdle.repl.commands import Repl
from mdle.repl.completion import MdleCompleter
from mdle.repl.highlight import MdleLexer
from mdle.runtime import BaseObserver, RunResult, Sample

if TYPE_CHECKING:
    from prompt_toolkit import PromptSession
    from prompt_toolkit.input import Input
    from prompt_toolkit.output import Output

# MdleCompleter and MdleLexer are re-exported: tests read them from here.
__all__ = [
    "PROMPT",
    "MdleCompleter",
    "MdleLexer",
    "ProgressLine",
    "ctrl_c_interrupts",
    "history_path",
    "make_prompt_session",
    "run_prompt",
]

PROMPT = "mdle> "


def history_path(environ: dict[str, str] | os._Environ[str] | None = None) -> Path:
    """Where the REPL keeps its history.

    ``$XDG_DATA_HOME/mdle/repl_history``, or ``~/.local/share/mdle/repl_history`` when
    ``XDG_DATA_HOME`` is unset or empty (the XDG base directory rule).
    """
    env = os.environ if environ is None else environ
    base = env.get("XDG_DATA_HOME") or ""
    root = Path(base) if base and os.path.isabs(base) else Path.home() / ".local" / "share"
    return root / "mdle" / "repl_history"


def make_prompt_session(repl: Repl, *, input: Input | None = None,
                        output: Output | None = None, history: bool = True
                        ) -> PromptSession[str]:
    """Return the prompt_toolkit session of the REPL (history, completion, lexer, key bindings).

    ``input``/``output`` default to the terminal; tests pass a pipe input and a dummy
    output. With ``history`` False (or when the data directory cannot be created) the
    history lives in memory only.
    """
    from prompt_toolkit.application import get_app
    from prompt_toolkit.completion.base import get_common_complete_suffix
    from prompt_toolkit.filters import Condition, has_completions
    from prompt_toolkit.history import FileHistory, History, InMemoryHistory
    from prompt_toolkit.key_binding import KeyBindings
    from prompt_toolkit.lexers import PygmentsLexer

    hist: History = InMemoryHistory()
    if history:
        path = history_path()
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            hist = FileHistory(str(path))
        except OSError:
            pass

    @Condition
    def unfinished() -> bool:
        buf = get_app().current_buffer
        return not repl.is_complete(buf.text)

    bindings = KeyBindings()

    @bindings.add("enter", filter=unfinished)
    def _newline(event: Any) -> None:
        # keep the indentation of the line being continued, plus one level
        buf = event.current_buffer
        line = buf.document.current_line
        indent = line[: len(line) - len(line.lstrip())]
        buf.insert_text("\n" + indent + ("    " if buf.text.rstrip().endswith(("(", "=", ","))
                                          and not indent else ""))

    completer = MdleCompleter(repl)

    @bindings.add("tab", filter=~has_completions)
    def _complete(event: Any) -> None:
        # Complete at once (prompt_toolkit's own Tab completes in a background task): a
        # single candidate is inserted, several insert their common part, and when there
        # is none the menu opens (then Tab moves through it).
        buf = event.current_buffer
        found = list(completer.get_completions(buf.document,
                                               CompleteEvent(completion_requested=True)))
        if len(found) == 1:
            buf.apply_completion(found[0])
            return
        common = get_common_complete_suffix(buf.document, found) if found else ""
        if common:
            buf.insert_text(common)
        elif found:
            buf.start_completion(select_first=False)

    return PromptSession(
        history=hist, completer=completer, lexer=PygmentsLexer(MdleLexer),
        key_bindings=bindings, multiline=False, complete_while_typing=False,
        prompt_continuation=lambda width, line, wrap: "...".rjust(width - 1) + " ",
        input=input, output=output)


def _ask_before_moving(repl: Repl, input: Input | None, output: Output | None) -> None:
    """On a robot, let the session ask at the prompt before the first motion."""
    from mdle.repl.robot import RobotSession

    session = repl.session
    if not isinstance(session, RobotSession) or session.confirm is not None:
        return

    def ask(question: str) -> bool:
        try:
            answer = PromptSession[str](input=input, output=output).prompt(
                f"{question} [y/N] ")
        except (EOFError, KeyboardInterrupt):
            return False
        return answer.strip().lower() in ("y", "yes")

    session.confirm = ask


class ProgressLine(BaseObserver):
    """While a run goes on, one status line on the terminal.

    It shows the active element, the simulated time and the pose, rewritten at most every
    ``interval`` seconds of wall time (the first time only after ``interval``, so quick
    runs show nothing) and erased when the run ends.
    """

    def __init__(self, stream: IO[str], interval: float = 0.2,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.stream = stream
        self.interval = interval
        self.clock = clock
        self._next = 0.0
        self._t0: float | None = None
        self._shown = False

    def on_start(self, scheduler: Any) -> None:
        """Arm the first update ``interval`` seconds from now."""
        self._next = self.clock() + self.interval
        self._t0 = None
        self._shown = False

    def on_tick(self, sample: Sample) -> None:
        """Rewrite the status line when ``interval`` has passed since the last one."""
        if self._t0 is None:
            self._t0 = sample.time
        now = self.clock()
        if now < self._next:
            return
        self._next = now + self.interval
        elapsed = sample.time - self._t0
        self.stream.write(f"\r\x1b[K  running {sample.path or '...'}: t {elapsed:.1f} s"
                          f"  x {sample.x:.2f} m  y {sample.y:.2f} m  (Ctrl-C stops it)")
        self.stream.flush()
        self._shown = True

    def on_end(self, result: RunResult) -> None:
        """Erase the status line."""
        if self._shown:
            self.stream.write("\r\x1b[K")
            self.stream.flush()
            self._shown = False


def run_prompt(repl: Repl, *, input: Input | None = None, output: Output | None = None,
               history: bool = True) -> int:
    """Read and do inputs at the prompt until Ctrl-D or ``:quit``; returns 0.

    On the real terminal (``output`` None) a :class:`ProgressLine` shows long runs.
    """
    session = make_prompt_session(repl, input=input, output=output, history=history)
    _ask_before_moving(repl, input, output)
    if output is None:
        repl.run_observers.append(ProgressLine(repl.out))
        repl.color = repl.out.isatty()
    repl.say(f"mdle repl: {repl.session.describe()}. "
             "`:help` lists the commands; Ctrl-D leaves.")
    while not repl.quit_requested:
        try:
            text = session.prompt(PROMPT)
        except KeyboardInterrupt as exc:  # Ctrl-C at the prompt: drop the line
            if ends_session(exc):  # SIGTERM, SIGHUP: leave
                raise
            continue
        except EOFError:  # Ctrl-D
            break
        with ctrl_c_interrupts(repl.out if output is None else None):
            repl.handle(text)
    return 0


@contextmanager
def ctrl_c_interrupts(stream: IO[str] | None) -> Iterator[None]:
    """Make sure Ctrl-C on the terminal behind ``stream`` raises KeyboardInterrupt here.

    Whatever mode the terminal was left in (a raw mode turns the key into a plain byte)
    and whatever became of the SIGINT handler: the terminal's ISIG flag is switched on
    (with Ctrl-C as its interrupt key) and a handler that raises is put in place for the
    block, both restored after it. Without a terminal (``stream`` None, or not a tty)
    only the handler is seen to.
    """
    handler = signal.getsignal(signal.SIGINT)
    if not callable(handler):  # SIG_IGN / SIG_DFL: a run could not be stopped
        signal.signal(signal.SIGINT, signal.default_int_handler)
    saved = None
    fd = -1
    try:
        import termios

        if stream is not None and stream.isatty():
            fd = stream.fileno()
            saved = termios.tcgetattr(fd)
            mode = list(saved)
            cc = list(mode[6])
            if not (mode[3] & termios.ISIG) or cc[termios.VINTR] != b"\x03":
                mode[3] |= termios.ISIG
                cc[termios.VINTR] = b"\x03"
                mode[6] = cc
                termios.tcsetattr(fd, termios.TCSANOW, mode)
            else:
                saved = None
    except (ImportError, OSError, ValueError):  # no termios, or not a real terminal
        saved = None
    try:
        yield
    finally:
        if saved is not None:
            try:
                import termios

                termios.tcsetattr(fd, termios.TCSANOW, saved)
            except OSError:
                pass
        if not callable(handler):
            signal.signal(signal.SIGINT, handler)
