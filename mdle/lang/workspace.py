"""The REPL's incremental view of a program: definitions added one input at a time.

A :class:`Workspace` holds every definition entered so far (and those of loaded
files). Unlike a file, it lets a later definition replace an earlier one of the same
name, so a user can fix ``cruise`` and carry on. Every change is checked as a whole
before it is kept: on an error the workspace is left exactly as it was.
"""

from __future__ import annotations

import os
from typing import Any

from mdle.atoms import default_registry
from mdle.atoms.registry import Registry
from mdle.core.errors import CheckError, Diagnostic, MdleError
from mdle.core.motion_limits import KnownRobot
from mdle.lang import syntax as st
from mdle.lang.check import _checker, check_program
from mdle.lang.check_state import _Abort
from mdle.lang.format import format_statement
from mdle.lang.hints import refine_error
from mdle.lang.loader import load_modules, read_source
from mdle.lang.parser import MAX_DEPTH, lex_fragment, parse_expression
from mdle.lang.program import Element, Program
from mdle.lang.resolve import build_namespace

__all__ = ["Workspace"]

_CONTINUES = {"_EQUALS", "COMPARE", "ADD_OP", "MUL_OP", "AND", "OR", "XOR", "NOT", "ATOM",
              "BEHAVIOR", "PLAN", "INTERRUPT", "IMPORT", "RUN"}


def _feed(piece: str, depth: int, opened: int, stopped: bool, last: str | None
          ) -> list[Any]:
    """Advance is_complete's lexer state over ``piece`` (which starts at a line break)."""
    if stopped or not piece:
        return [depth, opened, stopped, last]
    tokens, opened, stopped = lex_fragment(piece, opened)
    for tok in tokens:
        if tok.type in ("LPAR", "LSQB"):
            depth += 1
        elif tok.type in ("RPAR", "RSQB"):
            depth -= 1
    if tokens:
        last = tokens[-1].type
    return [depth, opened, stopped, last]


class Workspace:
    """Definitions entered so far, checked together.

    Parameters
    ----------
    registry : Registry, optional
        Control laws and sensor functions; ``atoms.default_registry()`` when None.
    """

    def __init__(self, registry: Registry | None = None) -> None:
        if registry is None:
            registry = default_registry()
        self.registry = registry
        self._defs: dict[str, st.Definition] = {}
        self._sources: dict[str, str] = {}
        self._entry: str | None = None
        self._warnings: tuple[Diagnostic, ...] = ()
        #: The robot definitions and elements are checked against (speed and turn-rate
        #: limits; None: no comparison). The REPL sets it to the session's robot.
        self.robot: KnownRobot | None = None
        #: The warnings of the element :meth:`element` compiled last.
        self.element_warnings: tuple[Diagnostic, ...] = ()
        #: is_complete's lexer state at the last line break it saw: (text up to there,
        #: bracket depth, brackets open for the depth guard, stopped, last token type)
        self._lexed: tuple[Any, ...] = ("", 0, 0, False, None)

    # ------------------------------------------------------------------ changes

    def define(self, text: str, file: str = "<repl>") -> tuple[Diagnostic, ...]:
        """Add (or replace) the definitions in ``text``; return the new warnings.

        Imports are relative to the current directory.

        Raises
        ------
        MdleError
            On any error; the workspace is then unchanged.
        """
        loaded = load_modules(text, file, base_dir=os.getcwd())
        return self._merge(loaded.modules, dict(loaded.sources), loaded.main)

    def load(self, path: str | os.PathLike[str]) -> tuple[Diagnostic, ...]:
        """Add the definitions of a file and its imports; returns the new warnings.

        Raises
        ------
        MdleError
            On any error; the workspace is then unchanged.
        """
        name = os.fspath(path)
        loaded = load_modules(read_source(name), name)
        return self._merge(loaded.modules, loaded.sources, loaded.main)

    def _merge(self, modules: tuple[st.Module, ...], sources: dict[str, str],
               main: st.Module | None) -> tuple[Diagnostic, ...]:
        # Within one input, the rules of a file hold (a name defined twice is an error).
        fresh = [d for m in modules for d in m.definitions]
        _, clashes = build_namespace(fresh, self.registry)
        all_sources = {**self._sources, **sources}
        if clashes:
            raise CheckError(clashes, all_sources)
        defs = dict(self._defs)
        for d in fresh:
            defs.pop(d.name, None)
            defs[d.name] = d
        runs = [s for s in (main.statements if main else ()) if isinstance(s, st.Run)]
        entry_module = st.Module("<workspace>", (*defs.values(), *runs[-1:]))
        program = check_program([entry_module], self.registry, sources=all_sources,
                                robot=self.robot)
        if runs:
            self._entry = program.entry
        old = {(w.span, w.message) for w in self._warnings}
        self._defs, self._sources, self._warnings = defs, all_sources, program.warnings
        return tuple(w for w in program.warnings if (w.span, w.message) not in old)

    # ------------------------------------------------------------------ queries

    def element(self, text: str) -> Element:
        """Compile a bare element (``cruise``, ``(go(0.3 m/s), stalled, 10 s)``, ``patrol``).

        Raises
        ------
        MdleError
            MdleSyntaxError or CheckError.
        """
        try:
            expr = parse_expression(text, "<repl>")
        except MdleError as err:
            raise refine_error(err, {"<repl>": text}) from None
        sources = {**self._sources, "<repl>": text}
        checker, errors, _ = _checker([st.Module("<workspace>", tuple(self._defs.values()))],
                                      self.registry, False, self.robot)
        element: Element | None = None
        try:
            element = checker.element(expr, {})
        except _Abort:
            pass
        except RecursionError:
            checker.error(expr.span, "this element nests too deeply to check")
        errors = errors + checker.errors
        if errors or element is None:
            raise CheckError(errors or [Diagnostic(expr.span, "not an element")], sources)
        self.element_warnings = tuple(checker.warnings)
        return element

    def is_complete(self, text: str) -> bool:
        """Whether the REPL has a whole input.

        Brackets balanced and the text does not end in the middle of a statement (after
        `=`, an operator, a comma or a keyword). The lexer state at the last line break
        is kept: when the next call's text extends the last one (a statement typed line
        by line), only the new lines are lexed, so a 4,000-line input costs one pass,
        not 4,000.
        """
        prefix, *state = self._lexed
        if not text.startswith(prefix):
            prefix, state = "", [0, 0, False, None]
        cut = text.rfind("\n") + 1
        state = _feed(text[len(prefix):cut], *state)
        self._lexed = (text[:cut], *state)
        depth, _, _, last = _feed(text[cut:], *state)
        if depth >= MAX_DEPTH:
            return True  # too deep to ever parse: let the parser say so now
        if depth > 0:
            return False
        if last is None:
            return True
        return last not in _CONTINUES and last != "_COMMA"

    def names(self) -> list[str]:
        """Return the names defined so far, sorted."""
        return sorted(self._defs)

    def definition(self, name: str) -> st.Definition | None:
        """Return the definition of ``name``, or None."""
        return self._defs.get(name)

    def definitions(self) -> tuple[st.Definition, ...]:
        """Return the definitions so far, oldest first (a replaced one counts as new)."""
        return tuple(self._defs.values())

    def format(self, entry: str | None = None) -> str:
        """Every definition so far in canonical form (as ``mdle fmt`` prints them).

        Then ``run ENTRY``: ``entry``, else the one a ``run`` input gave, if any.
        """
        lines = [format_statement(d) for d in self._defs.values()]
        entry = entry or self._entry
        if entry:
            lines.append(f"run {entry}")
        return "\n".join(lines) + ("\n" if lines else "")

    def program(self) -> Program:
        """Return the checked program of every definition so far."""
        runs: tuple[st.Statement, ...] = ()
        if self._entry:
            runs = (st.Run(self._entry),)
        module = st.Module("<workspace>", (*self._defs.values(), *runs))
        return check_program([module], self.registry, sources=self._sources)

    @property
    def warnings(self) -> tuple[Diagnostic, ...]:
        """The warnings of the definitions as they stand."""
        return self._warnings

