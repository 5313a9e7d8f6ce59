r"""Override parameter defaults of a program's definitions (``--set NAME=VALUE``, sweeps).

``NAME`` is ``DEFINITION.PARAMETER`` (``cruise.v``), or a parameter name alone
(``rc``), which sets that parameter of every definition that has one. ``VALUE`` is an
MDLe fixed value as a plan writes it (``0.2 m/s``, ``0.2m/s``, ``right``, ``2 * 0.5 m``).
The new default replaces the old one in the syntax tree before the program is checked,
and is checked by the checker's rules: a value of the dimension of the default it
replaces (a length for ``rc = 1 m``; a bare number where metres are meant is an error
with the unit to add, as everywhere in MDLe), a symbol the law takes, a fixed value (no
sensor reading). Every problem is located in the override's own text (shown as the file
``--set``), with a note at the parameter::

    --set:1:10: error: `v` of `cruise` is a speed such as `0.3 m/s`, found a length (`0.2 m`)
        cruise.v=0.2 m
                 ^^^^^

Elements that use the definition without that argument run with the new value; a call
that passes its own argument (``cruise(0.1 m/s)``) keeps it. ``mdle run --set`` and
``mdle sweep`` both come here, through ``load_text(..., settings=...)`` /
``load_program(..., settings=...)``.

>>> from mdle.lang.loader import load_text
>>> text = "atom cruise(v = 0.3 m/s) = (go(v), never, 1 s)\nplan main = ((cruise), never, inf)\n"
>>> p = load_text(text, settings={"cruise.v": "0.5 m/s"})
>>> p.elements["cruise"].args["v"]
0.5
"""

from __future__ import annotations

import dataclasses
import difflib
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from mdle.atoms import default_registry
from mdle.atoms.registry import Registry
from mdle.core.errors import CheckError, Diagnostic, MdleError, MdleSyntaxError, Severity, Span
from mdle.lang import syntax as st
from mdle.lang.check import Checker
from mdle.lang.check_state import _Abort
from mdle.lang.dimensions import Symbol, dim_example, dim_words, fits, unit_for
from mdle.lang.parser import parse_expression
from mdle.lang.resolve import Namespace, build_namespace
from mdle.lang.syntax import Loaded

__all__ = ["Override", "parse_override", "apply_overrides", "override_defaults", "OVERRIDE_FILE"]

#: The file name messages give an override's text (``--set:1:10: error: ...``).
OVERRIDE_FILE = "--set"

_NAME = re.compile(r"\s*(?:([A-Za-z_][A-Za-z0-9_]*)\.)?([A-Za-z_][A-Za-z0-9_]*)\s*$")


@dataclass(frozen=True)
class Override:
    """One parsed override: ``definition.param = value``.

    ``definition`` is None when only the parameter was named. ``value`` is the parsed
    expression, its spans in ``file`` (whose text is ``text``), so every message about
    the value points into the override as the user typed it.
    """

    definition: str | None
    param: str
    value: st.Expr
    text: str
    file: str = OVERRIDE_FILE

    @property
    def name(self) -> str:
        """The name as written: ``cruise.v`` or ``rc``."""
        return f"{self.definition}.{self.param}" if self.definition else self.param

    @property
    def name_span(self) -> Span:
        """Where the name is in :attr:`text`."""
        end = self.text.index("=") + 1 if "=" in self.text else len(self.text) + 1
        return Span(self.file, 1, 1, 1, max(2, end))


def parse_override(text: str, file: str = OVERRIDE_FILE) -> Override:
    """Parse ``NAME=VALUE``.

    Raises
    ------
    MdleError
        No ``=``, a name that is not ``PARAM`` or ``DEFINITION.PARAM``, or a value that
        does not parse (the message points into ``text``, shown as file ``file``).
    """
    sources = {file: text}
    whole = Span(file, 1, 1, 1, len(text) + 1)
    if "\n" in text:
        raise MdleSyntaxError(Diagnostic(whole, "an override is one line: NAME=VALUE"), sources)
    name, eq, value = text.partition("=")
    if not eq:
        raise MdleSyntaxError(Diagnostic(
            whole, f"expected NAME=VALUE, found `{text}`",
            hint="for example `cruise.v=0.2 m/s` (a definition's parameter) or `rc=1 m`"),
            sources)
    m = _NAME.match(name)
    if m is None:
        raise MdleSyntaxError(Diagnostic(
            Span(file, 1, 1, 1, len(name) + 1),
            f"`{name.strip()}` is not a parameter name: write PARAMETER or DEFINITION.PARAMETER",
            hint="for example `cruise.v=0.2 m/s` or `rc=1 m`"), sources)
    if not value.strip():
        raise MdleSyntaxError(Diagnostic(
            Span(file, 1, len(name) + 1, 1, len(name) + 2),
            f"no value after `{name.strip()}=`", hint="for example `cruise.v=0.2 m/s`"),
            sources)
    # Pad the value to its column, so the parser's spans point into the text as typed.
    try:
        expr = parse_expression(" " * (len(name) + 1) + value, file)
    except MdleError as err:  # show the text as typed under the message, not the padding
        diags = [dataclasses.replace(d, message=d.message.replace("the file", "the value"))
                 for d in err.diagnostics]
        raise type(err)(diags, sources) from None
    return Override(m.group(1), m.group(2), expr, text, file)


def apply_overrides(modules: Sequence[st.Module], overrides: Sequence[Override],
                    registry: Registry) -> tuple[list[st.Module], list[Diagnostic]]:
    """Return the modules with the overridden defaults, and the errors found.

    ``DEF.PARAM`` names one parameter; ``PARAM`` alone every definition's parameter of
    that name. The value must be a fixed value of the dimension of each default it
    replaces (a symbol for a symbol). Errors are located in the override's text, with a
    note at the parameter.
    """
    defs = [d for m in modules for d in m.definitions]
    ns, _ = build_namespace(defs, registry, replace=True)
    errors: list[Diagnostic] = []
    new_defaults: dict[tuple[str, str], st.Expr] = {}
    for o in overrides:
        targets = _targets(o, ns.definitions, errors)
        for target in targets:
            key = (target.name, o.param)
            if key in new_defaults:
                errors.append(Diagnostic(o.name_span, f"`{target.name}.{o.param}` is set twice"))
                continue
            problem = _misfit(o, target, ns)
            if problem is not None:
                errors.append(problem)
                break  # one message per override is enough
            new_defaults[key] = o.value
    if errors:
        return list(modules), errors
    return [_replaced(m, new_defaults) for m in modules], []


def _misfit(o: Override, target: st.Definition, ns: Namespace) -> Diagnostic | None:
    """Return why ``o``'s value cannot replace the default of ``target``'s parameter."""
    param = next(p for p in target.param_list if p.name == o.param)
    note = (Diagnostic(param.span, f"`{o.param}` of `{target.name}` is declared here",
                       Severity.NOTE),)
    checker = Checker(ns)
    try:
        new = checker.value(o.value, {})
    except _Abort:
        first = checker.errors[0]
        return dataclasses.replace(first, notes=first.notes + note)
    old = None
    if param.default is not None:
        try:
            old = Checker(ns).value(param.default, {})
        except _Abort:
            old = None  # the checker reports the default's own error
    what = f"`{o.param}` of `{target.name}`"
    if isinstance(old, Symbol) and not isinstance(new, Symbol):
        return Diagnostic(o.value.span, f"{what} takes a symbol such as `{old.name}`, found "
                          f"{dim_words(new.dim)}", notes=note)
    if isinstance(new, Symbol):
        choices = _symbol_choices(target, o.param, ns.registry)
        if choices and new.name not in choices:
            close = difflib.get_close_matches(new.name, list(choices), n=1)
            return Diagnostic(
                o.value.span, f"{what} is one of " + " or ".join(f"`{c}`" for c in choices)
                + f", found `{new.name}`", hint=f"did you mean `{close[0]}`?" if close else None,
                notes=note)
        if old is not None and not isinstance(old, Symbol):
            close = difflib.get_close_matches(new.name, ns.names(), n=1)
            return Diagnostic(
                o.value.span, f"{what} is {dim_example(None if old.bare else old.dim)}, "
                f"found the name `{new.name}`",
                hint=f"did you mean `{close[0]}`?" if close else None, notes=note)
        return None
    if isinstance(old, Symbol) or old is None or old.bare or fits(new, old.dim):
        return None
    assert old.dim is not None
    unit = unit_for(old.dim)
    hint = f"add a unit: `{_typed(o)} {unit}`" if new.bare and unit else None
    return Diagnostic(o.value.span, f"{what} is {dim_example(old.dim)}, found "
                      f"{dim_words(new.dim)} (`{_typed(o)}`)", hint=hint, notes=note)


def _symbol_choices(d: st.Definition, param: str, registry: Registry) -> tuple[str, ...]:
    """Return the symbols ``param`` may take where ``d`` passes it to a law or sensor."""
    choices: list[str] = []
    stack: list[st.Expr] = [d.body]
    while stack:
        e = stack.pop()
        if isinstance(e, st.Call):
            spec = registry.laws.get(e.name) or registry.sensors.get(e.name)
            for i, a in enumerate(e.args):
                if spec is None or not (isinstance(a.value, st.Name) and a.value.name == param):
                    continue
                p = spec.param(a.name) if a.name is not None else (
                    spec.params[i] if i < len(spec.params) else None)
                if p is not None:
                    choices += [c for c in p.choices if c not in choices]
        stack.extend(st.children(e))
    return tuple(choices)


def _typed(o: Override) -> str:
    """Return the value as the user typed it."""
    return o.text.partition("=")[2].strip()


def _targets(o: Override, defs: Mapping[str, st.Definition],
             errors: list[Diagnostic]) -> list[st.Definition]:
    """Return the definitions an override sets, or record why there are none."""
    if o.definition is not None:
        d = defs.get(o.definition)
        if d is None:
            close = difflib.get_close_matches(o.definition, list(defs), n=1)
            errors.append(Diagnostic(
                o.name_span, f"no definition named `{o.definition}` in the program",
                hint=f"did you mean `{close[0]}`?" if close else _listing(defs)))
            return []
        if not any(p.name == o.param for p in d.param_list):
            names = [p.name for p in d.param_list]
            close = difflib.get_close_matches(o.param, names, n=1)
            hint = (f"did you mean `{d.name}.{close[0]}`?" if close else
                    f"`{d.name}` has " + ", ".join(f"`{n}`" for n in names) if names else
                    f"`{d.name}` has no parameters")
            errors.append(Diagnostic(o.name_span,
                                     f"`{d.name}` has no parameter `{o.param}`", hint=hint))
            return []
        return [d]
    having = [d for d in defs.values() if any(p.name == o.param for p in d.param_list)]
    if not having:
        names = sorted({p.name for d in defs.values() for p in d.param_list})
        close = difflib.get_close_matches(o.param, names, n=1)
        errors.append(Diagnostic(o.name_span, f"no definition has a parameter `{o.param}`",
                                 hint=f"did you mean `{close[0]}`?" if close else _listing(defs)))
    return having


def _listing(defs: Mapping[str, st.Definition]) -> str:
    params = [f"{d.name}.{p.name}" for d in defs.values() for p in d.param_list]
    return ("parameters: " + ", ".join(f"`{p}`" for p in params)) if params else \
        "the program's definitions have no parameters"


def _replaced(module: st.Module, new: Mapping[tuple[str, str], st.Expr]) -> st.Module:
    """Return ``module`` with the new defaults (the module itself when none applies)."""
    changed = False
    statements: list[st.Statement] = []
    for s in module.statements:
        if isinstance(s, st.Definition) and any((s.name, p.name) in new for p in s.param_list):
            params = tuple(dataclasses.replace(p, default=new.get((s.name, p.name), p.default))
                           for p in s.param_list)
            s = dataclasses.replace(s, params=params)
            changed = True
        statements.append(s)
    return dataclasses.replace(module, statements=tuple(statements)) if changed else module


def override_defaults(loaded: Loaded, settings: Mapping[str, str] | Sequence[str],
                      registry: Registry | None = None) -> Loaded:
    """Return ``loaded`` with parameter defaults replaced by ``settings``.

    Parameters
    ----------
    loaded : Loaded
        The parsed files (:func:`mdle.lang.loader.load_modules`).
    settings : mapping or sequence
        ``NAME -> value text``, or ``NAME=VALUE`` texts as typed after ``--set``.
    registry : Registry, optional
        The control laws and sensor functions (default: the shipped ones).

    Raises
    ------
    MdleError
        Every override that names no parameter, does not parse or does not fit (located
        in its own text; the texts are in ``sources``).
    """
    if registry is None:
        registry = default_registry()
    texts = ([f"{k}={v}" for k, v in settings.items()] if isinstance(settings, Mapping)
             else list(settings))
    parsed: list[Override] = []
    errors: list[Diagnostic] = []
    sources: dict[str, str] = {}
    for i, text in enumerate(texts):
        file = OVERRIDE_FILE if len(texts) == 1 else f"{OVERRIDE_FILE}#{i + 1}"
        sources[file] = text
        try:
            parsed.append(parse_override(text, file))
        except MdleError as err:
            errors.extend(err.diagnostics)
    modules, more = apply_overrides(loaded.modules, parsed, registry)
    errors += more
    all_sources = {**loaded.sources, **sources}
    if errors:
        raise CheckError(errors, all_sources)
    main = next((new for old, new in zip(loaded.modules, modules, strict=True)
                 if old is loaded.main), None)
    return Loaded(tuple(modules), all_sources, main)
