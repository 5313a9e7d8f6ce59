"""The rooms of the house (docs/architecture.md) keep their doors where the docs say.

Read from the source text, not by importing: an import under ``if TYPE_CHECKING:`` or
inside a function counts as much as one at the top of a module.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
MDLE = REPO / "mdle"
LANG = MDLE / "lang"
RUNTIME = MDLE / "runtime"
#: Packages and modules the language must never import: they come after it in the flow
#: text -> syntax -> checked program -> runtime -> backend -> traces, plots, logs.
DOWNSTREAM = ("mdle.runtime", "mdle.sim", "mdle.drivers", "mdle.repl", "mdle.cli",
              "mdle.sweep", "mdle.experiments", "mdle.ros", "mdle.trace", "mdle.plot",
              "mdle.live", "mdle.backend", "mdle.teamrun", "mdle.teamfile", "mdle.teamcheck")


def _imports(path: Path) -> Iterator[tuple[int, str]]:
    """Yield (line, module) for every import in a file, at any depth."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            yield from ((node.lineno, a.name) for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            yield node.lineno, node.module
            # `from mdle.lang import check` names a module too
            yield from ((node.lineno, f"{node.module}.{a.name}") for a in node.names)


def _module_name(path: Path) -> str:
    parts = path.relative_to(REPO).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _is_submodule(name: str, package: Path) -> bool:
    prefix = _module_name(package / "__init__.py") + "."
    sub = name[len(prefix):].split(".")[0] if name.startswith(prefix) else ""
    return bool(sub) and (package / f"{sub}.py").exists()


def _every_module() -> list[Path]:
    # mdle/atoms and mdle/sim are links to the top-level folders; list their files once
    files = [p for p in MDLE.rglob("*.py")
             if not {MDLE / "atoms", MDLE / "sim"} & set(p.parents)]
    return sorted(files + [p for d in ("atoms", "sim") for p in (REPO / d).rglob("*.py")])


def _outside_language() -> list[Path]:
    return [p for p in _every_module() if LANG not in p.parents]


def test_the_rest_of_mdle_imports_the_language_through_its_face() -> None:
    wrong = [f"{p.relative_to(REPO)}:{line}: {name}"
             for p in _outside_language() for line, name in _imports(p)
             if _is_submodule(name, LANG)]
    assert not wrong, "import these from mdle.lang (add the name to its __all__):\n" + \
        "\n".join(wrong)


def test_the_language_never_imports_what_comes_after_it() -> None:
    wrong = [f"{p.relative_to(REPO)}:{line}: {name}"
             for p in sorted(LANG.glob("*.py")) for line, name in _imports(p)
             if any(name == d or name.startswith(d + ".") for d in DOWNSTREAM)]
    assert not wrong, "\n".join(wrong)


def test_runtime_modules_import_one_another_without_a_circle() -> None:
    graph = {_module_name(p): {n for _, n in _imports(p) if _is_submodule(n, RUNTIME)}
             for p in RUNTIME.glob("*.py") if p.name != "__init__.py"}
    graph = {m: {".".join(n.split(".")[:3]) for n in deps} - {m} for m, deps in graph.items()}
    done: set[str] = set()

    def visit(m: str, path: tuple[str, ...]) -> None:
        assert m not in path, "import circle: " + " -> ".join(path[path.index(m):] + (m,))
        if m in done:
            return
        for n in sorted(graph.get(m, ())):
            visit(n, path + (m,))
        done.add(m)

    for m in sorted(graph):
        visit(m, ())


def _lines(path: Path) -> int:
    return path.read_text(encoding="utf-8").count("\n")


def _says_why(path: Path) -> bool:
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
    paragraphs = doc.split("\n\n")
    return len(paragraphs) > 1 and paragraphs[1].startswith("Over 500 lines:")


@pytest.mark.parametrize("path", _every_module(), ids=lambda p: str(p.relative_to(REPO)))
def test_a_long_module_says_why_at_its_top(path: Path) -> None:
    name = path.relative_to(REPO).as_posix()
    if _lines(path) <= 500:
        return
    assert _says_why(path), \
        f"{name} has {_lines(path)} lines: split it, or say why in its docstring's " \
        "second paragraph (`Over 500 lines: ...`)"
