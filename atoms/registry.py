"""The registry of control laws and sensor functions the checker and runtime see.

A control law or sensor function is a plain Python function with a decorator that
attaches a typed, unit-annotated :class:`LawSpec` or :class:`SensorSpec`; the decorator
changes nothing else and registers nothing globally. :meth:`Registry.from_modules`
collects the specs of the given modules, and the checker takes a registry as an
argument, so tests can build small ones.

Modules that declare specs must not import numpy or shapely at import time: the
checker loads them to learn signatures, and ``mdle check`` stays fast only if the
numeric code is imported on first use.

Example
-------
>>> from mdle.core.units import SPEED
>>> @control_law(Param("v", SPEED, 0.3, doc="forward speed"))
... def cruise(args, ctx, state):
...     '''Drive straight ahead.'''
...     return Command(args["v"], 0.0)
>>> import types
>>> reg = Registry.from_modules(types.SimpleNamespace(cruise=cruise))
>>> reg.laws["cruise"].params[0].default
0.3
"""

from __future__ import annotations

import dataclasses
import enum
import inspect
import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Union

from mdle.core.backend import Command, Observation, RobotLimits
from mdle.core.units import NONE, Dim

__all__ = [
    "REQUIRED",
    "BOOL",
    "Param",
    "Bounds",
    "Report",
    "Context",
    "LawSpec",
    "SensorSpec",
    "control_law",
    "sensor",
    "Registry",
]


class _Required(enum.Enum):
    REQUIRED = "required"

    def __repr__(self) -> str:
        return "REQUIRED"


#: Default of a parameter that must be given.
REQUIRED = _Required.REQUIRED


class _Bool(enum.Enum):
    BOOL = "bool"

    def __str__(self) -> str:
        return "a condition (true or false)"


#: Result kind of a sensor function that answers true or false (``stalled``).
BOOL = _Bool.BOOL

Value = Union[float, str, bool]
Args = Mapping[str, Value]


@dataclass(frozen=True)
class Param:
    """A parameter of a control law or sensor function.

    ``dim`` is the physical dimension of a numeric parameter; a parameter with
    ``choices`` takes a symbol from that closed set instead (``side = right``).
    ``default`` is in SI units (or a symbol), or :data:`REQUIRED`.

    The values a numeric parameter accepts (in SI): at least ``low`` (more than ``low``
    with ``low_open``), at most ``high``, and a finite number unless ``finite`` is False
    (``inf`` may then stand for "no limit"); NaN never. The checker refuses anything
    else with the argument's place, so a law never starts with a value it cannot use.
    """

    name: str
    dim: Dim = NONE
    default: Value | _Required = REQUIRED
    choices: tuple[str, ...] = ()
    doc: str = ""
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    finite: bool = True
    #: For a speed or turn rate: the law commands it as given, so the checker warns when a
    #: constant exceeds the robot's limits. False for a ceiling the law keeps within the
    #: robot's own limit (``umax`` of ``follow_boundary``).
    commanded: bool = True
    #: For a sensor function's parameter: its argument must be a fixed value (by default
    #: a sensor function's numeric arguments may read other sensor functions each tick).
    fixed: bool = False
    any_name: str = ""
    """What an open name argument names (``channel``, ``robot``): any name is taken, and
    the checker records it so that a team can check its channels and robots."""

    @property
    def is_symbol(self) -> bool:
        """True when the parameter takes a symbol such as ``right`` rather than a number."""
        return bool(self.choices) or bool(self.any_name)

    def accepts(self, value: float) -> bool:
        """Whether ``value`` (SI) is within the declared range."""
        if math.isnan(value) or (self.finite and math.isinf(value)):
            return False
        if self.low is not None and (value < self.low or self.low_open and value == self.low):
            return False
        return self.high is None or value <= self.high

    def range_words(self) -> str:
        """Return the declared range in words: ``a finite number more than 0``."""
        parts = []
        if self.low is not None:
            parts.append(f"{'more than' if self.low_open else 'at least'} {self.low:g}")
        if self.high is not None:
            parts.append(f"at most {self.high:g}")
        what = "a finite number" if self.finite else "a number (or inf)"
        return what + (" " + " and ".join(parts) if parts else "")


@dataclass(frozen=True)
class Report:
    """A diagnostic a control law records each tick: its unit and how to read its values.

    ``dim`` is its dimension (SI inside: metres, radians, seconds). A ``flag`` is 0 or 1
    (no or yes); ``codes`` name the values 0, 1, 2, ... of a mode; ``absent`` is the value
    that stands for "nothing measured" (the trace holds numbers only).
    """

    dim: Dim = NONE
    doc: str = ""
    flag: bool = False
    codes: tuple[str, ...] = ()
    absent: float | None = None


class Context:
    """What a control law or sensor function may read during one tick.

    ``obs`` is the tick's observation, ``t`` the local time of the element being
    evaluated (seconds since it started), ``dt`` the tick length, ``limits`` the robot's
    limits, and ``cache`` a dictionary shared by every function during this tick only,
    so that an estimate (the boundary seen in the scan, say) is computed once per tick.
    The runtime owns the context and sets ``t`` before each evaluation. ``atom`` is the
    per-atom state of the innermost running atom (what its law's ``start`` made; None when
    none runs or it has none), so that a sensor function can report on the running law
    (``lost``: how long ``follow_boundary`` has lost its boundary). ``memory`` holds what
    the element being tested remembered when it started (``at_start(...)``).
    """

    __slots__ = ("obs", "t", "dt", "limits", "cache", "atom", "memory")

    def __init__(self, obs: Observation, t: float, dt: float, limits: RobotLimits,
                 cache: dict[Any, Any] | None = None, atom: Any = None) -> None:
        self.obs = obs
        self.t = t
        self.dt = dt
        self.limits = limits
        self.cache: dict[Any, Any] = {} if cache is None else cache
        self.atom = atom
        #: the values the element being tested remembered when it started (at_start)
        self.memory: Mapping[Any, Any] = _NO_MEMORY


#: The memory of an element that remembers nothing.
_NO_MEMORY: Mapping[Any, Any] = MappingProxyType({})

#: ``step(args, ctx, state) -> Command``: the control law, called once per tick.
StepFn = Callable[[Args, Context, Any], Command]
#: ``start(args, ctx) -> state``: makes the per-atom state when the atom starts.
StartFn = Callable[[Args, Context], Any]
#: ``fn(args, ctx) -> float | bool``: a sensor function.
SensorFn = Callable[[Args, Context], Union[float, bool]]


@dataclass(frozen=True)
class LawSpec:
    """A control law U: its name, parameters and the functions that run it.

    ``start`` (optional) builds the per-atom state when an atom using this law starts;
    the state is passed to every ``step`` and dropped when the atom ends. ``reports``
    declares the diagnostics the law records each tick (``ctx.cache["trace"]``), so that
    they can be shown with their units.
    """

    name: str
    params: tuple[Param, ...]
    step: StepFn
    start: StartFn | None = None
    doc: str = ""
    reports: Mapping[str, Report] = field(default_factory=lambda: MappingProxyType({}))

    def param(self, name: str) -> Param | None:
        """Return the parameter called ``name``, or None."""
        return next((p for p in self.params if p.name == name), None)


@dataclass(frozen=True)
class Bounds:
    """The values a sensor function can return (SI): from ``low`` to ``high``.

    ``theta`` lies in (-pi, pi]: ``Bounds(-math.pi, math.pi, low_open=True)``. The
    checker warns about a comparison with a constant that can never hold.
    """

    low: float
    high: float
    low_open: bool = False
    high_open: bool = False

    def holds_somewhere(self, op: str, c: float, reading_left: bool) -> bool:
        """Tell whether ``reading op c`` (or ``c op reading``) can hold for some value."""
        if not reading_left:  # c < r is r > c
            op = {"<": ">", "<=": ">=", ">": "<", ">=": "<="}.get(op, op)
        lo, hi = self.low, self.high
        if op == ">":
            return c < hi
        if op == ">=":
            return c < hi or (c == hi and not self.high_open)
        if op == "<":
            return c > lo
        if op == "<=":
            return c > lo or (c == lo and not self.low_open)
        if op == "==":
            return (lo < c < hi) or (c == lo and not self.low_open) or (
                c == hi and not self.high_open)
        return True


@dataclass(frozen=True)
class SensorSpec:
    """A sensor function: the y that interrupts (and control laws) read.

    ``result`` is the dimension of a numeric result, :data:`BOOL`, or None for a number
    whose dimension only its use tells (``message(channel)``: whatever was sent).
    ``bounds`` are the values it can return, when they are limited. ``overloads`` are
    other sensor functions of the same name taking other arguments (``bearing_to(robot)``
    and ``bearing_to(x, y)``): the checker picks the one the call's arguments fit.
    """

    name: str
    params: tuple[Param, ...]
    result: Dim | _Bool | None
    fn: SensorFn
    doc: str = ""
    bounds: Bounds | None = None
    overloads: tuple["SensorSpec", ...] = ()

    def param(self, name: str) -> Param | None:
        """Return the parameter called ``name``, or None."""
        return next((p for p in self.params if p.name == name), None)


_SPEC_ATTR = "__mdle_spec__"


def _doc(fn: Callable[..., Any]) -> str:
    return inspect.cleandoc(fn.__doc__ or "").split("\n\n")[0]


def control_law(*params: Param, name: str | None = None, start: StartFn | None = None,
                reports: Mapping[str, Report] | None = None) -> Callable[[StepFn], StepFn]:
    """Declare a function ``step(args, ctx, state) -> Command`` as a control law.

    The law's MDLe name is the function's name (trailing underscores dropped) unless
    ``name`` is given. ``reports`` declares the diagnostics it records (see
    :class:`Report`). The function is returned unchanged, with its spec attached.
    """

    def wrap(fn: StepFn) -> StepFn:
        spec = LawSpec(name or fn.__name__.rstrip("_"), tuple(params), fn, start, _doc(fn),
                       MappingProxyType(dict(reports or {})))
        setattr(fn, _SPEC_ATTR, spec)
        return fn

    return wrap


def sensor(*params: Param, result: Dim | _Bool | None, name: str | None = None,
           bounds: Bounds | None = None) -> Callable[[SensorFn], SensorFn]:
    """Declare a function ``fn(args, ctx) -> float | bool`` as a sensor function.

    ``bounds`` declares the values it can return (:class:`Bounds`), when they are limited.
    """

    def wrap(fn: SensorFn) -> SensorFn:
        spec = SensorSpec(name or fn.__name__.rstrip("_"), tuple(params), result, fn, _doc(fn),
                          bounds)
        setattr(fn, _SPEC_ATTR, spec)
        return fn

    return wrap


@dataclass(frozen=True)
class Registry:
    """Control laws and sensor functions by MDLe name. Immutable once built."""

    laws: Mapping[str, LawSpec] = field(default_factory=lambda: MappingProxyType({}))
    sensors: Mapping[str, SensorSpec] = field(default_factory=lambda: MappingProxyType({}))

    @classmethod
    def from_specs(cls, specs: Iterable[LawSpec | SensorSpec]) -> "Registry":
        """Build a registry from specs; a name used twice is a ``ValueError`` naming it."""
        laws: dict[str, LawSpec] = {}
        sensors: dict[str, SensorSpec] = {}
        for spec in specs:
            first = sensors.get(spec.name)
            if (isinstance(spec, SensorSpec) and first is not None
                    and _arities(spec).isdisjoint(
                        a for f in (first, *first.overloads) for a in _arities(f))):
                # the same name with other arguments: an overload (bearing_to(x, y))
                sensors[spec.name] = dataclasses.replace(
                    first, overloads=(*first.overloads, spec, *spec.overloads))
                continue
            if spec.name in laws or spec.name in sensors:
                raise ValueError(f"`{spec.name}` is registered twice")
            if isinstance(spec, LawSpec):
                laws[spec.name] = spec
            else:
                sensors[spec.name] = spec
        return cls(MappingProxyType(laws), MappingProxyType(sensors))

    @classmethod
    def from_modules(cls, *modules: Any) -> "Registry":
        """Collect every decorated function found in the given modules (or namespaces)."""
        specs: list[LawSpec | SensorSpec] = []
        seen: set[int] = set()
        for module in modules:
            for value in vars(module).values():
                spec = getattr(value, _SPEC_ATTR, None)
                if isinstance(spec, (LawSpec, SensorSpec)) and id(value) not in seen:
                    seen.add(id(value))
                    specs.append(spec)
        return cls.from_specs(specs)

    def merged(self, other: "Registry") -> "Registry":
        """Return a registry with the entries of both; a name in both is a ``ValueError``."""
        return Registry.from_specs([*self.laws.values(), *_flat(self.sensors.values()),
                                    *other.laws.values(), *_flat(other.sensors.values())])

    def names(self) -> list[str]:
        """Return every registered name, sorted (for completion and 'did you mean')."""
        return sorted([*self.laws, *self.sensors])


def _arities(spec: SensorSpec) -> frozenset[int]:
    """How many arguments a call of ``spec`` may pass (its defaults may be left out)."""
    needed = sum(1 for p in spec.params if p.default is REQUIRED)
    return frozenset(range(needed, len(spec.params) + 1))


def _flat(specs: Iterable[SensorSpec]) -> list[SensorSpec]:
    """Each spec without its overloads, then the overloads (for building again)."""
    out: list[SensorSpec] = []
    for s in specs:
        out.append(dataclasses.replace(s, overloads=()))
        out.extend(s.overloads)
    return out
