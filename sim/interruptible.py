"""Long calls into C that Ctrl-C must still cut (shapely's unions of a large map).

Python acts on a signal only between two bytecodes of its main thread: a call into
GEOS that takes seconds holds Ctrl-C for seconds. shapely lets go of the interpreter
(the GIL) while GEOS works, so such a call can run in a worker thread while the main
thread waits for it in short slices, acting on a signal between them: the
KeyboardInterrupt is raised at once, and the abandoned worker (a daemon thread) ends
with the process.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Generic, TypeVar

__all__ = ["call_interruptibly"]

T = TypeVar("T")

#: How long the main thread waits between two looks at the signals, seconds.
_SLICE = 0.02


@dataclass
class _Outcome(Generic[T]):
    """What the worker thread's call returned or raised."""

    value: list[T] = field(default_factory=list)
    error: list[BaseException] = field(default_factory=list)


def call_interruptibly(fn: Callable[[], T]) -> T:
    """Return ``fn()``, run so that a signal to the main thread is acted on meanwhile.

    ``fn`` should spend its time in C code that releases the GIL (shapely's set
    operations do); pure Python gains nothing. Off the main thread (a sweep's worker
    thread, say) ``fn`` is simply called. An exception of ``fn`` is raised here.
    """
    if threading.current_thread() is not threading.main_thread():
        return fn()
    out: _Outcome[T] = _Outcome()

    def work() -> None:
        try:
            out.value.append(fn())
        except BaseException as exc:  # noqa: BLE001 - handed to the caller below
            out.error.append(exc)

    worker = threading.Thread(target=work, name="mdle-long-call", daemon=True)
    worker.start()
    while worker.is_alive():
        worker.join(_SLICE)
    if out.error:
        raise out.error[0]
    return out.value[0]
