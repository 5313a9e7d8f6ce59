"""What a recording says about the robot: its body, its odometry noise, its law's numbers.

``body_header`` and ``profile_header`` give the trace header's ``radius`` and
``odometry`` (what ``/footprint`` and ``/odom``'s covariances are made from, so that a
recording and the export of its trace agree); ``footprint`` the body's outline;
``diagnostic_names`` the fields of ``mdle_msgs/msg/Diagnostics``.
"""

from __future__ import annotations

import math
from typing import Any

__all__ = ["FOOTPRINT_SIDES", "body_header", "diagnostic_names", "footprint", "profile_header"]


#: Corners of the polygon drawn for a disc-shaped body.
FOOTPRINT_SIDES = 24


def footprint(radius: float) -> list[tuple[float, float]]:
    """Return the outline of a disc of ``radius`` (m) about base_link's origin.

    A polygon of :data:`FOOTPRINT_SIDES` corners around the disc (its sides touch it), so
    the drawn body is never smaller than the simulated one.
    """
    r = radius / math.cos(math.pi / FOOTPRINT_SIDES)
    return [(r * math.cos(2 * math.pi * i / FOOTPRINT_SIDES),
             r * math.sin(2 * math.pi * i / FOOTPRINT_SIDES)) for i in range(FOOTPRINT_SIDES)]


def body_header(backend: Any) -> dict[str, Any]:
    """Return the trace header's ``radius`` and (simulation) ``odometry`` of a backend.

    The body's radius (m) draws ``/footprint``; the simulator's odometry noise model
    (``distance``, ``turn``, ``drift``) sets ``/odom``'s covariances
    (:mod:`mdle.rosmsg.covariance`). A robot's unknown noise is left out.
    """
    profile = getattr(backend, "profile", None)
    if hasattr(profile, "radius") and hasattr(profile, "odometry"):  # a simulated robot
        return profile_header(profile)
    limits = getattr(backend, "limits", None)
    radius = getattr(limits, "radius", 0.0)
    if isinstance(radius, (int, float)) and math.isfinite(radius) and radius > 0:
        return {"radius": float(radius)}
    return {}


def profile_header(profile: Any) -> dict[str, Any]:
    """Return the header's ``radius`` and ``odometry`` of a simulated robot's profile."""
    out: dict[str, Any] = {}
    if math.isfinite(profile.radius) and profile.radius > 0:
        out["radius"] = float(profile.radius)
    noise = profile.odometry
    out["odometry"] = {"distance": float(noise.distance), "turn": float(noise.turn),
                       "drift": float(noise.drift)}
    return out


def diagnostic_names() -> tuple[str, ...]:
    """Return every diagnostic a built-in control law records, each once, in order."""
    from mdle.atoms import default_registry

    names: dict[str, None] = {}
    for law in default_registry().laws.values():
        names.update(dict.fromkeys(law.reports))
    return tuple(names)
