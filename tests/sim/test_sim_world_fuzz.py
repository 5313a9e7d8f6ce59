"""Whatever a world file holds, loading gives a World or a WorldError, never a traceback."""

from __future__ import annotations

import math

import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mdle.core.errors import WorldError
from mdle.sim.world_yaml import OBSTACLE_TYPES, parse_world

KEYS = ["name", "description", "seed", "start", "robot", "ladar", "extent", "obstacles", "type",
        "points", "center", "size", "radius", "axes", "angle", "thickness", "closed", "start",
        "end", "spacing", "profile", "x", "y", "theta", "noise", "sigma", "rate", "beams",
        "fov", "max_range", "resolution", "odometry", "ladar_mount", "max_speed", *OBSTACLE_TYPES]

OBSTACLE_KEYS = ["points", "center", "size", "radius", "axes", "angle", "thickness", "closed",
                 "start", "end", "spacing", "name"]

scalars = st.one_of(st.none(), st.booleans(), st.integers(-5, 20),
                    st.floats(-20, 20), st.sampled_from([math.nan, math.inf, -math.inf]),
                    st.sampled_from(KEYS), st.text(max_size=5))
values = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=5),
    st.dictionaries(st.one_of(st.sampled_from(KEYS), st.integers(0, 3)), inner, max_size=5)),
    max_leaves=25)
obstacle = st.fixed_dictionaries({"type": st.one_of(st.sampled_from([*OBSTACLE_TYPES, "blob"]),
                                                   values)},
                                 optional={k: values for k in OBSTACLE_KEYS})
world = st.fixed_dictionaries({}, optional={
    "seed": values, "start": values, "robot": values, "ladar": values, "extent": values,
    "obstacles": st.lists(st.one_of(obstacle, values), max_size=4), "name": values})


def _load(data: object) -> None:
    text = yaml.safe_dump(data, allow_unicode=True)
    try:
        parse_world(text, file="fuzz.yaml")
    except WorldError as err:
        assert err.diagnostics and err.diagnostics[0].message


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(world)
def test_structured_fuzz_never_crashes(data: object) -> None:
    _load(data)


@settings(max_examples=150, deadline=None)
@given(values)
def test_arbitrary_documents_never_crash(data: object) -> None:
    _load(data)


@settings(max_examples=150, deadline=None)
@given(st.text(max_size=60))
def test_arbitrary_text_never_crashes(text: str) -> None:
    try:
        parse_world(text, file="fuzz.yaml")
    except WorldError:
        pass
