"""A world file's obstacles: one YAML entry to one validated shape of :mod:`sim.shapes`."""

from __future__ import annotations

import math
from typing import Any

from mdle.sim.yaml_doc import _Doc
from mdle.sim.yaml_values import (
    _boolean,
    _closest,
    _mapping,
    _number,
    _point,
    _points,
    _show,
    _string,
)

__all__ = ["OBSTACLE_TYPES"]

#: Keys each obstacle type requires and allows (besides ``type`` and ``name``).
OBSTACLE_TYPES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "polygon": (("points",), ("holes",)),
    "rectangle": (("center", "size"), ("angle",)),
    "circle": (("center", "radius"), ()),
    "ellipse": (("center", "axes"), ("angle",)),
    "wall": (("points",), ("thickness", "closed")),
    "arc": (("center", "radius", "start", "end"), ("thickness",)),
    "curve": (("points",), ("thickness", "closed", "spacing")),
}
_DEFAULT_WALL_THICKNESS = 0.1
_MAX_CURVE_SAMPLES = 100_000


def _obstacle(doc: _Doc, path: str, v: Any) -> Any:
    from mdle.sim import shapes

    if not isinstance(v, dict):
        raise doc.fail(path, f"expected a mapping with a `type`, got {_show(v)}")
    kind = v.get("type")
    if kind is None:
        raise doc.fail(path, f"missing key `type` (one of: {', '.join(OBSTACLE_TYPES)})")
    if not isinstance(kind, str) or kind not in OBSTACLE_TYPES:
        hint = _closest(str(kind), tuple(OBSTACLE_TYPES))
        raise doc.fail(f"{path}.type", f"unknown obstacle type {kind!r}"
                       + (f" (did you mean `{hint}`?)" if hint else "")
                       + f"; one of: {', '.join(OBSTACLE_TYPES)}")
    required, optional = OBSTACLE_TYPES[kind]
    _mapping(doc, path, v, ("type", "name", *required, *optional), f"a {kind}")
    for key in required:
        if key not in v:
            raise doc.fail(path, f"missing key `{key}` (a {kind} needs {', '.join(required)})")
    name = _string(doc, f"{path}.name", v["name"]) if "name" in v else ""

    def P(key: str) -> str:
        return f"{path}.{key}"


    if kind == "polygon":
        pts = _points(doc, P("points"), v["points"], 3, "a polygon")
        raw_holes = v.get("holes", [])
        if not isinstance(raw_holes, list):
            raise doc.fail(P("holes"), f"expected a list of rings of [x, y] points, got "
                           f"{_show(raw_holes)}")
        holes = tuple(_points(doc, f"{P('holes')}[{i}]", h, 3, "a hole")
                      for i, h in enumerate(raw_holes))
        shape: Any = shapes.Polygon(pts, name, holes)
        g = shape.geometry()
        if not g.is_valid or g.area <= 0:
            raise doc.fail(P("holes" if holes else "points"),
                           "the polygon crosses itself, or its holes cross it or each other, "
                           "or it has no area" if holes else
                           "the polygon crosses itself or has no area")
        return shape
    if kind in ("rectangle", "ellipse"):   # a centre, two sizes and a turn
        c = _point(doc, P("center"), v["center"])
        key, pair = ("size", "[width, height]") if kind == "rectangle" else ("axes",
                                                                            "semi-axes [a, b]")
        sizes = _sizes(doc, P(key), v[key], pair)
        ang = math.radians(_number(doc, P("angle"), v.get("angle", 0.0), unit="deg"))
        return (shapes.Rectangle if kind == "rectangle" else shapes.Ellipse)(c, sizes, ang, name)
    if kind == "circle":
        return shapes.Circle(_point(doc, P("center"), v["center"]),
                             _number(doc, P("radius"), v["radius"], size=True), name)
    if kind == "wall":
        closed = _boolean(doc, P("closed"), v.get("closed", False))
        pts = _points(doc, P("points"), v["points"], 3 if closed else 2,
                      "a closed wall" if closed else "a wall")
        t = _number(doc, P("thickness"), v.get("thickness", _DEFAULT_WALL_THICKNESS),
                    size=True)
        shape = shapes.Wall(pts, t, closed, name)
        if shape.geometry().is_empty:
            raise doc.fail(P("points"), "the wall has no area")
        return shape
    if kind == "arc":
        c = _point(doc, P("center"), v["center"])
        r = _number(doc, P("radius"), v["radius"], size=True)
        a0 = math.radians(_number(doc, P("start"), v["start"], unit="deg"))
        a1 = math.radians(_number(doc, P("end"), v["end"], unit="deg"))
        t = _number(doc, P("thickness"), v.get("thickness", _DEFAULT_WALL_THICKNESS),
                    size=True)
        if t >= 2 * r:
            raise doc.fail(P("thickness"), f"must be less than twice the radius ({2 * r} m)")
        if abs(a1 - a0) < 1e-12:
            raise doc.fail(P("end"), "must differ from `start` (the arc runs counter-clockwise "
                           "from start to end)")
        return shapes.Arc(c, r, a0, a1, t, name)
    # curve
    closed = _boolean(doc, P("closed"), v.get("closed", False))
    pts = _points(doc, P("points"), v["points"], 3 if closed else 2,
                  "a closed curve" if closed else "a curve")
    thick: float | None
    if "thickness" in v:
        thick = _number(doc, P("thickness"), v["thickness"], size=True)
    elif closed:
        thick = None
    else:
        raise doc.fail(path, "missing key `thickness` (an open curve is a wall and needs one)")
    spacing = _number(doc, P("spacing"), v.get("spacing", 0.05), size=True)
    # An open curve has one chord fewer than points: the shorter side ends the pairs.
    ends = pts[1:] + (pts[:1] if closed else ())
    length = sum(math.dist(a, b) for a, b in zip(pts, ends, strict=False))
    if 2 * length / spacing > _MAX_CURVE_SAMPLES:   # Catmull-Rom runs up to ~2x the chords
        least = 2 * length / _MAX_CURVE_SAMPLES
        raise doc.fail(P("spacing"), f"too fine for a curve {length:.3g} m long (at most "
                       f"{_MAX_CURVE_SAMPLES} samples); use at least {least:.3g} m")
    shape = shapes.Curve(pts, thick, closed, spacing, name)
    g = shape.geometry()
    if not g.is_valid or g.area <= 0:
        raise doc.fail(P("points"), "the curve crosses itself (or its thickness folds it)")
    return shape


def _sizes(doc: _Doc, path: str, v: Any, pair: str) -> tuple[float, float]:
    """Read two sizes in metres (a rectangle's ``[width, height]``, an ellipse's semi-axes)."""
    if not isinstance(v, list) or len(v) != 2:
        raise doc.fail(path, f"expected {pair} in metres, got {_show(v)}")
    return (_number(doc, path + "[0]", v[0], size=True),
            _number(doc, path + "[1]", v[1], size=True))
