"""The language's modules import one another one way, at the top, with no cycle.

Read from the source text: an import inside a function hides a cycle as well as it
delays a cost, so the language has none (its start-up costs are in what it imports,
not in when).
"""

from __future__ import annotations

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
LANG = REPO / "mdle" / "lang"


def _modules() -> dict[str, Path]:
    return {p.stem: p for p in sorted(LANG.glob("*.py")) if p.stem != "__init__"}


def _lang_imports(tree: ast.AST) -> set[str]:
    """The modules of mdle.lang an import statement names (``from mdle.lang import x`` too)."""
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module.startswith("mdle.lang."):
                out.add(node.module.split(".")[2])
            elif node.module == "mdle.lang":
                out |= {a.name for a in node.names if (LANG / f"{a.name}.py").exists()}
        elif isinstance(node, ast.Import):
            out |= {a.name.split(".")[2] for a in node.names if a.name.startswith("mdle.lang.")}
    return out


def test_no_import_inside_a_function() -> None:
    hidden = []
    for name, path in _modules().items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                hidden += [f"{name}.py:{inner.lineno}" for inner in ast.walk(node)
                           if isinstance(inner, (ast.Import, ast.ImportFrom))]
    assert hidden == []


def test_no_import_cycle_between_the_language_s_modules() -> None:
    graph = {name: _lang_imports(ast.parse(path.read_text(encoding="utf-8"))) - {name}
             for name, path in _modules().items()}
    assert "overrides" in graph["loader"] and "loader" not in graph["overrides"]
    # Depth-first search for a back edge; the path to it names the cycle.
    state: dict[str, int] = {}  # 1: on the path, 2: done
    cycles: list[list[str]] = []

    def visit(name: str, path: list[str]) -> None:
        state[name] = 1
        for other in sorted(graph.get(name, ())):
            if state.get(other) == 1:
                cycles.append(path[path.index(other):] + [name, other] if other in path
                              else [name, other])
            elif other not in state:
                visit(other, path + [name])
        state[name] = 2

    for name in graph:
        if name not in state:
            visit(name, [])
    assert cycles == []
