r"""Override parameter defaults of a program's definitions (``--set NAME=VALUE``, sweeps).

A setting ``rc=0.8`` replaces the default of every parameter called ``rc`` of the
definitions (atoms, behaviors, plans, interrupts) in the program's main file; elements
that use the definition without that argument then run with the new value. A bare
number takes the unit of the default it replaces (``0.8`` for ``rc = 1 m`` means
``0.8 m``); the value may be any MDLe expression (``0.8 m``, ``40 deg/s``, ``left``).

>>> from mdle.loader import load_text
>>> text = "atom cruise(v = 0.3 m/s) = (go(v), never, 1 s)\nplan main = ((cruise), never, inf)\n"
>>> p = load_text(text, settings={"v": "0.5"})
>>> p.elements["cruise"].args["v"]
0.5
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import TYPE_CHECKING

from mdle import syntax as st
from mdle.errors import CheckError, Diagnostic, MdleError
from mdle.parser import parse_expression

if TYPE_CHECKING:  # the loader imports this module inside load_text
    from mdle.loader import Loaded

__all__ = ["override_defaults", "settable_parameters", "parse_setting"]


def parse_setting(text: str) -> tuple[str, str]:
    """Split ``NAME=VALUE`` into its two parts.

    Raises
    ------
    ValueError
        No ``=``, or an empty name or value.
    """
    name, eq, value = text.partition("=")
    name, value = name.strip(), value.strip()
    if not eq or not name or not value:
        raise ValueError(f"expected NAME=VALUE, got {text!r}")
    return name, value


def settable_parameters(module: st.Module) -> list[str]:
    """Return the parameter names of the definitions in ``module``, sorted, each once."""
    names = {p.name for d in module.statements if isinstance(d, st.Definition)
             for p in (d.params or ())}
    return sorted(names)


def _value(name: str, text: str, default: st.Expr | None) -> st.Expr:
    where = f"<--set {name}>"
    try:
        expr = parse_expression(text, where)
    except MdleError as err:
        raise CheckError(Diagnostic(None, f"--set {name}={text}: not a value "
                                          f"({err.diagnostics[0].message})")) from None
    if (isinstance(expr, st.Number) and not expr.unit and isinstance(default, st.Number)
            and default.unit):
        expr = parse_expression(f"{text} {default.unit}", where)
    return expr


def override_defaults(loaded: Loaded, settings: Mapping[str, str]) -> Loaded:
    """Return ``loaded`` with the main file's parameter defaults replaced by ``settings``.

    Parameters
    ----------
    loaded : Loaded
        The parsed files (:func:`mdle.loader.load_modules`).
    settings : mapping
        ``NAME -> value text``.

    Raises
    ------
    CheckError
        A name no definition of the main file has as a parameter (the message lists
        those it has), or a value that does not parse.
    """
    from mdle.loader import Loaded

    main = loaded.main if loaded.main is not None else (
        loaded.modules[-1] if loaded.modules else None)
    if main is None:
        raise CheckError(Diagnostic(None, "--set: the program has no file to set parameters in"))
    known = settable_parameters(main)
    for name in settings:
        if name not in known:
            import difflib

            close = difflib.get_close_matches(name, known, n=1)
            hint = (f"did you mean `{close[0]}`?" if close else
                    ("parameters: " + ", ".join(known)) if known else
                    "its definitions have no parameters: write `atom NAME(rc = 1 m) = ...`")
            raise CheckError(Diagnostic(None, f"--set {name}: no definition in `{main.file}` "
                                              f"has a parameter `{name}`", hint=hint))
    statements: list[st.Statement] = []
    for s in main.statements:
        if isinstance(s, st.Definition) and s.params and any(p.name in settings
                                                             for p in s.params):
            params = tuple(dataclasses.replace(p, default=_value(p.name, settings[p.name],
                                                                 p.default))
                           if p.name in settings else p for p in s.params)
            s = dataclasses.replace(s, params=params)
        statements.append(s)
    new_main = dataclasses.replace(main, statements=tuple(statements))
    modules = tuple(new_main if m is main else m for m in loaded.modules)
    return Loaded(modules, loaded.sources, new_main)

