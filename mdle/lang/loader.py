"""Files to checked programs: reading, imports, and the whole check.

``import "other.mdle"`` names a file relative to the importing file (relative to the
current directory for text that comes from no file). Every file is read once however
many files import it; an import cycle is an error naming the chain. Syntax errors of
every file are reported together, then the check errors.
"""

from __future__ import annotations

import functools
import os
import re
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass

from mdle.atoms import default_registry
from mdle.atoms.registry import Registry
from mdle.core.collector import collector_paused, release_in_slices
from mdle.core.errors import CheckError, Diagnostic, MdleError, MdleSyntaxError, Severity, Span
from mdle.core.motion_limits import KnownRobot
from mdle.core.userfile import UserFileError, read_user_file
from mdle.lang import syntax as st
from mdle.lang.check import check_program
from mdle.lang.hints import refine_hints
from mdle.lang.overrides import override_defaults
from mdle.lang.parser import normalise_newlines, parse_partial
from mdle.lang.program import Program
from mdle.lang.syntax import Loaded
from mdle.lang.vocabulary import word_of

__all__ = ["load_program", "load_text", "load_modules", "read_source", "plan_bundle", "Loaded"]


def read_source(path: str | os.PathLike[str], shown: str | None = None,
                span: Span | None = None) -> str:
    """Return the text of a plan file (UTF-8, an optional BOM dropped).

    Only a regular file of at most :data:`mdle.core.userfile.MAX_FILE_BYTES` is read.

    Raises
    ------
    MdleError
        A CheckError if the file cannot be read, a MdleSyntaxError if it is not text.
    """
    name = shown if shown is not None else os.fspath(path)
    try:
        data = read_user_file(path)
    except UserFileError as err:
        raise CheckError(Diagnostic(span, f"cannot read `{name}`: {err.reason}")) from None
    try:
        return normalise_newlines(data.decode("utf-8-sig"))
    except UnicodeDecodeError as err:
        line = data[:err.start].count(b"\n") + 1
        col = err.start - (data.rfind(b"\n", 0, err.start) + 1) + 1
        raise MdleSyntaxError(Diagnostic(
            Span(name, line, col, line, col + 1),
            f"`{name}` is not UTF-8 text (byte 0x{data[err.start]:02x} at offset {err.start})",
            hint="MDLe plans are plain text files; is this a binary file?")) from None


@functools.lru_cache(maxsize=1)
def _import_line() -> re.Pattern[str]:
    """Return the pattern of an import statement on a line of its own."""
    return re.compile(r'^[ \t]*' + word_of("IMPORT") + r'[ \t]+"([^"\n]*)"', re.M)


def _scan_imports(text: str, file: str) -> list[st.Import]:
    """Return the imports of a file that does not parse (found line by line)."""
    out = []
    for m in _import_line().finditer(text):
        line = text.count("\n", 0, m.start()) + 1
        col = m.start() - (text.rfind("\n", 0, m.start()) + 1) + 1
        out.append(st.Import(m.group(1), Span(file, line, col, line, col + len(m.group(0)))))
    return out


def _imports(module: st.Module) -> Iterator[st.Import]:
    return (s for s in module.statements if isinstance(s, st.Import))


def load_modules(text: str, file: str, base_dir: str | None = None,
                 files: Mapping[str, str] | None = None) -> Loaded:
    """Parse a text and every file it imports, transitively.

    ``files`` gives the imported files' texts by path relative to ``base_dir`` (the
    main file's folder), instead of reading them from disk: a plan that travels to
    another machine with its imports (see :func:`plan_bundle`).

    Raises
    ------
    MdleError
        With the diagnostics of every file (syntax errors, missing files, import cycles).
    """
    found = _load(text, file, base_dir, files)
    if found.diagnostics:
        raise _error(found.diagnostics, found.loaded.sources, found.syntax_failed)
    return found.loaded


@dataclass(frozen=True)
class _Found:
    """Every file of a program as far as it parses, and what went wrong."""

    loaded: Loaded
    diagnostics: list[Diagnostic]
    syntax_failed: bool
    imports_failed: bool  # an import missing, unreadable, in a cycle or with a syntax error
    unparsed: frozenset[str]  # names defined by statements with syntax errors


def _load(text: str, file: str, base_dir: str | None,
          files: Mapping[str, str] | None) -> _Found:
    text = normalise_newlines(text)
    sources: dict[str, str] = {file: text}
    diagnostics: list[Diagnostic] = []
    unparsed: set[str] = set()
    syntax_failed = imports_failed = False

    def parse(src: str, name: str) -> st.Module:
        nonlocal syntax_failed, imports_failed
        part = parse_partial(src, name)
        if not part.diagnostics:
            return part.module
        syntax_failed = True
        imports_failed = imports_failed or part.broken_import
        diagnostics.extend(refine_hints(part.diagnostics, {name: src}))
        unparsed.update(part.unparsed)
        # Still follow every import of the file (those in broken statements too), so
        # their errors are reported as well.
        kept = part.module.statements
        seen = {(s.path, s.span.line) for s in kept if isinstance(s, st.Import)}
        more = [i for i in _scan_imports(src, name) if (i.path, i.span.line) not in seen]
        return st.Module(name, kept + tuple(more), part.module.comments)

    root_dir = base_dir if base_dir is not None else (
        os.path.dirname(os.path.abspath(file)) if not file.startswith("<") else os.getcwd())
    main = parse(text, file)
    order: list[st.Module] = []
    root_key = os.path.realpath(file) if not file.startswith("<") else file
    state: dict[str, int] = {root_key: 1}  # 1: being loaded (on the path), 2: done
    path: list[tuple[str, str]] = [(root_key, file)]
    stack: list[tuple[st.Module, str, Iterator[st.Import]]] = [(main, root_dir, _imports(main))]
    while stack:
        module, folder, todo = stack[-1]
        imp = next(todo, None)
        if imp is None:
            stack.pop()
            key, _ = path.pop()
            state[key] = 2
            order.append(module)
            continue
        if not imp.path or "\x00" in imp.path:
            diagnostics.append(Diagnostic(imp.span, "`import` needs a file name",
                                          hint='for example `import "common.mdle"`'))
            imports_failed = True
            continue
        target = os.path.join(folder, imp.path)
        key = os.path.realpath(target)
        shown = os.path.normpath(os.path.join(os.path.dirname(module.file), imp.path)) \
            if not module.file.startswith("<") else os.path.normpath(imp.path)
        if state.get(key) == 1:
            chain = [s for k, s in path[[k for k, _ in path].index(key):]] + [shown]
            diagnostics.append(Diagnostic(imp.span, "import cycle: " + " \u2192 ".join(chain),
                                          hint="move the shared definitions into a file that "
                                               "both import"))
            imports_failed = True
            continue
        if state.get(key) == 2:
            continue
        try:
            src = (read_source(target, shown, imp.span) if files is None
                   else _from_bundle(files, os.path.relpath(target, root_dir), shown, imp.span))
        except MdleError as err:
            diags = err.diagnostics
            if diags and diags[0].span is imp.span:
                diags = (Diagnostic(imp.span, diags[0].message.replace(
                    f"cannot read `{shown}`", f"cannot import `{imp.path}`"),
                    hint=f"looked for {os.path.abspath(target)} (imports are relative to the "
                         "importing file)"),)
            syntax_failed = syntax_failed or isinstance(err, MdleSyntaxError)
            imports_failed = True
            diagnostics.extend(diags)
            state[key] = 2
            continue
        sources[shown] = src
        sub = parse(src, shown)
        state[key] = 1
        path.append((key, shown))
        stack.append((sub, os.path.dirname(target), _imports(sub)))
    return _Found(Loaded(tuple(order), sources, main), diagnostics, syntax_failed,
                  imports_failed, frozenset(unparsed))


def _from_bundle(files: Mapping[str, str], rel: str, shown: str, span: Span) -> str:
    try:
        return files[os.path.normpath(rel)]
    except KeyError:
        raise CheckError(Diagnostic(span, f"cannot read `{shown}`: no such file")) from None


def plan_bundle(path: str | os.PathLike[str]) -> tuple[str, dict[str, str]]:
    """Return a plan file's text and its imports' texts by path relative to its folder.

    What :func:`load_text` needs (with ``files=``) to load the program on a machine
    that has none of the files.

    Raises
    ------
    MdleError
        The file or an import cannot be read, or does not parse.
    """
    name = os.fspath(path)
    text = read_source(name)
    loaded = load_modules(text, name)
    folder = os.path.dirname(name)
    files = {os.path.normpath(os.path.relpath(shown, folder or ".")): src
             for shown, src in loaded.sources.items() if shown != name}
    return text, files


def _error(diags: list[Diagnostic], sources: dict[str, str], syntax: bool) -> MdleError:
    cls = MdleSyntaxError if syntax else CheckError
    files = {name: i for i, name in enumerate(sources)}
    ordered = sorted(diags, key=lambda d: (files.get(d.span.file, len(files)), d.span.line,
                                           d.span.column) if d.span else (-1, 0, 0))
    return cls(ordered, sources)


def load_text(text: str, file: str = "<string>", registry: Registry | None = None, *,
              settings: Mapping[str, str] | Sequence[str] | None = None,
              files: Mapping[str, str] | None = None, base_dir: str | None = None,
              robot: KnownRobot | None = None) -> Program:
    """Parse and check a program given as text.

    Parameters
    ----------
    text : str
        The program.
    file : str
        The name messages show; imports are relative to its folder (to the current
        directory for names such as ``<string>``).
    registry : Registry, optional
        Control laws and sensor functions; ``atoms.default_registry()`` when None.
    settings : mapping, optional
        Parameter defaults to override: ``NAME -> value text``, or ``NAME=VALUE`` texts
        (``mdle run --set``); see :func:`mdle.lang.overrides.override_defaults`.
    files : mapping, optional
        Imported files' texts by relative path, instead of the disk (see
        :func:`load_modules`); ``base_dir`` is the folder they are relative to.
    robot : KnownRobot, optional
        The robot the plan is meant for: constants beyond its speed or turn-rate limits
        are warnings (see :mod:`mdle.core.motion_limits`).

    Raises
    ------
    MdleError
        MdleSyntaxError or CheckError, with ``.sources`` filled.
    """
    if registry is None:
        registry = default_registry()
    with collector_paused():  # millions of objects that live on: see mdle/core/collector.py
        found = _load(text, file, base_dir, files)
        loaded = found.loaded
        if found.diagnostics:
            raise _error(found.diagnostics + _check_errors(found, registry), loaded.sources,
                         found.syntax_failed)
        if settings:
            loaded = override_defaults(loaded, settings, registry)
        program = check_program(loaded.modules, registry, sources=loaded.sources,
                                main=loaded.main, robot=robot)
        # The syntax trees go a slice of statements at a time: freed at once when this
        # returned, those of a 200,000-line plan held Ctrl-C for 0.2 s of CPU
        statements = [s for m in (*found.loaded.modules, *loaded.modules) for s in m.statements]
        del found, loaded
        release_in_slices(statements)
        return program


def _check_errors(found: _Found, registry: Registry) -> list[Diagnostic]:
    """Return the check errors of the statements that parsed, in files with syntax errors.

    One pass then reports every independent error of a file. Not done when an import
    is missing or circular: every name it should define would be reported unknown.
    """
    if found.imports_failed:
        return []
    loaded = found.loaded
    try:
        check_program(loaded.modules, registry, sources=loaded.sources, main=loaded.main,
                      unparsed=found.unparsed)
    except CheckError as err:
        return list(err.diagnostics)
    return []


def load_program(path: str | os.PathLike[str], registry: Registry | None = None, *,
                 settings: Mapping[str, str] | Sequence[str] | None = None,
                 robot: KnownRobot | None = None) -> Program:
    """Read, parse, resolve imports and check a plan file.

    ``registry=None`` means ``atoms.default_registry()``; ``settings`` and ``robot`` as
    for :func:`load_text`.

    Raises
    ------
    MdleError
        MdleSyntaxError or CheckError (with ``.sources`` filled) on any error.
    """
    name = os.fspath(path)
    text = read_source(name)
    try:
        return load_text(text, name, registry, settings=settings, robot=robot)
    except RecursionError:  # a last guard; the nesting limits should make it unreachable
        raise CheckError(Diagnostic(Span(name, 1, 1, 1, 2), "the program nests too deeply",
                                    Severity.ERROR), {name: text}) from None
