"""Result tables on standard output: rich boxes on a terminal, plain wide text elsewhere.

Every column names its unit, and the notes under a table explain what its columns measure,
so a table read on its own (in a log, pasted in an issue) says what it means.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import IO

__all__ = ["print_table", "yes_no", "metres"]


def yes_no(flag: bool) -> str:
    """Return ``YES`` (a collision stands out) or ``no``."""
    return "YES" if flag else "no"


def metres(x: float | None, digits: int = 3) -> str:
    """Format a distance in metres without its unit (the column names it); ``-`` when unknown."""
    return "-" if x is None or math.isnan(x) else f"{x:.{digits}f}"


def print_table(stream: IO[str], title: str, columns: Sequence[tuple[str, str]],
                rows: Sequence[Sequence[str]], notes: Sequence[str] = ()) -> None:
    """Print a table: ``columns`` are (header with unit, ``left``/``right``) pairs."""
    from rich.console import Console
    from rich.table import Table

    tty = stream.isatty()
    # off a terminal: wide enough that no header or note wraps (logs, pipes, notes)
    console = Console(file=stream, highlight=False, width=None if tty else 200,
                      force_terminal=tty, no_color=not tty, soft_wrap=not tty)
    table = Table(title=title, title_justify="left")
    for name, justify in columns:
        table.add_column(name, justify=justify)  # type: ignore[arg-type]
    for row in rows:
        table.add_row(*row)
    console.print(table)
    for note in notes:
        console.print(note)
