"""The budget on how far a program's parameterised definitions expand.

The checker makes each definition once per distinct set of argument values and shares
that instance wherever the same values are passed (the cache in
:mod:`mdle.lang.check_state`), so a chain such as
``interrupt iK(a) = iK-1(a) or iK-1(a + 1 deg)`` costs work linear in its lines. Values
that stay distinct at every level (``iK-1(a * 2) or iK-1(a + 1 deg)``) cannot be shared:
30 such lines describe about 10 million instances. :class:`ExpansionBudget` counts the
syntax nodes of every instance beyond each definition's first (which the file itself
pays for) and refuses the program, at the call that would cross the limit and before
that instance is checked, once the count passes :data:`MAX_EXPANSION`.
"""

from __future__ import annotations

from mdle.lang import syntax as st

__all__ = ["MAX_EXPANSION", "ExpansionBudget", "syntax_size"]

#: Syntax nodes that instances of definitions with new argument values may add to a
#: program (docs/limits.md). A plan passing a hundred different values to each of ten
#: ten-node definitions uses half of it.
MAX_EXPANSION = 20_000


def syntax_size(expr: st.Expr) -> int:
    """Return the number of syntax nodes in ``expr`` (iteratively: any depth)."""
    count, stack = 0, [expr]
    while stack:
        node = stack.pop()
        count += 1
        stack.extend(st.children(node))
    return count


class ExpansionBudget:
    """What instances of definitions have added to a program, against the limit."""

    def __init__(self, limit: int = MAX_EXPANSION) -> None:
        self.limit = limit
        self.used = 0
        #: set once the limit is passed: later instances are refused without a message
        self.exceeded = False
        #: set once the refusal has been reported
        self.reported = False
        self._sizes: dict[str, int] = {}  # by definition name; absent: not yet made

    def charge(self, d: st.Definition) -> bool:
        """Account for one more instance of ``d``; False when it would pass the limit."""
        if self.exceeded:
            return False
        size = self._sizes.get(d.name)
        if size is None:  # the first instance: the file's own text pays for it
            self._sizes[d.name] = syntax_size(d.body)
            return True
        if self.used + size > self.limit:
            self.exceeded = True
            return False
        self.used += size
        return True

    def message(self, d: st.Definition) -> str:
        """Return the words of the error at the call that passed the limit."""
        return (f"this use of `{d.name}` expands the program past mdle's limit: instances "
                f"of definitions with new argument values would add more than {self.limit:,} "
                f"syntax nodes")
