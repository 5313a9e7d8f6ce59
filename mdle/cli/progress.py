"""A progress bar on standard error for work in steps (a rich bar on a terminal only).

Off a terminal nothing is drawn: logs keep only the results.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator

__all__ = ["steps"]


@contextlib.contextmanager
def steps(label: str, total: int) -> Iterator[Callable[[], None]]:
    """Yield a function that counts one step of ``total``; the bar shows while inside."""
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    console = Console(stderr=True)
    if not console.is_terminal:
        yield lambda: None
        return
    with Progress(TextColumn(label), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  TextColumn("ETA"), TimeRemainingColumn(), console=console,
                  transient=False) as bar:
        task = bar.add_task(label, total=total)
        yield lambda: bar.advance(task)
