"""``mdle show``: a program's tree and its structure figures, as plain text.

Pure functions from a checked program to a string (colour, if any, is added by the
CLI). The figures:

* atoms: the atoms in the tree (an atom used twice counts twice);
* distinct control laws: how many different laws those atoms run;
* nesting depth: levels from the element shown down to its deepest atom (an atom
  alone is 1);
* worst-case duration: an atom lasts at most its timer; a string at most the sum of
  its elements' worst cases, capped by its own timer; a repeated string lasts until
  its own timer (``inf`` if none). ``inf`` means only an interrupt (or the user) can
  end it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mdle.core.units import NONE, Dim
from mdle.lang.program import AtomNode, Element, Program, StringNode

__all__ = ["Structure", "structure", "show_element", "show_program", "format_time"]


@dataclass(frozen=True)
class Structure:
    """The structure figures of an element (see the module docstring)."""

    atoms: int
    laws: tuple[str, ...]
    depth: int
    duration: float

    @property
    def distinct_laws(self) -> int:
        """How many different control laws the atoms run."""
        return len(self.laws)


def format_time(seconds: float) -> str:
    """Return a duration as people write it: ``inf``, ``10 min``, ``2.5 s``."""
    if math.isinf(seconds):
        return "inf"
    if seconds >= 60 and seconds % 60 == 0:
        return f"{seconds / 60:g} min"
    return f"{seconds:g} s"


def structure(element: Element) -> Structure:
    """Count atoms, laws and depth, and bound the duration, of an element.

    Each distinct element is visited once (memoised by identity), so a definition used
    many times costs one visit: a chain of behaviors each holding the previous one twice
    is counted in time linear in its length, however many atoms it expands to.
    """
    figures: dict[int, tuple[int, frozenset[str], int, float]] = {}
    # Post-order without recursion: (node, children pushed?).
    stack: list[tuple[Element, bool]] = [(element, False)]
    while stack:
        node, expanded = stack.pop()
        if id(node) in figures:
            continue
        if isinstance(node, AtomNode):
            figures[id(node)] = (1, frozenset((node.law.name,)), 1, node.timer)
            continue
        if not expanded:
            stack.append((node, True))
            stack.extend((c, False) for c in node.elements if id(c) not in figures)
            continue
        kids = [figures[id(c)] for c in node.elements]
        laws = frozenset().union(*(k[1] for k in kids)) if kids else frozenset()
        inner = math.inf if node.repeat else sum(k[3] for k in kids)
        below = max((k[2] for k in kids), default=0)  # 0: no atom below to count down to
        figures[id(node)] = (sum(k[0] for k in kids), laws, 1 + below if below else 0,
                             min(node.timer, inner))
    atoms, laws, depth, duration = figures[id(element)]
    return Structure(atoms, tuple(sorted(laws)), depth, duration)


def _show_arg(value: object, dim: Dim) -> str:
    if isinstance(value, str):
        return value
    x = float(value)  # type: ignore[arg-type]
    if dim == NONE:
        return f"{x:g}"
    if dim.angle == 1 and dim.length == 0:
        unit = "deg" + ("/s" if dim.time == -1 else "")
        if dim.time in (0, -1):
            return f"{math.degrees(x):.4g} {unit}"
    return f"{x:.4g} {dim.symbol()}"


def _atom_text(a: AtomNode) -> str:
    live = {} if a.live is None else {arg.name: arg.text for arg in a.live.args}
    args = ", ".join(f"{p.name} = {live.get(p.name) or _show_arg(a.args[p.name], p.dim)}"
                     for p in a.law.params if p.name in a.args)
    text = f"{a.law.name}({args})"
    if a.scale != (1.0, 1.0):
        sv, sw = a.scale
        text += f" scaled by {sv:g}" if sv == sw else f" scaled by [{sv:g}, {sw:g}]"
    return text


def _head(e: Element) -> str:
    ends = f"[{e.interrupt.source} | {format_time(e.timer)}]"
    if isinstance(e, AtomNode):
        name = "atom" if e.label == e.law.name else f"atom {e.label}:"
        sends = "".join(f", {x.source}" for x in e.sends)
        return f"{name} {_atom_text(e)}  {ends}" + (f"  {sends[2:]}" if sends else "")
    kind = e.kind.value
    title = kind if e.label == "group" else f"{kind} {e.label}"
    return f"{title}{' (repeats)' if e.repeat else ''}  {ends}"


def show_element(element: Element) -> str:
    """Return the tree of an element, one line per element, with box-drawing guides.

    A behavior or plan met again (the same definition with the same arguments) is shown
    once in full; later uses are one line ending ``(as above)``, so the text grows with
    the program, not with its expansion.
    """
    lines: list[str] = []
    shown: set[int] = set()
    stack: list[tuple[Element, str, str]] = [(element, "", "")]
    while stack:
        node, lead, child_lead = stack.pop()
        if isinstance(node, StringNode) and node.elements and id(node) in shown:
            lines.append(lead + _head(node) + "  (as above)")
            continue
        lines.append(lead + _head(node))
        if isinstance(node, StringNode):
            shown.add(id(node))
            kids = node.elements
            for i in range(len(kids) - 1, -1, -1):
                last = i == len(kids) - 1
                stack.append((kids[i], child_lead + ("\u2514\u2500\u2500 " if last else
                                                     "\u251c\u2500\u2500 "),
                              child_lead + ("    " if last else "\u2502   ")))
    return "\n".join(lines)


def show_program(program: Program, name: str | None = None) -> str:
    """Show the tree and figures of one element of a program (default: its entry).

    With no entry, every runnable definition is shown.
    """
    names = [name] if name is not None else ([program.entry] if program.entry else
                                             list(program.elements))
    blocks = []
    for n in names:
        e = program.elements[n]
        s = structure(e)
        figures = (f"atoms: {s.atoms}   distinct control laws: {s.distinct_laws} "
                   f"({', '.join(s.laws)})   nesting depth: {s.depth}   "
                   f"worst-case duration: {format_time(s.duration)}")
        blocks.append(show_element(e) + "\n" + figures)
    return "\n\n".join(blocks) + "\n" if blocks else "(no runnable definitions)\n"

