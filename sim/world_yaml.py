r"""World files: YAML (metres and degrees) to a validated :class:`sim.world.World`.

Loading validates everything and reports the first problem as a
:class:`mdle.errors.WorldError` naming the file, the line and column, and the key path
(``obstacles[3].points``) with what was wrong. Only ``yaml`` safe loading is used.
The format is documented in ``docs/worlds.md``.

>>> w = parse_world('''
... name: demo
... start: {x: 0, y: 0, theta: 90}
... obstacles:
...   - {type: circle, center: [3, 0], radius: 1}
... ''')
>>> w.name, round(w.start_pose.theta, 6), type(w.obstacles[0]).__name__
('demo', 1.570796, 'Circle')
>>> try:
...     parse_world("obstacles:\n  - {type: circle, center: [3, 0]}\n", file="bad.yaml")
... except WorldError as err:
...     print(err)
bad.yaml:2:5: error: obstacles[0]: missing key `radius` (a circle needs center, radius)
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mdle.backend import Pose
from mdle.errors import Diagnostic, Span, WorldError

__all__ = ["OBSTACLE_TYPES", "MAX_COORDINATE", "MAX_LADAR_RATE", "MAX_SEED", "MAX_YAML_DEPTH",
           "parse_world", "parse_world_robot", "read_world", "read_world_robot"]

#: Keys each obstacle type requires and allows (besides ``type`` and ``name``).
OBSTACLE_TYPES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "polygon": (("points",), ()),
    "rectangle": (("center", "size"), ("angle",)),
    "circle": (("center", "radius"), ()),
    "ellipse": (("center", "axes"), ("angle",)),
    "wall": (("points",), ("thickness", "closed")),
    "arc": (("center", "radius", "start", "end"), ("thickness",)),
    "curve": (("points",), ("thickness", "closed", "spacing")),
}
_TOP_KEYS = ("name", "description", "seed", "start", "robot", "ladar", "extent", "obstacles",
             "robots")
_TEAM_ROBOT_KEYS = ("name", "robot", "ladar", "start")
_ROBOT_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_LADAR_KEYS = ("profile", "beams", "fov", "max_range", "noise", "sigma", "resolution", "rate")
_DEFAULT_WALL_THICKNESS = 0.1
_FLOAT = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")
_MAX_CURVE_SAMPLES = 100_000
_MIN_SIZE, _MAX_SIZE = 1e-4, 1e5   # metres: sizes outside this are typos, not worlds
_MAX_BEAMS = 100_000
#: Coordinates (m) farther than this from the origin are typos, not worlds.
MAX_COORDINATE = 1e6
#: Fastest ladar scan rate accepted, Hz (the LMS-200 scans at up to 75 Hz).
MAX_LADAR_RATE = 1000.0
#: Deepest nesting of lists and mappings in a world file (a world needs about 5).
MAX_YAML_DEPTH = 64
#: Largest seed (the simulator's generator takes 64-bit seeds).
MAX_SEED = 2 ** 64 - 1


@dataclass
class _Doc:
    """The YAML text, its file name, and where each key path starts."""

    file: str
    text: str
    marks: dict[str, tuple[int, int, int]] = field(default_factory=dict)

    def fail(self, path: str, problem: str) -> WorldError:
        where = self.marks.get(path)
        probe = path
        while where is None and probe:   # fall back to the nearest enclosing key
            probe = probe.rpartition(".")[0] if "." in probe else (
                probe.rpartition("[")[0] if "[" in probe else "")
            where = self.marks.get(probe)
        span = None
        if where is not None:
            line, col, width = where
            span = Span(self.file, line, col, line, col + max(1, width))
        elif self.file:
            span = Span(self.file, 1, 1, 1, 1)
        msg = f"{path}: {problem}" if path and not path.startswith("<") else problem
        return WorldError(Diagnostic(span, msg), sources={self.file: self.text})


_YAML_INT = re.compile(r"[-+]?(?:0|[1-9][0-9]*)")
_YAML_FLOAT = re.compile(r"[-+]?(?:[0-9]+\.[0-9]*|\.[0-9]+)(?:[eE][-+][0-9]+)?")


def _events(text: str, fast: bool = True) -> Any:
    """Return the YAML event stream (libyaml's C parser when installed and ``fast``)."""
    import yaml

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader) if fast else yaml.SafeLoader
    return yaml.parse(text, Loader=loader)


class _Builder:
    """YAML events to Python values, with each key path's position recorded.

    Built from the event stream with an explicit stack (no recursion), so nesting is
    refused at the first level past :data:`MAX_YAML_DEPTH` instead of exhausting a
    stack. An alias is the very object its anchor made, never a copy, so aliases of
    aliases ("billion laughs") cost nothing; an alias of an anchor still open (a value
    containing itself) is refused. Plain numbers take a fast path; every other scalar is
    resolved and constructed by PyYAML's safe loader, as ``yaml.safe_load`` would.
    """

    def __init__(self, doc: _Doc) -> None:
        import yaml

        self.doc = doc
        self.resolver = yaml.SafeLoader("")
        self.anchors: dict[str, Any] = {}
        self.open: set[str] = set()

    def fail_at(self, mark: Any, problem: str) -> WorldError:
        self.doc.marks["<yaml>"] = (mark.line + 1, mark.column + 1, 1)
        return self.doc.fail("<yaml>", problem)

    def scalar(self, ev: Any, path: str) -> Any:
        import yaml

        value = ev.value
        if ev.implicit[0] and ev.tag is None:
            if _YAML_INT.fullmatch(value):
                try:
                    return int(value)
                except ValueError as err:  # more digits than Python converts
                    raise self.doc.fail(path, f"cannot read the value: {err}") from None
            if _YAML_FLOAT.fullmatch(value):
                return float(value)
        tag = ev.tag
        if tag is None or tag == "!":
            tag = self.resolver.resolve(yaml.ScalarNode, value, ev.implicit)
        node = yaml.ScalarNode(tag, value, ev.start_mark, ev.end_mark, ev.style)
        try:
            return self.resolver.construct_object(node, deep=True)
        except (ValueError, OverflowError) as err:  # e.g. an integer of 5,000 digits
            raise self.doc.fail(path, f"cannot read the value: {err}") from None

    def build(self, events: Any) -> Any:
        """Return the document's value (None for an empty document)."""
        import yaml

        doc = self.doc
        marks = doc.marks
        # each open container: [value, path, start mark, anchor, pending key, key mark]
        stack: list[list[Any]] = []
        result: Any = None
        done = False
        scalar_event = yaml.ScalarEvent
        for ev in events:
            # the common case first: a number in a list (the points of a polygon)
            if type(ev) is scalar_event and stack and ev.anchor is None \
                    and type(stack[-1][0]) is list:
                seq, where = stack[-1][0], stack[-1][1]
                path = f"{where}[{len(seq)}]"
                m, e = ev.start_mark, ev.end_mark
                marks[path] = (m.line + 1, m.column + 1,
                               max(1, e.index - m.index) if e.line == m.line else 1)
                seq.append(self.scalar(ev, path))
                continue
            if isinstance(ev, (yaml.StreamStartEvent, yaml.StreamEndEvent,
                               yaml.DocumentEndEvent)):
                continue
            if isinstance(ev, yaml.DocumentStartEvent):
                if done:
                    raise self.fail_at(ev.start_mark, "a world file holds one YAML document, "
                                                      "found a second")
                continue
            if isinstance(ev, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
                value, path, start, anchor, _, _ = stack.pop()
                end = ev.end_mark
                width = end.index - start.index if end.line == start.line else 1
                marks[path] = (start.line + 1, start.column + 1, max(1, width))
                if anchor is not None:
                    self.open.discard(anchor)
                    self.anchors[anchor] = value
                self._place(stack, value, path)
                if not stack:
                    result, done = value, True
                continue
            # a node: where does it go?
            top = stack[-1] if stack else None
            if top is None:
                path = ""
            elif isinstance(top[0], list):
                path = f"{top[1]}[{len(top[0])}]" if top[1] else f"[{len(top[0])}]"
            elif top[4] is _NO_KEY:
                path = "<key>"
            else:
                path = f"{top[1]}.{top[4]}" if top[1] else str(top[4])
            if isinstance(ev, yaml.AliasEvent):
                if ev.anchor in self.open:
                    marks.setdefault(path, (ev.start_mark.line + 1, ev.start_mark.column + 1,
                                            1))
                    raise doc.fail(path, f"the alias `*{ev.anchor}` refers to itself (it "
                                         "stands inside its own anchor)")
                if ev.anchor not in self.anchors:
                    raise self.fail_at(ev.start_mark, f"not valid YAML: unknown alias "
                                                      f"`*{ev.anchor}`")
                value = self.anchors[ev.anchor]
            elif isinstance(ev, yaml.ScalarEvent):
                m, e = ev.start_mark, ev.end_mark
                marks[path] = (m.line + 1, m.column + 1,
                               max(1, e.index - m.index) if e.line == m.line else 1)
                value = self.scalar(ev, path)
                if ev.anchor is not None:
                    self.anchors[ev.anchor] = value
            else:  # a mapping or sequence starts
                if len(stack) >= MAX_YAML_DEPTH:
                    raise self.fail_at(ev.start_mark, f"the YAML nests more than "
                                                      f"{MAX_YAML_DEPTH} levels deep here; a "
                                                      "world needs a handful")
                marks[path] = (ev.start_mark.line + 1, ev.start_mark.column + 1, 1)
                if ev.anchor is not None:
                    self.open.add(ev.anchor)
                container: Any = [] if isinstance(ev, yaml.SequenceStartEvent) else {}
                stack.append([container, path, ev.start_mark, ev.anchor, _NO_KEY, None])
                continue
            if path == "<key>":
                assert top is not None
                self._key(top, value, (ev.start_mark.line + 1, ev.start_mark.column + 1))
                continue
            self._place(stack, value, path)
            if not stack:
                result, done = value, True
        return result

    def _key(self, top: list[Any], key: Any, km: tuple[int, int]) -> None:
        import reprlib

        doc = self.doc
        if not isinstance(key, str):
            doc.marks["<key>"] = (*km, 1)
            where = f"in `{top[1]}`: " if top[1] else ""
            short = reprlib.Repr()
            short.maxlevel, short.maxlist, short.maxdict, short.maxstring = 2, 4, 4, 40
            raise doc.fail("<key>", f"{where}keys must be names, got {short.repr(key)}")
        sub = f"{top[1]}.{key}" if top[1] else key
        if key in top[0]:
            doc.marks[sub] = (*km, len(key))
            raise doc.fail(sub, "key given twice")
        doc.marks.setdefault(sub + "#key", (*km, len(key)))
        top[4], top[5] = key, km

    def _place(self, stack: list[list[Any]], value: Any, path: str) -> None:
        if not stack:
            return
        top = stack[-1]
        if isinstance(top[0], list):
            top[0].append(value)
        elif top[4] is _NO_KEY:  # a mapping or sequence where a key belongs
            line, column, _ = self.doc.marks.get(path, (1, 1, 1))
            self._key(top, value, (line, column))
        else:
            top[0][top[4]] = value
            top[4] = _NO_KEY


_NO_KEY = object()


# ---------------------------------------------------------------- value checkers
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
        from mdle.units import unit_value

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


# ---------------------------------------------------------------- sections
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
        shape: Any = shapes.Polygon(pts, name)
        g = shape.geometry()
        if not g.is_valid or g.area <= 0:
            raise doc.fail(P("points"), "the polygon crosses itself or has no area")
        return shape
    if kind == "rectangle":
        c = _point(doc, P("center"), v["center"])
        size = v["size"]
        if not isinstance(size, list) or len(size) != 2:
            raise doc.fail(P("size"), f"expected [width, height] in metres, got {_show(size)}")
        w = _number(doc, P("size") + "[0]", size[0], size=True)
        h = _number(doc, P("size") + "[1]", size[1], size=True)
        ang = math.radians(_number(doc, P("angle"), v.get("angle", 0.0), unit="deg"))
        return shapes.Rectangle(c, (w, h), ang, name)
    if kind == "circle":
        return shapes.Circle(_point(doc, P("center"), v["center"]),
                             _number(doc, P("radius"), v["radius"], size=True), name)
    if kind == "ellipse":
        c = _point(doc, P("center"), v["center"])
        ax = v["axes"]
        if not isinstance(ax, list) or len(ax) != 2:
            raise doc.fail(P("axes"), f"expected semi-axes [a, b] in metres, got {_show(ax)}")
        a = _number(doc, P("axes") + "[0]", ax[0], size=True)
        b = _number(doc, P("axes") + "[1]", ax[1], size=True)
        ang = math.radians(_number(doc, P("angle"), v.get("angle", 0.0), unit="deg"))
        return shapes.Ellipse(c, (a, b), ang, name)
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


def _robot(doc: _Doc, path: str, v: Any) -> Any:
    from mdle.sim.profiles import DEFAULT_ROBOT, robot_profile
    from mdle.sim.robot_yaml import ROBOT_KEYS, check_mount, robot_overrides

    def lookup(name: str) -> Any:
        # A profile file named in a world file is found next to the world file.
        if doc.file and not doc.file.startswith("<") and not os.path.isabs(name):
            near = Path(doc.file).parent / name
            if name.endswith((".yaml", ".yml")) and near.exists():
                return robot_profile(str(near))
        return robot_profile(name)

    if isinstance(v, str):
        return _named(doc, path, v, lookup)
    m = _mapping(doc, path, v, ("profile", *ROBOT_KEYS),
                 "a profile name or file, or `profile` and overrides")
    base = _named(doc, f"{path}.profile", m.get("profile", DEFAULT_ROBOT), lookup)
    robot = base.with_overrides(**robot_overrides(doc, path, m))
    check_mount(doc, path, m, robot)
    return robot


def _ladar(doc: _Doc, path: str, v: Any) -> Any:
    from mdle.sim.ladar import NOISE_MODELS, ladar_profile

    if isinstance(v, str):
        return _named(doc, path, v, ladar_profile)
    m = _mapping(doc, path, v, _LADAR_KEYS, "a profile name, or `profile` and overrides")
    base = _named(doc, f"{path}.profile", m.get("profile", "lms200"), ladar_profile)
    ch: dict[str, Any] = {}
    if "beams" in m:
        ch["beams"] = _integer(doc, f"{path}.beams", m["beams"], minimum=1)
        if ch["beams"] > _MAX_BEAMS:
            raise doc.fail(f"{path}.beams", f"must be at most {_MAX_BEAMS}, got {m['beams']}")
    if "fov" in m:
        fov = _number(doc, f"{path}.fov", m["fov"], positive=True, unit="deg")
        if fov > 360:
            raise doc.fail(f"{path}.fov", f"must be at most 360 degrees, got {m['fov']}")
        ch["fov"] = math.radians(fov)
    if "max_range" in m:
        ch["max_range"] = _number(doc, f"{path}.max_range", m["max_range"], positive=True,
                                   unit="m")
    if "noise" in m:
        if m["noise"] not in NOISE_MODELS:
            raise doc.fail(f"{path}.noise", f"unknown noise model {m['noise']!r}; one of: "
                           f"{', '.join(NOISE_MODELS)}")
        ch["noise"] = m["noise"]
    for key in ("sigma", "resolution", "rate"):
        if key in m:
            ch[key] = _number(doc, f"{path}.{key}", m[key], nonneg=True)
    if ch.get("rate", 0.0) > MAX_LADAR_RATE:
        raise doc.fail(f"{path}.rate", f"must be at most {MAX_LADAR_RATE:g} Hz, got {m['rate']}")
    return base.with_overrides(**ch)


def _named(doc: _Doc, path: str, v: Any, lookup: Callable[[str], Any]) -> Any:
    name = _string(doc, path, v)
    try:
        return lookup(name)
    except WorldError as err:
        raise doc.fail(path, err.diagnostics[0].message) from None


def _start(doc: _Doc, path: str, v: Any) -> Pose:
    if isinstance(v, list):
        if len(v) != 3:
            raise doc.fail(path, f"expected [x, y, theta] (m, m, deg), got {_show(v)}")
        x, y, th = (_number(doc, f"{path}[{i}]", v[i], coordinate=i < 2,
                             unit="m" if i < 2 else "deg") for i in range(3))
    else:
        m = _mapping(doc, path, v, ("x", "y", "theta"), "x, y in metres, theta in degrees")
        for key in ("x", "y"):
            if key not in m:
                raise doc.fail(path, f"missing key `{key}`")
        x = _number(doc, f"{path}.x", m["x"], coordinate=True)
        y = _number(doc, f"{path}.y", m["y"], coordinate=True)
        th = _number(doc, f"{path}.theta", m.get("theta", 0.0), unit="deg")
    return Pose(x, y, math.radians(th))


def _yaml_value(doc: _Doc) -> Any:
    """Return the value of a YAML document (None if empty); WorldError on bad YAML.

    Also used by other YAML inputs (study specs), so they get the same limits.
    """
    import yaml

    try:
        data = _Builder(doc).build(_events(doc.text))
    except yaml.MarkedYAMLError as fast:
        # libyaml words some errors differently: the pure-Python parser's words are the
        # documented ones (the parse is redone only on this error path)
        err = fast
        try:
            for _ in _events(doc.text, fast=False):
                pass
        except yaml.MarkedYAMLError as slow:
            err = slow
        except yaml.YAMLError:
            pass
        mark = err.problem_mark or err.context_mark
        line, col = (mark.line + 1, mark.column + 1) if mark else (1, 1)
        doc.marks["<yaml>"] = (line, col, 1)
        problem = err.problem or err.context or "malformed YAML"
        raise doc.fail("<yaml>", f"not valid YAML: {problem}") from None
    except yaml.YAMLError as err:
        raise doc.fail("", f"not valid YAML: {err}") from None
    return data


def parse_world(text: str, file: str = "<string>", default_name: str = "world") -> Any:
    """Parse and validate world YAML text into a :class:`sim.world.World`.

    Raises
    ------
    WorldError
        With the file, line, column, key path and problem of the first error found.
    """
    from mdle.sim.ladar import LMS200
    from mdle.sim.profiles import DEFAULT_ROBOT, robot_profile
    from mdle.sim.world import World

    doc = _Doc(file, text)
    data = _yaml_value(doc)
    if data is None:
        data = {}
    top = _mapping(doc, "", data, _TOP_KEYS, "a world")
    name = _string(doc, "name", top["name"]) if "name" in top else default_name
    description = _string(doc, "description", top.get("description", ""))
    seed = _integer(doc, "seed", top["seed"], maximum=MAX_SEED) if "seed" in top else 0
    start = _start(doc, "start", top["start"]) if "start" in top else Pose()
    robot = (_robot(doc, "robot", top["robot"]) if "robot" in top
             else robot_profile(DEFAULT_ROBOT))
    ladar = _ladar(doc, "ladar", top["ladar"]) if "ladar" in top else LMS200
    extent = None
    if "extent" in top:
        e = top["extent"]
        if not isinstance(e, list) or len(e) != 4:
            raise doc.fail("extent", f"expected [xmin, ymin, xmax, ymax] in metres, got {_show(e)}")
        ex = tuple(_number(doc, f"extent[{i}]", e[i], coordinate=True) for i in range(4))
        if ex[2] <= ex[0] or ex[3] <= ex[1]:
            raise doc.fail("extent", "xmax and ymax must exceed xmin and ymin")
        extent = (ex[0], ex[1], ex[2], ex[3])
        if not (ex[0] <= start.x <= ex[2] and ex[1] <= start.y <= ex[3]):
            raise doc.fail("start" if "start" in top else "extent",
                           f"the start ({start.x:g}, {start.y:g}"
                           + ("" if "start" in top else "; no `start` is given")
                           + ") lies outside the world's "
                           f"extent [{ex[0]:g}, {ex[1]:g}, {ex[2]:g}, {ex[3]:g}] (xmin, ymin, "
                           "xmax, ymax): the robot would start off the map")
    obs_raw = top.get("obstacles", [])
    if obs_raw is None:
        obs_raw = []
    if not isinstance(obs_raw, list):
        raise doc.fail("obstacles", f"expected a list of obstacles, got {_show(obs_raw)}")
    obstacles = tuple(_obstacle(doc, f"obstacles[{i}]", o) for i, o in enumerate(obs_raw))
    world = World(name=name, obstacles=obstacles, start_pose=start, seed=seed, robot=robot,
                  ladar=ladar, description=description,
                  source=None if file.startswith("<") else file, extent=extent)
    if "start" in top or "robots" not in top:  # a team's own start: only if given
        _check_start(doc, "start", world, robot, start, "the robot")
    if "robots" in top:
        team = _team(doc, top["robots"], robot, ladar)
        world = dataclasses.replace(world, robots=team)
        for i, r in enumerate(team):
            _check_start(doc, f"robots[{i}].start", world, r.profile, r.start,
                         f"robot `{r.name}`")
    return world


def _check_start(doc: _Doc, path: str, world: Any, robot: Any, start: Pose, who: str) -> None:
    """Refuse a start where the robot's body overlaps or touches an obstacle."""
    from mdle.sim.collision import CONTACT

    if not world.obstacles:
        return
    clearance = world.clearance((start.x, start.y), robot.radius)
    if clearance <= CONTACT:  # touching counts: the simulator would stall it at t = 0
        near = int(world.nearest_boundary((start.x, start.y)).obstacle)
        what = _describe(world.obstacles[near], near)
        how = "overlaps" if clearance < 0 else "touches"
        raise doc.fail(path, f"{who} ({robot.name}, radius {robot.radius} m) at "
                       f"({start.x:g}, {start.y:g}) {how} {what}")


def _team(doc: _Doc, v: Any, robot: Any, ladar: Any) -> tuple[Any, ...]:
    """Read ``robots:``, the robots of a team: names unique, starts apart."""
    from mdle.sim.world import RobotPlace

    if not isinstance(v, list) or not v:
        raise doc.fail("robots", f"expected a list of robots (name, start, and optionally "
                       f"robot and ladar), got {_show(v)}")
    out: list[Any] = []
    for i, raw in enumerate(v):
        path = f"robots[{i}]"
        m = _mapping(doc, path, raw, _TEAM_ROBOT_KEYS, "a robot: name, start, robot, ladar")
        for key in ("name", "start"):
            if key not in m:
                raise doc.fail(path, f"missing key `{key}` (a robot needs a name and a start)")
        name = _string(doc, f"{path}.name", m["name"])
        if not _ROBOT_NAME.fullmatch(name):
            raise doc.fail(f"{path}.name", f"a robot's name is a plan name (letters, digits, "
                           f"`_`, not starting with a digit), got {name!r}")
        if any(r.name == name for r in out):
            raise doc.fail(f"{path}.name", f"robot `{name}` is listed twice")
        place = RobotPlace(name,
                           _robot(doc, f"{path}.robot", m["robot"]) if "robot" in m else robot,
                           _ladar(doc, f"{path}.ladar", m["ladar"]) if "ladar" in m else ladar,
                           _start(doc, f"{path}.start", m["start"]))
        for other in out:
            gap = math.hypot(place.start.x - other.start.x, place.start.y - other.start.y)
            if gap < place.profile.radius + other.profile.radius:
                raise doc.fail(f"{path}.start", f"robot `{name}` at ({place.start.x:g}, "
                               f"{place.start.y:g}) overlaps robot `{other.name}` at "
                               f"({other.start.x:g}, {other.start.y:g}): centres {gap:.3g} m "
                               f"apart, radii {place.profile.radius:g} + "
                               f"{other.profile.radius:g} m")
        out.append(place)
    return tuple(out)


def _describe(shape: Any, index: int) -> str:
    label = f"obstacles[{index}] ({shape.kind}"
    return label + (f" `{shape.name}`)" if shape.name else ")")


def read_world(path: str | os.PathLike[str]) -> Any:
    """Read and validate a world file (WorldError if unreadable or invalid).

    Only a regular file of at most :data:`mdle.userfile.MAX_FILE_BYTES` is read.
    """
    return parse_world(_world_text(path), file=str(path), default_name=Path(path).stem)


def read_world_robot(path: str | os.PathLike[str]) -> Any:
    """Read only the robot of a world file (see :func:`parse_world_robot`)."""
    return parse_world_robot(_world_text(path), file=str(path))


def parse_world_robot(text: str, file: str = "<string>") -> Any:
    """Return the :class:`sim.robot.RobotProfile` a world's YAML names (the default if none).

    Only the YAML, the top-level keys and ``robot`` are checked: no obstacle is built,
    so this needs neither numpy nor shapely.

    Raises
    ------
    WorldError
        Not YAML, an unknown top-level key, or a bad ``robot`` entry.
    """
    from mdle.sim.profiles import DEFAULT_ROBOT, robot_profile

    doc = _Doc(file, text)
    data = _yaml_value(doc)
    top = _mapping(doc, "", {} if data is None else data, _TOP_KEYS, "a world")
    return _robot(doc, "robot", top["robot"]) if "robot" in top else robot_profile(DEFAULT_ROBOT)


def _world_text(path: str | os.PathLike[str]) -> str:
    from mdle.userfile import UserFileError, read_user_file

    p = Path(path)
    try:
        data = read_user_file(p)
    except UserFileError as err:
        if err.reason == "no such file":
            raise WorldError(f"world file not found: {p}") from None
        raise WorldError(f"cannot read world file {p}: {err.reason}") from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise WorldError(f"cannot read world file {p}: not UTF-8 text (byte "
                         f"0x{data[err.start]:02x} at offset {err.start})") from None
