"""A user's own control laws and sensor functions, from a Python file: ``--laws FILE.py``.

The file declares them with the decorators the shipped ones use
(``@control_law(...)``, ``@sensor(...)`` of :mod:`mdle.atoms.registry`);
:func:`load_laws` runs it and returns the shipped registry with them added, for
``mdle check``, ``mdle run`` and ``mdle repl``. Whatever goes wrong is an
:class:`~mdle.core.errors.MdleError` naming the file, and the line where the file failed.
"""

from __future__ import annotations

import importlib.util
import inspect
import os
import traceback

from mdle.atoms import default_registry
from mdle.atoms.registry import REQUIRED, LawSpec, Registry, SensorSpec
from mdle.core.errors import Diagnostic, MdleError, Span
from mdle.core.units import Dim

__all__ = ["load_laws", "laws_option", "check_spec"]


def load_laws(path: str | os.PathLike[str], base: Registry | None = None) -> Registry:
    """Return the shipped control laws and sensor functions with those of ``path``.

    ``base`` is the registry they join (None: the shipped one; the installed packages'
    laws, :mod:`mdle.atoms.installed_laws`, when there are any).

    Raises
    ------
    MdleError
        The file is missing, fails while it is run (a wrong spec in a decorator, a
        syntax error: located at its line), declares nothing, or declares a name the
        shipped registry has.
    """
    name = os.fspath(path)
    if not os.path.isfile(name):
        raise MdleError(Diagnostic(None, f"--laws {name}: no such file"))
    spec = importlib.util.spec_from_file_location(
        "mdle_user_laws_" + os.path.splitext(os.path.basename(name))[0], name)
    if spec is None or spec.loader is None:
        raise MdleError(Diagnostic(None, f"--laws {name}: not a Python file (FILE.py)"))
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # the user's code: any failure is theirs, reported located
        raise MdleError(Diagnostic(_where(exc, name), f"the laws of `{name}` could not be "
                                   f"loaded: {type(exc).__name__}: {exc}")) from None
    try:
        user = Registry.from_modules(module)
    except ValueError as exc:  # a name declared twice in the file
        raise MdleError(Diagnostic(None, f"`{name}`: {exc}")) from None
    declared: list[LawSpec | SensorSpec] = [*user.laws.values(), *user.sensors.values()]
    for declared_spec in declared:
        check_spec(declared_spec, name)
    if not user.laws and not user.sensors:
        raise MdleError(Diagnostic(
            None, f"`{name}` declares no control law or sensor function",
            hint="decorate them with `@control_law(...)` or `@sensor(...)` from "
                 "mdle.atoms.registry"))
    shipped = default_registry()
    known = shipped if base is None else base
    for n in (*user.laws, *user.sensors):
        if n in known.laws or n in known.sensors:
            owner = ("a shipped" if n in shipped.laws or n in shipped.sensors
                     else "an installed package's")  # an mdle.laws entry point's
            kind = "control law" if n in known.laws else "sensor function"
            raise MdleError(Diagnostic(
                None, f"`{n}` of `{name}` is already {owner} {kind}",
                hint=f"give it another name, such as `my_{n}` (`name=` in its decorator)"))
    return known.merged(user)


def laws_option(path: str | None) -> Registry | None:
    """Return the registry for ``--laws`` (None, the shipped one, when it is not given)."""
    return None if path is None else load_laws(path)


def check_spec(spec: LawSpec | SensorSpec, name: str) -> None:
    """Refuse a declaration the checker could not use, at the line of its function."""
    fn = spec.step if isinstance(spec, LawSpec) else spec.fn
    try:
        line = inspect.getsourcelines(fn)[1]
        where: Span | None = Span(name, line, 1, line, 2)
    except (OSError, TypeError):
        where = None
    for p in spec.params:
        problem = None
        if not isinstance(p.dim, Dim):
            problem = (f"its dimension is `{p.dim!r}`: give a dimension of mdle.core.units "
                       "(LENGTH, SPEED, ...)")
        elif not (p.default is REQUIRED or isinstance(p.default, (int, float, str))):
            problem = f"its default `{p.default!r}` is not a number in SI units or a symbol"
        elif isinstance(p.default, str) and p.choices and p.default not in p.choices:
            problem = f"its default `{p.default}` is not one of {', '.join(p.choices)}"
        if problem is not None:
            raise MdleError(Diagnostic(where, f"parameter `{p.name}` of `{spec.name}`: "
                                       f"{problem}"))


def _where(exc: BaseException, name: str) -> Span | None:
    """Return the line of ``name`` where ``exc`` was raised (a syntax error's own place)."""
    if isinstance(exc, SyntaxError) and exc.lineno:
        return Span(name, exc.lineno, exc.offset or 1, exc.lineno, (exc.offset or 1) + 1)
    target = os.path.abspath(name)
    line = None
    for frame in traceback.extract_tb(exc.__traceback__):
        if os.path.abspath(frame.filename) == target and frame.lineno:
            line = frame.lineno  # the last frame in the file: where it called what failed
    return None if line is None else Span(name, line, 1, line, 2)
