"""What MDLe atoms are made of: control laws, sensor functions, boundary estimators.

:func:`default_registry` gathers every control law and sensor function mdle ships.
The modules it reads declare specs only; numpy is imported on first use.
"""

from __future__ import annotations

from mdle.atoms.registry import Registry

__all__ = ["default_registry"]


def default_registry() -> Registry:
    """Return the registry of the built-in control laws and sensor functions."""
    from mdle.atoms import boundary, follow, laws, motion, sensors, team

    return Registry.from_modules(laws, sensors, boundary, follow, motion, team)
