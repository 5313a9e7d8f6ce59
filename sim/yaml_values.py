"""Plain values read from a YAML document: numbers, whole numbers, text, points, mappings.

Each check takes the :class:`~mdle.sim.yaml_doc._Doc` and the key path, and raises the
document's :class:`mdle.core.errors.WorldError` for that path when the value is not what
was expected (saying, for a number written with a unit, that units are implied).
"""

from __future__ import annotations

import math
import re
from typing import Any

from mdle.sim.yaml_doc import _Doc

__all__ = ["MAX_COORDINATE"]

_FLOAT = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")
_MIN_SIZE, _MAX_SIZE = 1e-4, 1e5   # metres: sizes outside this are typos, not worlds
#: Coordinates (m) farther than this from the origin are typos, not worlds.
MAX_COORDINATE = 1e6


def _number(doc: _Doc, path: str, v: Any, *, positive: bool = False, nonneg: bool = False,
            size: bool = False, coordinate: bool = False, shown: str | None = None,
            unit: str | None = None) -> float:
    """Read a plain number.

    ``unit`` is the unit it is in (sizes and coordinates: metres), named when a unit was
    written (``1.6 m``: units are implied, never written).
    """
    if isinstance(v, str) and _FLOAT.fullmatch(v.strip()):
        # YAML 1.1 reads 1e-3 (no dot) as text; take it as the number meant.
        return _number(doc, path, float(v), positive=positive, nonneg=nonneg, size=size,
                       coordinate=coordinate, shown=v.strip(), unit=unit)
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        implied = unit or ("m" if size or coordinate else None)
        raise doc.fail(path, f"expected a number, got {_show(v)}" + _written_unit(v, implied))
    try:
        x = float(v)
    except OverflowError:  # an integer of hundreds of digits
        x, shown = (math.inf if v > 0 else -math.inf), _short_int(int(v))
    if not math.isfinite(x):
        raise doc.fail(path, f"expected a finite number, got {shown or v}")
    if (positive or size) and x <= 0:
        raise doc.fail(path, f"must be positive, got {shown or v}")
    if size and not _MIN_SIZE <= x <= _MAX_SIZE:
        raise doc.fail(path, f"must be between {_MIN_SIZE:g} m and {_MAX_SIZE:g} m, got "
                             f"{shown or v}")
    if nonneg and x < 0:
        raise doc.fail(path, f"must not be negative, got {shown or v}")
    if coordinate and abs(x) > MAX_COORDINATE:
        raise doc.fail(path, f"must be within \u00b1{MAX_COORDINATE:g} m of the origin, got "
                             f"{shown or v}")
    return x


_WITH_UNIT = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*"
                        r"([A-Za-z][A-Za-z/^0-9]*)\s*")
_UNIT_WORDS = {"m": "metres", "deg": "degrees", "s": "seconds", "Hz": "hertz",
               "m/s": "metres per second", "deg/s": "degrees per second",
               "m/s^2": "metres per second squared", "deg/s^2": "degrees per second squared"}


def _written_unit(v: Any, implied: str | None) -> str:
    """Say, for a number written with a unit (``1.6 m``), that units are implied.

    And what to write instead (converted when the unit written is another of the same kind).
    """
    m = _WITH_UNIT.fullmatch(v) if isinstance(v, str) else None
    if m is None:
        return ""
    number, written = m.group(1), m.group(2)
    value = number.lstrip("+")
    if implied is not None and written != implied:
        from mdle.core.units import unit_value

        try:
            (f_written, d_written), (f_implied, d_implied) = (unit_value(written),
                                                              unit_value(implied))
        except KeyError:
            d_written, d_implied = None, None
        if d_written is None or d_written != d_implied:
            value = ""
        else:
            value = f"{float(number) * f_written / f_implied:.6g}"
    if implied is None:
        return f": a world file writes plain numbers (units are implied); write `{value}`"
    words = _UNIT_WORDS.get(implied, implied)
    if not value:
        return f": this takes a number of {words}, with no unit written"
    return f": {words} are implied, not written; write `{value}`"


def _integer(doc: _Doc, path: str, v: Any, *, minimum: int = 0,
             maximum: int | None = None) -> int:
    if isinstance(v, bool) or not isinstance(v, int):
        raise doc.fail(path, f"expected a whole number, got {_show(v)}")
    if v < minimum:
        raise doc.fail(path, f"must be at least {minimum}, got {_short_int(v)}")
    if maximum is not None and v > maximum:
        raise doc.fail(path, f"must be at most {maximum}, got {_short_int(v)}")
    return int(v)


def _short_int(v: int) -> str:
    digits = len(str(abs(v))) if abs(v) < 10 ** 4000 else 4000
    return str(v) if digits <= 30 else f"a number of {digits} digits"


def _boolean(doc: _Doc, path: str, v: Any) -> bool:
    if not isinstance(v, bool):
        raise doc.fail(path, f"expected true or false, got {_show(v)}")
    return v


def _string(doc: _Doc, path: str, v: Any) -> str:
    if not isinstance(v, str):
        raise doc.fail(path, f"expected text, got {_show(v)}")
    return v


def _point(doc: _Doc, path: str, v: Any) -> tuple[float, float]:
    if not isinstance(v, list) or len(v) != 2:
        raise doc.fail(path, f"expected a point [x, y] in metres, got {_show(v)}")
    return (_number(doc, f"{path}[0]", v[0], coordinate=True),
            _number(doc, f"{path}[1]", v[1], coordinate=True))


def _points(doc: _Doc, path: str, v: Any, minimum: int, what: str
            ) -> tuple[tuple[float, float], ...]:
    if not isinstance(v, list):
        raise doc.fail(path, f"expected a list of [x, y] points, got {_show(v)}")
    if len(v) < minimum:
        raise doc.fail(path, f"{what} needs at least {minimum} points, got {len(v)}")
    pts = tuple(_point(doc, f"{path}[{i}]", p) for i, p in enumerate(v))
    for i in range(1, len(pts)):
        if pts[i] == pts[i - 1]:
            raise doc.fail(f"{path}[{i}]", f"repeats the previous point {list(pts[i])}")
    return pts


def _show(v: Any) -> str:
    if isinstance(v, dict):
        return "a mapping"
    if isinstance(v, list):
        return f"a list of {len(v)}"
    if v is None:
        return "nothing"
    return repr(v)


def _mapping(doc: _Doc, path: str, v: Any, allowed: tuple[str, ...], what: str) -> dict[str, Any]:
    if not isinstance(v, dict):
        raise doc.fail(path, f"expected a mapping ({what}), got {_show(v)}")
    for k in v:
        if k not in allowed:
            sub = f"{path}.{k}" if path else k
            doc.marks[sub] = doc.marks.get(sub + "#key", doc.marks.get(sub, (1, 1, 1)))
            hint = _closest(k, allowed)
            raise doc.fail(sub, f"unknown key `{k}`" + (f" (did you mean `{hint}`?)" if hint
                                                       else f"; allowed: {', '.join(allowed)}"))
    return v


def _closest(word: str, options: tuple[str, ...]) -> str | None:
    import difflib

    m = difflib.get_close_matches(word, options, n=1, cutoff=0.6)
    return m[0] if m else None
