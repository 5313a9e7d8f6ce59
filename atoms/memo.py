"""Memoise pure functions of a sensor's fixed arrays, found again by the array's identity.

A sensor sends the same bearings with every scan, as one read-only array (the simulator's
ladar and the drivers keep one per scan size). What the estimators derive from them (unit
directions, which beams a ray reads) is memoised; finding it again by the bearings' bytes
(copy and hash 181 floats) costs more per tick than several of the numpy calls it saves.
:class:`ByIdentity` finds it by the array object instead, and falls back to the function
(itself memoised by content) for any array whose contents could change under it.

The identity alone is not enough: numpy lets the owner of an array make it writable
again, write, and make it read-only once more, so the flag says nothing about what happened
in between. Each entry keeps the bytes, shape and type the value was computed from, and a
hit is taken only when the array still holds exactly those (a comparison of 1.4 kB, no
hash: about half a microsecond).

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
>>> b.setflags(write=True); b[0] = 5.0; b.setflags(write=False)
>>> memo(b, 2), len(calls)                      # changed behind the flag: computed again
(16.0, 4)
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import Any, Generic, TypeVar

__all__ = ["ByIdentity"]

T = TypeVar("T")


class _Entry(Generic[T]):
    """A remembered value, with the array it came from and what that array held then.

    ``array`` is kept so that its ``id`` is not reused while remembered. (A slotted class,
    not a dataclass: ``mdle check`` loads this module, and a dataclass is made by ``exec``.)
    """

    __slots__ = ("array", "data", "shape", "dtype", "value")

    def __init__(self, array: Any, value: T) -> None:
        self.array = array
        self.data: bytes = array.tobytes()
        self.shape: tuple[int, ...] = array.shape
        self.dtype: Any = array.dtype
        self.value = value

    def holds(self, a: Any) -> bool:
        """Whether ``a`` is the remembered array and still holds what it held."""
        return (a is self.array and not a.flags.writeable and a.shape == self.shape
                and a.dtype == self.dtype and a.tobytes() == self.data)


class ByIdentity(Generic[T]):
    """Memo of ``fn(array, *extra)`` for arrays that cannot change, looked up by identity.

    Only a read-only numpy array that owns its data is remembered (a writable one, or a view
    whose base may be written, is passed to ``fn`` every time), with a reference to it so
    that its ``id`` is never reused while remembered, and with a copy of its bytes, shape and
    type; it is found again only while it is still read-only and still holds those. At most
    ``size`` entries: the memo starts afresh when full.
    """

    def __init__(self, fn: Callable[..., T], size: int = 16) -> None:
        self._fn = fn
        self._size = size
        self._seen: dict[tuple[Hashable, ...], _Entry[T]] = {}

    def __call__(self, a: Any, *extra: Hashable) -> T:
        """Return ``fn(a, *extra)``, remembered when ``a`` is a fixed array."""
        key = (id(a), *extra)
        hit = self._seen.get(key)
        if hit is not None and hit.holds(a):
            return hit.value
        value = self._fn(a, *extra)
        flags = getattr(a, "flags", None)
        if flags is not None and not flags.writeable and getattr(a, "base", 0) is None:
            if len(self._seen) >= self._size:
                self._seen.clear()
            self._seen[key] = _Entry(a, value)
        return value
