"""Control laws and sensor functions of installed packages: the ``mdle.laws`` entry points.

A package declares its laws for ``mdle check``, ``mdle run`` and ``mdle repl`` with an
entry point in the group ``mdle.laws``, naming a module whose functions carry the
decorators the shipped laws use (``@control_law(...)``, ``@sensor(...)``), or one such
function. In the package's ``pyproject.toml``::

    [project.entry-points."mdle.laws"]
    spiral = "mdle_spiral.laws"

:func:`installed_laws` loads every such entry point; :func:`registry_option` adds a
``--laws FILE.py`` on top. Whatever goes wrong (an entry point that fails to import, a
wrong spec, one that declares nothing, a name that is taken) is an
:class:`~mdle.core.errors.MdleError` naming the entry point and its package, located at the
line that failed, else at the line of ``entry_points.txt`` that declares it.
"""

from __future__ import annotations

import importlib.metadata
import os
import sysconfig
import traceback
from pathlib import Path
from types import ModuleType
from typing import Any

from mdle.atoms import default_registry
from mdle.atoms.registry import LawSpec, Registry, SensorSpec
from mdle.core.errors import Diagnostic, MdleError, Span

__all__ = ["GROUP", "installed_laws", "registry_option"]

#: The entry point group a package declares its laws in.
GROUP = "mdle.laws"

#: Where mdle's own code lives (the package's folder, and those it links to). This module
#: is imported as mdle/atoms/installed_laws.py (through the link in a checkout), so two
#: folders up is the package's.
_MDLE = tuple(os.path.realpath(Path(__file__).parent.parent / d) + os.sep
              for d in (".", "atoms", "sim", "grammar"))
#: Python's standard library (importlib), and where packages are installed (which may lie
#: inside it, as in a pyenv interpreter)
_STDLIB = os.path.realpath(sysconfig.get_paths()["stdlib"]) + os.sep
_SITE = tuple(os.path.realpath(sysconfig.get_paths()[k]) + os.sep for k in ("purelib", "platlib"))


def registry_option(laws: str | None) -> Registry | None:
    """Return the registry for ``mdle check/run/repl``: the installed laws and ``--laws``.

    None (the shipped registry) when no package declares laws and ``--laws`` is not given.
    """
    from mdle.atoms.userlaws import load_laws

    installed = installed_laws()
    if laws is None:
        return installed
    return load_laws(laws, base=installed)


def installed_laws() -> Registry | None:
    """Return the shipped laws with those of every ``mdle.laws`` entry point (None: none).

    Raises
    ------
    MdleError
        An entry point fails to load, names something that declares no law, declares a
        wrong spec, or a name the shipped laws or another entry point already have.
    """
    points = sorted(importlib.metadata.entry_points(group=GROUP),
                    key=lambda ep: (ep.name, ep.value))
    if not points:
        return None

    registry = default_registry()
    owner: dict[str, str] = {}  # each name declared by an entry point: which one
    for ep in points:
        what = _describe(ep)
        user = _load(ep, what)
        for name in (*user.laws, *user.sensors):
            if name in registry.laws or name in registry.sensors:
                taken = owner.get(name)
                kind = "control law" if name in registry.laws else "sensor function"
                already = (f"already a {kind} of the {taken}" if taken is not None
                           else f"already a shipped {kind}")
                raise MdleError(Diagnostic(
                    _declared_at(ep), f"`{name}` of the {what} is {already}",
                    hint=f"give it another name, such as `my_{name}` (`name=` in its "
                         "decorator)"))
            owner[name] = what
        registry = registry.merged(user)
    return registry


def _load(ep: importlib.metadata.EntryPoint, what: str) -> Registry:
    """Import one entry point and return what it declares (checked)."""
    from mdle.atoms.userlaws import check_spec

    try:
        target: Any = ep.load()
    except Exception as exc:  # the package's code: any failure is its own, located
        raise MdleError(Diagnostic(
            _failed_at(exc) or _declared_at(ep),
            f"the {what} could not be loaded: {type(exc).__name__}: {exc}",
            hint=_fix(ep))) from None
    if isinstance(target, ModuleType):
        try:
            user = Registry.from_modules(target)
        except ValueError as exc:  # a name declared twice in the module
            raise MdleError(Diagnostic(_declared_at(ep), f"the {what}: {exc}")) from None
    else:
        spec = getattr(target, "__mdle_spec__", None)
        user = Registry.from_specs([spec] if isinstance(spec, (LawSpec, SensorSpec)) else [])
    if not user.laws and not user.sensors:
        raise MdleError(Diagnostic(
            _declared_at(ep), f"the {what} declares no control law or sensor function",
            hint="name a module whose functions are decorated with `@control_law(...)` or "
                 "`@sensor(...)` from mdle.atoms.registry, or one such function"))
    declared_specs: list[LawSpec | SensorSpec] = [*user.laws.values(), *user.sensors.values()]
    for declared in declared_specs:
        fn = declared.step if isinstance(declared, LawSpec) else declared.fn
        code = getattr(fn, "__code__", None)
        check_spec(declared, ep.value if code is None else code.co_filename)
    return user


def _describe(ep: importlib.metadata.EntryPoint) -> str:
    """``entry point `spiral = mdle_spiral.laws` of mdle-spiral 0.1 (group mdle.laws)``."""
    dist = getattr(ep, "dist", None)
    package = "" if dist is None else f" of {dist.metadata['Name']} {dist.version}"
    return f"entry point `{ep.name} = {ep.value}`{package} (group {GROUP})"


def _fix(ep: importlib.metadata.EntryPoint) -> str:
    dist = getattr(ep, "dist", None)
    name = "the package" if dist is None else dist.metadata["Name"]
    return (f"fix {name}, or uninstall it (`pip uninstall {name}`) to run without its laws"
            if dist is not None else "fix the package that declares it, or uninstall it")


def _failed_at(exc: BaseException) -> Span | None:
    """Return the line of the package's code where ``exc`` was raised, if it is known."""
    if isinstance(exc, SyntaxError) and exc.filename and exc.lineno:
        return Span(exc.filename, exc.lineno, exc.offset or 1, exc.lineno,
                    (exc.offset or 1) + 1)
    last = None
    for frame in traceback.extract_tb(exc.__traceback__):
        name = frame.filename
        if name.startswith("<") or not frame.lineno:
            continue  # importlib's own frames
        real = os.path.realpath(name)
        if real.startswith(_MDLE) or (real.startswith(_STDLIB) and not real.startswith(_SITE)):
            continue  # mdle's decorators, importlib: the package's line called them
        last = Span(name, frame.lineno, 1, frame.lineno, 2)
    return last


def _declared_at(ep: importlib.metadata.EntryPoint) -> Span | None:
    """Return the line of ``entry_points.txt`` that declares ``ep`` (None if not found)."""
    dist = getattr(ep, "dist", None)
    if dist is None:
        return None
    for f in dist.files or ():
        if f.name != "entry_points.txt":
            continue
        path = Path(str(dist.locate_file(f)))
        try:
            lines = path.read_text(encoding="utf-8").splitlines()
        except (OSError, UnicodeDecodeError):
            return None
        for number, line in enumerate(lines, 1):
            key, _, value = line.partition("=")
            if key.strip() == ep.name and value.strip() == ep.value:
                return Span(str(path), number, 1, number, len(line) + 1)
    return None
