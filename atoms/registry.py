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
>>> from mdle.units import SPEED
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

import enum
import inspect
import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Union

from mdle.backend import Command, Observation, RobotLimits
from mdle.units import NONE, Dim

__all__ = [
    "REQUIRED",
    "BOOL",
    "Param",
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


class Context:
    """What a control law or sensor function may read during one tick.

    ``obs`` is the tick's observation, ``t`` the local time of the element being
    evaluated (seconds since it started), ``dt`` the tick length, ``limits`` the robot's
    limits, and ``cache`` a dictionary shared by every function during this tick only,
    so that an estimate (the boundary seen in the scan, say) is computed once per tick.
    The runtime owns the context and sets ``t`` before each evaluation. ``atom`` is the
    per-atom state of the innermost running atom (what its law's ``start`` made; None when
    none runs or it has none), so that a sensor function can report on the running law
    (``lost``: how long ``follow_boundary`` has lost its boundary).
    """

    __slots__ = ("obs", "t", "dt", "limits", "cache", "atom")

    def __init__(self, obs: Observation, t: float, dt: float, limits: RobotLimits,
                 cache: dict[Any, Any] | None = None, atom: Any = None) -> None:
        self.obs = obs
        self.t = t
        self.dt = dt
        self.limits = limits
        self.cache: dict[Any, Any] = {} if cache is None else cache
        self.atom = atom


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
    the state is passed to every ``step`` and dropped when the atom ends.
    """

    name: str
    params: tuple[Param, ...]
    step: StepFn
    start: StartFn | None = None
    doc: str = ""

    def param(self, name: str) -> Param | None:
        """Return the parameter called ``name``, or None."""
        return next((p for p in self.params if p.name == name), None)


@dataclass(frozen=True)
class SensorSpec:
    """A sensor function: the y that interrupts (and control laws) read.

    ``result`` is the dimension of a numeric result, :data:`BOOL`, or None for a number
    whose dimension only its use tells (``message(channel)``: whatever was sent).
    """

    name: str
    params: tuple[Param, ...]
    result: Dim | _Bool | None
    fn: SensorFn
    doc: str = ""

    def param(self, name: str) -> Param | None:
        """Return the parameter called ``name``, or None."""
        return next((p for p in self.params if p.name == name), None)


_SPEC_ATTR = "__mdle_spec__"


def _doc(fn: Callable[..., Any]) -> str:
    return inspect.cleandoc(fn.__doc__ or "").split("\n\n")[0]


def control_law(*params: Param, name: str | None = None,
                start: StartFn | None = None) -> Callable[[StepFn], StepFn]:
    """Declare a function ``step(args, ctx, state) -> Command`` as a control law.

    The law's MDLe name is the function's name (trailing underscores dropped) unless
    ``name`` is given. The function is returned unchanged, with its spec attached.
    """

    def wrap(fn: StepFn) -> StepFn:
        spec = LawSpec(name or fn.__name__.rstrip("_"), tuple(params), fn, start, _doc(fn))
        setattr(fn, _SPEC_ATTR, spec)
        return fn

    return wrap


def sensor(*params: Param, result: Dim | _Bool | None, name: str | None = None
           ) -> Callable[[SensorFn], SensorFn]:
    """Declare a function ``fn(args, ctx) -> float | bool`` as a sensor function."""

    def wrap(fn: SensorFn) -> SensorFn:
        spec = SensorSpec(name or fn.__name__.rstrip("_"), tuple(params), result, fn, _doc(fn))
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
        return Registry.from_specs([*self.laws.values(), *self.sensors.values(),
                                    *other.laws.values(), *other.sensors.values()])

    def names(self) -> list[str]:
        """Return every registered name, sorted (for completion and 'did you mean')."""
        return sorted([*self.laws, *self.sensors])
