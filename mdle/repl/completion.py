"""Tab completion in the REPL: what may come next at the cursor.

Keywords, defined names, control laws and sensor functions; a law's or sensor's parameter
names inside its call (``follow_boundary(r`` -> ``rc = ``); a symbol parameter's choices
(``side = `` -> ``right``, ``left``); units after a number; the ``:`` commands and their
arguments (world names, file paths). The session's definitions and registry are read
each time, so new definitions complete at once.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Iterable, Iterator

from prompt_toolkit.completion import CompleteEvent, Completer, Completion, PathCompleter
from prompt_toolkit.document import Document

from mdle.core.units import unit_value
from mdle.lang import DefKind
from mdle.repl.commands import COMMANDS, DEFINITION_KEYWORDS, KEYWORDS, Repl

__all__ = ["UNITS", "MdleCompleter"]

#: Units offered after a number (the table of :mod:`mdle.core.units` and their quotients).
UNITS = ("m", "cm", "mm", "s", "ms", "min", "deg", "rad", "m/s", "deg/s", "rad/s")

_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*$")
_NUMBER_BEFORE = re.compile(r"(?<![A-Za-z0-9_.])(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?[ \t]*$")
_CALLEE = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)\s*$")
_KEYWORD_ARG = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)\s*=\s*$")


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


#: The head of a definition with parameters (its keywords are the grammar's: DefKind's).
_DEF_HEAD = re.compile(r"^\s*(?:" + "|".join(k.value for k in DefKind) +
                       r")\s+[A-Za-z_]\w*\s*\(([^)]*)\)\s*=")


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
