"""Fast constructors for frozen dataclasses made in hot loops.

A frozen dataclass's ``__init__`` sets each field through ``object.__setattr__``, which is
most of the cost of a small object; the parsers make one or two syntax nodes per token,
the checker several typed parts per interrupt, a backend an observation and a scan every
tick. :func:`builder` makes a constructor that writes the fields straight into the new
instance's ``__dict__``: the result is an ordinary instance, equal to the one ``__init__``
makes.

>>> from dataclasses import dataclass
>>> @dataclass(frozen=True)
... class P:
...     x: float
...     y: float = 0.0
>>> new_p = builder(P)
>>> new_p(1.0, 2.0) == P(1.0, 2.0), new_p(y=2.0, x=1.0) == P(1.0, 2.0)
(True, True)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, TypeVar

__all__ = ["builder"]

_T = TypeVar("_T")


def builder(cls: type[_T]) -> Callable[..., _T]:
    """Return a constructor of the frozen dataclass ``cls`` taking every field.

    The fields are its parameters, in order and by name, all required (defaults are not
    applied). It suits plain data classes only (no ``__post_init__``, no slots).
    """
    names = [f.name for f in dataclasses.fields(cls)]  # type: ignore[arg-type]
    assert not hasattr(cls, "__post_init__") and not hasattr(cls, "__slots__")
    body = "".join(f"    d[{n!r}] = {n}\n" for n in names)
    code = (f"def build({', '.join(names)}):\n    o = new(cls)\n    d = o.__dict__\n{body}"
            "    return o\n")
    namespace: dict[str, Any] = {"new": object.__new__, "cls": cls}
    exec(code, namespace)
    build: Callable[..., _T] = namespace["build"]
    return build
