"""A progress bar on standard error for work in steps (a rich bar on a terminal only).

Off a terminal nothing is drawn: logs keep only the results.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from typing import Any

__all__ = ["bar", "steps"]


def bar(console: Any, label: str, *middle: Any) -> Any:
    """Return mdle's rich progress bar (not started) on ``console``.

    ``label``, the bar, done/total, the ``middle`` columns (e.g. a failure count), the time
    elapsed and the ETA; the final bar stays on screen.
    """
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    return Progress(TextColumn(label), BarColumn(), MofNCompleteColumn(), *middle,
                    TimeElapsedColumn(), TextColumn("ETA"), TimeRemainingColumn(),
                    console=console, transient=False)


@contextlib.contextmanager
def steps(label: str, total: int) -> Iterator[Callable[[], None]]:
    """Yield a function that counts one step of ``total``; the bar shows while inside."""
    from rich.console import Console

    console = Console(stderr=True)
    if not console.is_terminal:
        yield lambda: None
        return
    with bar(console, label) as progress:
        task = progress.add_task(label, total=total)
        yield lambda: progress.advance(task)
