"""The checker's entry point: syntax tree to the runnable program of :mod:`mdle.lang.program`.

:func:`check_program` builds the namespace, finds recursive definitions, and checks
every definition in dependency order with one :class:`Checker`, which joins the
checker's concerns: names and arity (:mod:`~mdle.lang.check_names`), dimensions
(:mod:`~mdle.lang.check_dimensions`), structure and reachability
(:mod:`~mdle.lang.check_structure`), over their shared state
(:mod:`~mdle.lang.check_state`). Errors are collected, not raised one at a time:
:func:`check_program` raises one :class:`~mdle.core.errors.CheckError` with all of them.

A definition with parameters is checked once on its own (parameters without a
default may be anything) and again for each distinct use with arguments, so a
dimension that only a call fixes is still checked; results are cached per arguments.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from types import MappingProxyType

from mdle.atoms.registry import REQUIRED, Registry
from mdle.core.collector import release_in_slices
from mdle.core.errors import CheckError, Diagnostic, Severity, Span
from mdle.core.motion_limits import KnownRobot
from mdle.lang import syntax as st
from mdle.lang.check_dimensions import DimensionChecks
from mdle.lang.check_names import NameChecks
from mdle.lang.check_state import _UNKNOWN, MAX_NESTING, _Abort, _freeze, _kind_name
from mdle.lang.check_structure import StructureChecks, never_ends
from mdle.lang.program import Element, Program
from mdle.lang.resolve import Namespace, build_namespace, find_cycles, uses_of

__all__ = ["Checker", "check_program", "MAX_NESTING", "missing_entry", "never_ends"]


class Checker(NameChecks, DimensionChecks, StructureChecks):
    """Checks definitions and compiles elements against one namespace.

    Diagnostics accumulate in :attr:`errors` and :attr:`warnings`; each public method
    returns None for a part that has errors (after reporting them).
    """

    # ------------------------------------------------------------------ whole programs

    def limit_warnings(self, entry: str | None) -> None:
        """Give the held robot-limit warnings of atoms not used only scaled.

        An atom that runs as it stands (the entry, an unscaled use, or no use at all) gets
        its warnings; one whose every use scales it gets only the scaled uses' own.
        """
        for name, held in self.deferred.items():
            uses = self.scaled_uses.get(name, set())
            if uses == {True} and name != entry:
                continue
            for where, message, hint in held:
                self.warn(where, message, hint=hint)

    def release(self) -> None:
        """Empty the checker's tables a slice at a time; it is not used afterwards.

        Freed with the checker in one go, the tables of a 200,000-line plan took 0.1 s
        of CPU in which no signal was acted on.
        """
        for table in vars(self).values():  # its own tables (the registry is not one)
            if isinstance(table, (list, dict)):
                release_in_slices(table)

    def check_definition(self, d: st.Definition) -> Element | None:
        """Check a definition on its own; returns its element if it can run as it stands."""
        if d.name in self.broken:
            return None
        slots = self.slots_of(d)
        if slots:
            runnable = all(s.default is not REQUIRED for s in slots)
            bound = {s.name: (_UNKNOWN if s.default is REQUIRED else s.default) for s in slots}
        else:
            runnable, bound = True, {}
        self._partial = not runnable
        if d.kind is st.DefKind.ATOM:
            self._deferring = self.deferred.setdefault(d.name, [])
        try:
            if d.kind is st.DefKind.INTERRUPT:
                self._interrupt_body(d, bound, None)
                return None
            e = self.instance(d, bound)
        except _Abort:
            return None
        finally:
            self._partial = False
            self._deferring = None
        if runnable:
            key = ("element", d.name, _freeze(bound))
            self.element_uses[d.name] = tuple(dict.fromkeys(self._key_uses.get(key, ())))
        return e if runnable else None


def check_program(modules: Sequence[st.Module], registry: Registry, *,
                  sources: Mapping[str, str] | None = None, main: st.Module | None = None,
                  replace: bool = False, unparsed: frozenset[str] = frozenset(),
                  robot: KnownRobot | None = None) -> Program:
    """Check the modules of a program (the main file last) and build its :class:`Program`.

    Parameters
    ----------
    modules : sequence of Module
        Every file of the program, imports first, each once.
    registry : Registry
        The control laws and sensor functions names resolve to.
    sources : mapping, optional
        File texts by name (kept in the program and the error, for messages).
    main : Module, optional
        The file whose ``run`` names the entry (default: the last module).
    replace : bool
        Later definitions replace earlier ones of the same name (the REPL).
    unparsed : frozenset of str
        Names defined by statements with syntax errors (left out of ``modules``): using
        one is not reported again.
    robot : KnownRobot, optional
        The robot the plan is meant for: a constant speed or turn rate beyond its limits
        is a warning. None: no comparison.

    Raises
    ------
    CheckError
        With every error found (warnings are in ``Program.warnings``).
    """
    srcs = dict(sources or {})
    checker, errors, uses = _checker(modules, registry, replace, robot)
    checker.unparsed = unparsed
    main = main if main is not None else (modules[-1] if modules else None)
    elements: dict[str, Element] = {}
    for d in _dependency_order(checker.ns, checker.broken, uses):
        try:
            e = checker.check_definition(d)
        except RecursionError:  # a last guard: the nesting limits should prevent this
            checker.error(d.span, f"`{d.name}` nests too deeply to check",
                          hint="flatten it: fewer levels of elements or interrupts inside "
                               "each other")
            checker.broken.add(d.name)
            continue
        if e is not None:
            elements[d.name] = e
    try:
        entry = _entry(checker, main, elements)
    except RecursionError:
        checker.error(None, "the program nests too deeply to check")
        entry = None
    checker.limit_warnings(entry)
    errors.extend(checker.errors)
    if errors:
        raise CheckError(_ordered(errors), srcs)
    program = Program(MappingProxyType(elements), entry, MappingProxyType(srcs),
                      tuple(_ordered(checker.warnings)), tuple(dict.fromkeys(checker.uses)),
                      MappingProxyType({n: u for n, u in checker.element_uses.items()
                                        if n in elements}))
    checker.release()
    release_in_slices(uses)
    return program


def _dependency_order(ns: Namespace, broken: set[str],
                      uses: Mapping[str, list[st.Name | st.Call]]) -> list[st.Definition]:
    """Order definitions so that what each uses comes first.

    A long chain of definitions is then checked one link at a time (each use finds its
    element already built).
    """
    order: list[st.Definition] = []
    done: set[str] = set()
    for root in ns.definitions:
        if root in done:
            continue
        stack = [(root, False)]
        while stack:
            name, expanded = stack.pop()
            if expanded:
                order.append(ns.definitions[name])
                continue
            if name in done:
                continue
            done.add(name)
            stack.append((name, True))
            if name not in broken:
                stack.extend((r.name, False) for r in uses[name] if r.name not in done)
    return order


def _checker(modules: Sequence[st.Module], registry: Registry, replace: bool,
             robot: KnownRobot | None = None
             ) -> tuple[Checker, list[Diagnostic], dict[str, list[st.Name | st.Call]]]:
    defs = [d for m in modules for d in m.definitions]
    ns, errors = build_namespace(defs, registry, replace=replace)
    uses = uses_of(ns)
    broken, cycle_errors = find_cycles(ns, uses)
    checker = Checker(ns, robot)
    checker.broken = broken
    # definitions refused for taking a law's or sensor function's name: their uses are
    # not reported again (the refusal says it all)
    checker.refused = frozenset(d.name for d in defs if d.name not in ns.definitions)
    return checker, errors + cycle_errors, uses


def _entry(checker: Checker, main: st.Module | None, elements: Mapping[str, Element]) -> str | None:
    runs = [s for s in main.statements if isinstance(s, st.Run)] if main else []
    if len(runs) > 1:
        checker.error(runs[1].span, f"`run` is given twice: {runs[0].span} and {runs[1].span}",
                      notes=(Diagnostic(runs[0].span, "first `run` here", Severity.NOTE),))
    if not runs:
        return "main" if "main" in elements else None
    run = runs[-1]
    target = checker.ns.lookup(run.name)
    if isinstance(target, st.Definition) and target.kind is not st.DefKind.INTERRUPT:
        if run.name in elements:
            return run.name
        missing = [s.name for s in checker.slots_of(target) if s.default is REQUIRED]
        if missing:
            checker.error(run.name_span, f"`{run.name}` cannot run as it stands: it needs "
                          + ", ".join(f"`{m}`" for m in missing),
                          hint="give those parameters defaults, or define a plan that calls "
                               f"`{run.name}(...)` with arguments")
        return None
    if target is None:
        pool = [n for n, d in checker.ns.definitions.items() if d.kind is not st.DefKind.INTERRUPT]
        checker._unknown(run.name, run.name_span, "element", pool)
    else:
        checker.error(run.name_span, f"`run` takes an atom, behavior or plan; `{run.name}` is "
                      f"{_kind_name(target)}")
    return None


def missing_entry(program: Program, file: str) -> Diagnostic | None:
    """Return the warning for a file ``mdle run`` cannot run: no ``run`` and no ``main``.

    None when the program has an entry. The warning points at the line after the file's
    last, where a ``run`` line would go.
    """
    if program.entry is not None:
        return None
    text = program.sources.get(file, "")
    end = text.rstrip().count("\n") + 2 if text.strip() else 1
    span = Span(file, end, 1, end, 2)
    names = sorted(program.elements)
    hint = (f"add `run {names[-1] if len(names) == 1 else 'NAME'}` (runnable here: "
            f"{', '.join(names)}); a file that other plans only import needs none" if names
            else "nothing here runs as it stands: define an atom, behavior or plan whose "
                 "parameters all have defaults (or that calls others with arguments), and "
                 "`run` it")
    return Diagnostic(span, "nothing to run: the file has no `run NAME` line and no plan "
                      "named `main`, so `mdle run` cannot run it", Severity.WARNING, hint)


def _ordered(diags: list[Diagnostic]) -> list[Diagnostic]:
    return sorted(diags, key=lambda d: (d.span.file, d.span.line, d.span.column)
                  if d.span else ("", 0, 0))

