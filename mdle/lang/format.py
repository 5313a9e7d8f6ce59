"""The canonical form of MDLe text (``mdle fmt``).

Layout rules (docs/language.md, "Layout"):

* one statement per line, in the order written; one blank line kept where the source
  had one or more;
* a statement that fits in :data:`WIDTH` columns stays on one line; otherwise the
  outermost tuple or call that does not fit is opened, one part per line indented by
  four spaces, each part followed by a comma, and the closing bracket on its own line;
* spaces around ``=`` and binary operators, after commas; numbers keep their digits
  and take one space before the unit (``0.3 m/s``);
* comments are kept: a comment on its own line stays above the statement that
  follows it, a comment after a statement stays at the end of that statement, and a
  comment inside a statement moves to just above it.

Parsing the output gives the same syntax tree (the round trip is tested), and
formatting is idempotent.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from mdle.core.errors import MdleError
from mdle.lang import syntax as st
from mdle.lang.hints import refine_error
from mdle.lang.parser import parse_module

__all__ = ["WIDTH", "format_source", "format_module", "format_statement", "format_expr"]

#: Line width the formatter aims for.
WIDTH = 100
_INDENT = "    "


def format_source(text: str, file: str = "<string>") -> str:
    """Return the canonical form of a text (raises MdleSyntaxError if it does not parse)."""
    try:
        module = parse_module(text, file)
    except MdleError as err:
        raise refine_error(err, {file: text}) from None
    return format_module(module)


def format_expr(expr: st.Expr, names: Mapping[str, str] | None = None) -> str:
    """Return an expression on one line (interrupt sources in traces and ``mdle show`` use this).

    ``names`` replaces names by texts (the checker shows a parameter's value this way).
    """
    parts: list[str] = []
    stack: list[st.Expr | str] = [expr]
    # Iterative, so formatting never meets the recursion limit.
    while stack:
        e = stack.pop()
        if isinstance(e, str):
            parts.append(e)
        elif isinstance(e, st.Number):
            parts.append(_number(e))
        elif isinstance(e, st.Name):
            parts.append(names.get(e.name, e.name) if names else e.name)
        elif isinstance(e, st.Never):
            parts.append("never")
        elif isinstance(e, st.Inf):
            parts.append("inf")
        elif isinstance(e, st.Unary):
            stack.append(e.operand)
            parts.append("not " if e.op == "not" else e.op)
        elif isinstance(e, st.Binary):
            stack.extend([e.right, f" {e.op} ", e.left])
        elif isinstance(e, st.Call):
            todo: list[st.Expr | str] = [f"{e.name}("]
            for i, a in enumerate(e.args):
                if i:
                    todo.append(", ")
                if a.name is not None:
                    todo.append(f"{a.name} = ")
                todo.append(a.value)
            todo.append(")")
            stack.extend(reversed(todo))
        elif isinstance(e, (st.Group, st.Vector)):
            opening, closing = ("[", "]") if isinstance(e, st.Vector) else ("(", ")")
            todo = [opening]
            for i, item in enumerate(e.items):
                if i:
                    todo.append(", ")
                todo.append(item)
            todo.append(closing + ("..." if isinstance(e, st.Group) and e.repeat else ""))
            stack.extend(reversed(todo))
        else:  # pragma: no cover - every node type is handled above
            raise TypeError(f"not an expression: {e!r}")
    return "".join(parts)


def _number(n: st.Number) -> str:
    return f"{n.text} {n.unit}" if n.unit else n.text


def _layout(expr: st.Expr, indent: str, room: int) -> list[str]:
    """Lay out ``expr`` after text already on the line (``room`` columns left there).

    Later lines start with ``indent``.
    """
    flat = format_expr(expr)
    if len(flat) <= room or not isinstance(expr, (st.Group, st.Vector, st.Call)):
        return [flat]
    inner = indent + _INDENT
    if isinstance(expr, st.Call):
        head, closing = f"{expr.name}(", ")"
        parts: Sequence[tuple[str, st.Expr]] = [
            (f"{a.name} = " if a.name is not None else "", a.value) for a in expr.args]
    else:
        head, closing = ("[", "]") if isinstance(expr, st.Vector) else ("(", ")")
        if isinstance(expr, st.Group) and expr.repeat:
            closing += "..."
        parts = [("", item) for item in expr.items]
    lines = [head]
    for prefix, value in parts:
        sub = _layout(value, inner, WIDTH - len(inner) - len(prefix) - 1)
        sub[0] = inner + prefix + sub[0]
        sub[-1] += ","
        lines.extend(sub)
    lines.append(indent + closing)
    return lines


def format_statement(s: st.Statement) -> str:
    """One statement in canonical form (possibly several lines, no trailing newline)."""
    if isinstance(s, st.Import):
        return f'import "{s.path}"'
    if isinstance(s, st.Run):
        return f"run {s.name}"
    head = f"{s.kind.value} {s.name}"
    if s.params is not None:
        head += "(" + ", ".join(
            p.name if p.default is None else f"{p.name} = {format_expr(p.default)}"
            for p in s.params) + ")"
    head += " = "
    lines = _layout(s.body, "", WIDTH - len(head))
    lines[0] = head + lines[0]
    return "\n".join(lines)


def format_module(module: st.Module) -> str:
    """Return a whole file in canonical form, comments kept.

    The text ends with one newline (and is empty for an empty file).
    """
    comments = sorted(module.comments, key=lambda c: (c.span.line, c.span.column))
    out: list[str] = []
    last_line = 0  # the last source line already accounted for
    ci = 0

    def blank_if_gap(line: int) -> None:
        if out and last_line and line > last_line + 1 and out[-1] != "":
            out.append("")

    for s in module.statements:
        start, end = s.span.line, s.span.end_line
        # Comments on their own lines before the statement.
        while ci < len(comments) and comments[ci].span.line < start:
            c = comments[ci]
            blank_if_gap(c.span.line)
            out.append(c.text.rstrip())
            last_line = c.span.line
            ci += 1
        blank_if_gap(start)
        inside: list[str] = []
        trailing: list[str] = []
        while ci < len(comments) and comments[ci].span.line <= end:
            c = comments[ci]
            (trailing if c.span.line == end and c.span.column > s.span.end_column
             else inside).append(c.text.rstrip())
            ci += 1
        out.extend(inside)
        text = format_statement(s)
        if trailing:
            text += "  " + " ".join(trailing)
        out.append(text)
        last_line = end
    while ci < len(comments):
        c = comments[ci]
        blank_if_gap(c.span.line)
        out.append(c.text.rstrip())
        last_line = c.span.line
        ci += 1
    return "\n".join(out) + "\n" if out else ""
