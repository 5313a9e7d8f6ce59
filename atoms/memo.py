"""Memoise pure functions of a sensor's fixed arrays, found again by the array's identity.

A sensor sends the same bearings with every scan, as one read-only array (the simulator's
ladar and the drivers keep one per scan size). What the estimators derive from them (unit
directions, which beams a ray reads) is memoised; finding it again by the bearings' bytes
(copy and hash 181 floats) costs more per tick than several of the numpy calls it saves.
:class:`ByIdentity` finds it by the array object instead, and falls back to the function
(itself memoised by content) for any array whose contents could change under it.

No numpy here: :mod:`atoms.boundary` loads this module for the checker.

>>> import numpy as np
>>> calls = []
>>> memo = ByIdentity(lambda a, k: calls.append(k) or float(a.sum()) * k)
>>> b = np.arange(3.0)
>>> b.setflags(write=False)
>>> memo(b, 2), memo(b, 2), len(calls)          # read-only and owning its data: found again
(6.0, 6.0, 1)
>>> w = np.arange(3.0)
>>> memo(w, 2), memo(w, 2), len(calls)          # writable: computed each time
(6.0, 6.0, 3)
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import Any, Generic, TypeVar

__all__ = ["ByIdentity"]

T = TypeVar("T")


class ByIdentity(Generic[T]):
    """Memo of ``fn(array, *extra)`` for arrays that cannot change, looked up by identity.

    Only a read-only numpy array that owns its data is remembered (a writable one, or a view
    whose base may be written, is passed to ``fn`` every time), with a reference to it so
    that its ``id`` is never reused while remembered; and it is found again only while it is
    still read-only. At most ``size`` entries: the memo starts afresh when full.
    """

    def __init__(self, fn: Callable[..., T], size: int = 16) -> None:
        self._fn = fn
        self._size = size
        self._seen: dict[tuple[Hashable, ...], tuple[Any, T]] = {}

    def __call__(self, a: Any, *extra: Hashable) -> T:
        """Return ``fn(a, *extra)``, remembered when ``a`` is a fixed array."""
        key = (id(a), *extra)
        hit = self._seen.get(key)
        if hit is not None and hit[0] is a and not a.flags.writeable:
            return hit[1]
        value = self._fn(a, *extra)
        flags = getattr(a, "flags", None)
        if flags is not None and not flags.writeable and getattr(a, "base", 0) is None:
            if len(self._seen) >= self._size:
                self._seen.clear()
            self._seen[key] = (a, value)
        return value
