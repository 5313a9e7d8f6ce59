"""The rooms of the house (docs/architecture.md) keep their doors where the docs say.

Read from the source text, not by importing: an import under ``if TYPE_CHECKING:`` or
inside a function counts as much as one at the top of a module.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterator
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
MDLE = REPO / "mdle"
LANG = MDLE / "lang"


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
    if parts[0] in ("atoms", "sim"):  # installed as mdle.atoms and mdle.sim
        parts = ("mdle", *parts)
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


#: The layer table of docs/architecture.md: `| N | `mdle.a`, `mdle.b` | what they hold |`.
_ROW = re.compile(r"^\|\s*(\d+)\s*\|([^|]*)\|")


def _layers() -> dict[str, int]:
    """Return {package: layer} from the table under `## Layers` in docs/architecture.md."""
    text = (REPO / "docs" / "architecture.md").read_text(encoding="utf-8")
    section = text.split("\n## Layers", 1)[1].split("\n## ", 1)[0]
    layers: dict[str, int] = {}
    for line in section.splitlines():
        m = _ROW.match(line)
        if m:
            for name in re.findall(r"`([\w.]+)`", m[2]):
                layers[name] = int(m[1])
    return layers


def _package_of(module: str, layers: dict[str, int]) -> str | None:
    """Return the longest package of the table that holds ``module`` (None: none does)."""
    parts = module.split(".")
    for n in range(len(parts), 0, -1):
        if ".".join(parts[:n]) in layers:
            return ".".join(parts[:n])
    return None


def _graph() -> dict[str, set[str]]:
    """Return {module: the mdle modules it imports}, any import at any depth."""
    modules = {_module_name(p): p for p in _every_module()}
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        deps = set()
        for _, imported in _imports(path):
            while imported and imported not in modules:
                imported = imported.rpartition(".")[0]
            # a module's own package's face is not an edge (`from mdle.record import require`)
            if imported and imported != name and not name.startswith(imported + "."):
                deps.add(imported)
        graph[name] = deps
    return graph


def test_the_layer_table_names_every_module() -> None:
    layers = _layers()
    assert layers["mdle.core"] < layers["mdle.lang"] < layers["mdle.runtime"] < layers["mdle.cli"]
    lost = [m for m in _graph() if _package_of(m, layers) is None]
    assert not lost, "add these to the table of docs/architecture.md:\n" + "\n".join(lost)


def test_each_package_imports_only_the_layers_below_it() -> None:
    layers = _layers()
    wrong = []
    for module, deps in sorted(_graph().items()):
        mine = _package_of(module, layers)
        assert mine is not None
        for dep in sorted(deps):
            theirs = _package_of(dep, layers)
            assert theirs is not None
            if theirs != mine and layers[theirs] >= layers[mine]:
                wrong.append(f"{module} (layer {layers[mine]}) imports {dep} "
                             f"(layer {layers[theirs]})")
    assert not wrong, "\n".join(wrong)


def test_no_module_imports_itself_through_a_circle() -> None:
    graph = _graph()
    state: dict[str, int] = {}  # 1 on the path, 2 done

    def visit(m: str, path: list[str]) -> None:
        state[m] = 1
        for n in sorted(graph[m]):
            assert state.get(n) != 1, "import circle: " + " -> ".join(path[path.index(n):] + [m, n])
            if n not in state:
                visit(n, path + [m])
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m, [])


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


def _loads_at_import(tree: ast.Module) -> Iterator[str]:
    """Yield the modules a module's top level loads (with their packages), not those
    imported only for type checking."""
    def walk(body: list[ast.stmt]) -> Iterator[ast.stmt]:
        for node in body:
            if isinstance(node, ast.If):
                test = ast.unparse(node.test)
                if test not in ("TYPE_CHECKING", "typing.TYPE_CHECKING"):
                    yield from walk(node.body)
                yield from walk(node.orelse)
            elif isinstance(node, ast.Try):
                yield from walk(node.body)
            else:
                yield node

    for node in walk(tree.body):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
        for name in names:
            parts = name.split(".")
            yield from (".".join(parts[:k]) for k in range(1, len(parts) + 1))


def test_an_import_inside_a_function_defers_a_module() -> None:
    """An import inside a function is there for start-up time: it must defer a module the
    module's own top-level imports do not load already (else it belongs at the top)."""
    trees = {_module_name(p): ast.parse(p.read_text(encoding="utf-8")) for p in _every_module()}
    loads = {m: set(_loads_at_import(t)) for m, t in trees.items()}
    closure: dict[str, set[str]] = {}

    def loaded(m: str) -> set[str]:
        if m not in closure:
            seen: set[str] = set()
            stack = [m]
            while stack:
                x = stack.pop()
                if x not in seen:
                    seen.add(x)
                    stack.extend(loads.get(x, ()))
            closure[m] = seen
        return closure[m]

    wrong = []
    for m, tree in sorted(trees.items()):
        for fn in ast.walk(tree):
            if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            for node in ast.walk(fn):
                if isinstance(node, ast.Import):
                    targets = [a.name for a in node.names]
                elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                    targets = [f"{node.module}.{a.name}" if f"{node.module}.{a.name}" in trees
                               else node.module for a in node.names]
                else:
                    continue
                guarded = any(isinstance(t, ast.Try) and node in ast.walk(t)
                              for t in ast.walk(fn))
                if not guarded and all(t in loaded(m) for t in targets):
                    wrong.append(f"{m}:{node.lineno}: {ast.unparse(node)}")
    assert not wrong, "already loaded at import; move to the top:\n" + "\n".join(wrong)
