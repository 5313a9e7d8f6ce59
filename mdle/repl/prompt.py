"""The REPL on a terminal: prompt_toolkit with history, completion and highlighting.

* History is kept across sessions in ``$XDG_DATA_HOME/mdle/repl_history``
  (``~/.local/share/mdle/repl_history`` when the variable is unset).
* Tab completes keywords, defined names, control laws and sensor functions, a law's or
  sensor's parameter names inside its call (``follow_boundary(r`` -> ``rc = ``), a symbol
  parameter's choices (``side = `` -> ``right``, ``left``), units after a number, the
  ``:`` commands and their arguments (world names, file paths).
* MDLe input is highlighted by :class:`MdleLexer`, a small pygments lexer (pygments is
  already installed as a dependency of rich).
* Enter on an unfinished input (brackets still open, or ending in ``=``, an operator or a
  comma) starts a new line instead of submitting it.
* Ctrl-C at the prompt discards the line; during a run it stops the robot and gives the
  prompt back; Ctrl-D on an empty line leaves.
"""

from __future__ import annotations

import os
import re
import time
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, ClassVar

from prompt_toolkit.completion import CompleteEvent, Completer, Completion, PathCompleter
from prompt_toolkit.document import Document
from pygments.lexer import RegexLexer, default, words
from pygments.token import (
    Comment,
    Keyword,
    Name,
    Number,
    Operator,
    Punctuation,
    String,
    Text,
    Whitespace,
)

from mdle.cli.signals import ends_session
from mdle.repl.commands import COMMANDS, DEFINITION_KEYWORDS, KEYWORDS, Repl
from mdle.runtime import BaseObserver, RunResult, Sample

if TYPE_CHECKING:
    from prompt_toolkit import PromptSession
    from prompt_toolkit.input import Input
    from prompt_toolkit.output import Output

__all__ = [
    "PROMPT",
    "UNITS",
    "MdleCompleter",
    "MdleLexer",
    "ProgressLine",
    "ctrl_c_interrupts",
    "history_path",
    "make_prompt_session",
    "run_prompt",
]

PROMPT = "mdle> "
#: Units offered after a number (the table of :mod:`mdle.units` and their quotients).
UNITS = ("m", "cm", "mm", "s", "ms", "min", "deg", "rad", "m/s", "deg/s", "rad/s")

_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*$")
_NUMBER_BEFORE = re.compile(r"(?<![A-Za-z0-9_.])(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?[ \t]*$")
_CALLEE = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)\s*$")
_KEYWORD_ARG = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)\s*=\s*$")


class MdleLexer(RegexLexer):
    """Pygments lexer for MDLe text and the REPL's ``:`` commands."""

    name = "MDLe"
    aliases: ClassVar[list[str]] = ["mdle"]
    filenames: ClassVar[list[str]] = ["*.mdle"]

    tokens: ClassVar[dict[str, list[Any]]] = {
        "root": [
            (r"^\s*:[a-z]+", Name.Builtin, "command"),
            (r"#.*?$", Comment.Single),
            (r"\s+", Whitespace),
            (r'"[^"\n]*"', String),
            (words(DEFINITION_KEYWORDS, suffix=r"\b"), Keyword.Declaration),
            (words(("never", "inf"), suffix=r"\b"), Keyword.Constant),
            (words(("and", "or", "xor", "not"), suffix=r"\b"), Operator.Word),
            (r"(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?", Number, "unit"),
            (r"[A-Za-z_][A-Za-z0-9_]*(?=\s*\()", Name.Function),
            (r"[A-Za-z_][A-Za-z0-9_]*", Name),
            (r"\.\.\.", Keyword),
            (r"<=|>=|==|!=|[<>+\-*/=]", Operator),
            (r"[()\[\],]", Punctuation),
            (r".", Text),
        ],
        "unit": [
            ((r"[ \t]*(?!(?:and|or|xor|not|never|inf|import|run|atom|behavior|plan|interrupt)"
              r"\b)[A-Za-z_][A-Za-z0-9_]*(?:[ \t]*/[ \t]*[A-Za-z_][A-Za-z0-9_]*)?"),
             Keyword.Type, "#pop"),
            default("#pop"),
        ],
        "command": [
            (r".+$", String, "#pop"),
            default("#pop"),
        ],
    }


def history_path(environ: dict[str, str] | os._Environ[str] | None = None) -> Path:
    """Where the REPL keeps its history.

    ``$XDG_DATA_HOME/mdle/repl_history``, or ``~/.local/share/mdle/repl_history`` when
    ``XDG_DATA_HOME`` is unset or empty (the XDG base directory rule).
    """
    env = os.environ if environ is None else environ
    base = env.get("XDG_DATA_HOME") or ""
    root = Path(base) if base and os.path.isabs(base) else Path.home() / ".local" / "share"
    return root / "mdle" / "repl_history"


class MdleCompleter(Completer):
    """Completion for the REPL.

    It reads the session's definitions and registry each time, so new definitions are
    offered at once.
    """

    def __init__(self, repl: Repl) -> None:
        self.repl = repl
        self._paths = PathCompleter(expanduser=True)
        # `:world` offers folders and world files only, `:load` folders and plans: a
        # plot or trace lying in the folder is never a world or a plan
        self._worlds = PathCompleter(expanduser=True, file_filter=_suffix_filter(
            (".yaml", ".yml")))
        self._plans = PathCompleter(expanduser=True, file_filter=_suffix_filter((".mdle",)))

    # ------------------------------------------------------------------ entry point

    def get_completions(self, document: Document, complete_event: CompleteEvent
                        ) -> Iterator[Completion]:
        """Yield the completions of the text before the cursor (prompt_toolkit's hook)."""
        text = document.text_before_cursor
        if text.lstrip().startswith(":"):
            yield from self._command(text.lstrip())
            return
        word_match = _WORD.search(text)
        word = word_match.group(0) if word_match else ""
        before = text[: len(text) - len(word)]
        if _NUMBER_BEFORE.search(before) and (word or before.endswith((" ", "\t"))):
            yield from _starting(word, self._units(before))
            return
        if re.search(r"[0-9.]$", before) and not word:
            return
        yield from self._mdle(before, word)

    # ------------------------------------------------------------------ MDLe text

    def _mdle(self, before: str, word: str) -> Iterator[Completion]:
        registry = self.repl.session.workspace.registry
        callee = _enclosing_call(before)
        if callee is not None:
            params = self._params(callee)
            kw = _KEYWORD_ARG.search(before)
            if kw is not None and params is not None:
                choices = next((p[2] for p in params if p[0] == kw.group(1)), ())
                if choices:
                    yield from _starting(word, ((c, "symbol") for c in choices))
                    return
            if params is not None and before.rstrip().endswith(("(", ",")):
                # an argument: a parameter name, a symbol, or a parameter of the
                # definition being typed (`atom a(d = 1 m) = (go(d), ...)`)
                yield from _starting(word, [
                    *((f"{n} = ", doc or "parameter", n) for n, doc, _ in params),
                    *((c, f"symbol for {n}") for n, _, choices in params for c in choices),
                    *((n, "parameter of this definition") for n in _own_params(before))])
                return
        offered: list[tuple[str, str]] = []
        if not before.strip():
            offered += [(k, "keyword") for k in DEFINITION_KEYWORDS]
        ws = self.repl.session.workspace
        for name in ws.names():
            d = ws.definition(name)
            offered.append((name, d.kind.value if d is not None else "defined"))
        offered += [(n, "control law") for n in registry.laws]
        offered += [(n, "sensor") for n in registry.sensors]
        offered += [(k, "keyword") for k in KEYWORDS if k not in DEFINITION_KEYWORDS]
        if word:
            yield from _starting(word, offered)

    def _units(self, before: str) -> list[tuple[str, str]]:
        """Units for the number just typed.

        Those of the parameter's dimension when the number is an argument of a law or
        sensor, else every unit.
        """
        from mdle.units import unit_value

        found = _enclosing_call_at(before)
        dim = None
        if found is not None:
            callee, index, keyword = found
            registry = self.repl.session.workspace.registry
            spec = registry.laws.get(callee) or registry.sensors.get(callee)
            if spec is not None:
                param = spec.param(keyword) if keyword else (
                    spec.params[index] if index < len(spec.params) else None)
                if param is not None and not param.is_symbol:
                    dim = param.dim
        units = [(u, f"unit of {unit_value(u)[1]}") for u in UNITS]
        if dim is None:
            return units
        fitting = [(u, m) for u, m in units if unit_value(u)[1] == dim]
        return fitting or units

    def _params(self, callee: str) -> list[tuple[str, str, tuple[str, ...]]] | None:
        """(name, doc, choices) of the parameters of a law, sensor or definition."""
        ws = self.repl.session.workspace
        spec = ws.registry.laws.get(callee) or ws.registry.sensors.get(callee)
        if spec is not None:
            return [(p.name, p.doc, p.choices) for p in spec.params]
        d = ws.definition(callee)
        if d is not None:
            return [(p.name, f"parameter of {callee}", ()) for p in d.param_list]
        return None

    # ------------------------------------------------------------------ commands

    def _command(self, text: str) -> Iterator[Completion]:
        head, space, rest = text[1:].partition(" ")
        if not space:
            for name, each in COMMANDS.items():
                if name.startswith(head):
                    yield Completion(name, -len(head), display=f":{name}",
                                     display_meta=each.help)
            return
        cmd = COMMANDS.get(head)
        if cmd is None:
            return
        arg = rest.lstrip()
        if " " in arg:
            return
        if cmd.name == "help":
            yield from _starting(arg, ((n, "command") for n in COMMANDS))
        elif cmd.name == "set":
            yield from _starting(arg, (("seed", "random seed"), ("until", "run limit, s"),
                                       ("realtime", "on or off")))
        elif cmd.completes == "world":
            from mdle import sim

            yield from _starting(arg, ((n, "reference world") for n in sim.list_worlds()))
            if arg:
                yield from self._files(arg, self._worlds)
        elif cmd.name == "load":
            yield from self._files(arg, self._plans)
        elif cmd.completes == "file":
            yield from self._files(arg, self._paths)

    @staticmethod
    def _files(arg: str, completer: PathCompleter) -> Iterable[Completion]:
        return completer.get_completions(Document(arg, len(arg)), CompleteEvent())


def _suffix_filter(suffixes: tuple[str, ...]) -> Callable[[str], bool]:
    """Return a filter keeping folders and files whose names end in one of ``suffixes``."""
    def keep(path: str) -> bool:
        return os.path.isdir(path) or path.lower().endswith(suffixes)

    return keep


def _starting(word: str, items: Iterable[tuple[str, ...]]) -> Iterator[Completion]:
    """Completions of ``word`` among (text, meta[, display]) items, each offered once."""
    seen: set[str] = set()
    for item in items:
        text, meta = item[0], item[1]
        display = item[2] if len(item) > 2 else text
        if text in seen or not text.startswith(word) or text == word:
            continue
        seen.add(text)
        yield Completion(text, -len(word), display=display, display_meta=meta)


_DEF_HEAD = re.compile(r"^\s*(?:atom|behavior|plan|interrupt)\s+[A-Za-z_]\w*\s*\(([^)]*)\)\s*=")


def _own_params(before: str) -> list[str]:
    """Parameter names of the definition being typed (``atom a(d = 1 m, t) = ...``)."""
    m = _DEF_HEAD.match(before)
    if m is None:
        return []
    return [p.split("=")[0].strip() for p in m.group(1).split(",") if p.split("=")[0].strip()]


def _enclosing_call(before: str) -> str | None:
    """Return the name called by the innermost unclosed ``name(`` before the cursor, if any."""
    found = _enclosing_call_at(before)
    return None if found is None else found[0]


def _enclosing_call_at(before: str) -> tuple[str, int, str | None] | None:
    """Find the innermost unclosed call before the cursor.

    Returns (name, index of the argument being typed, its keyword if written
    ``name = ``), or None.
    """
    depth = 0
    commas = 0
    for i in range(len(before) - 1, -1, -1):
        ch = before[i]
        if ch in ")]":
            depth += 1
        elif ch in "([":
            if depth == 0:
                if ch == "[":
                    return None
                m = _CALLEE.search(before[:i])
                if m is None:
                    return None
                arg = before[i + 1:]
                last = arg[_last_top_comma(arg) + 1:]
                kw = re.match(r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*=(?!=)", last)
                return m.group(1), commas, kw.group(1) if kw else None
            depth -= 1
        elif ch == "," and depth == 0:
            commas += 1
    return None


def _last_top_comma(text: str) -> int:
    """Index of the last comma outside brackets in ``text`` (-1 when none)."""
    depth, at = 0, -1
    for i, ch in enumerate(text):
        if ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
        elif ch == "," and depth == 0:
            at = i
    return at


def make_prompt_session(repl: Repl, *, input: Input | None = None,
                        output: Output | None = None, history: bool = True
                        ) -> PromptSession[str]:
    """Return the prompt_toolkit session of the REPL (history, completion, lexer, key bindings).

    ``input``/``output`` default to the terminal; tests pass a pipe input and a dummy
    output. With ``history`` False (or when the data directory cannot be created) the
    history lives in memory only.
    """
    from prompt_toolkit import PromptSession
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
        from prompt_toolkit import PromptSession

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
    import signal

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
