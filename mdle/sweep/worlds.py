"""Worlds as they travel with a task: YAML text, or the parameters of a generated shape.

A generated obstacle (:mod:`sim.generated`) travels as its generator's parameters (seed,
index, family) in canonical JSON: the generator is seeded, so every worker rebuilds the
same shape, and the parameters (with :data:`GENERATOR_VERSION`) are what run keys hash.
Every other world travels as its YAML text.
"""

from __future__ import annotations

import json
from typing import Any

from mdle.sim.yaml_doc import _Doc
from mdle.sweep.keys import canonical

__all__ = ["GENERATOR_VERSION", "generated_text", "build_world"]

#: Part of a generated world's text, so results tables rerun if the generator changes.
GENERATOR_VERSION = 1
_PREFIX = '{"generated":'


def generated_text(seed: int, index: int, family: str | None = None) -> str:
    """Return the travelling text of generated shape ``(seed, index)``."""
    return canonical({"generated": {"seed": seed, "index": index, "family": family,
                                    "version": GENERATOR_VERSION}})


def build_world(text: str, label: str, robot: str | dict[str, Any] | None = None) -> Any:
    """Rebuild a :class:`sim.world.World` from its travelling text, with ``robot`` if given.

    ``robot`` is a profile name or a profile mapping (a world file's ``robot`` section);
    None keeps the world's own (the ideal unicycle for generated shapes).

    Raises
    ------
    WorldError
        Invalid world text or robot profile.
    """
    from mdle.sim.world_yaml import parse_world

    if text.startswith(_PREFIX):
        from mdle.sim.generated import generate_shape
        from mdle.sim.profiles import robot_profile

        g = json.loads(text)["generated"]
        shape = generate_shape(int(g["seed"]), int(g["index"]), g.get("family"))
        return shape.world(robot=robot_profile("ideal") if robot is None
                           else robot_from(robot, label))
    if robot is not None:
        import yaml

        data = yaml.safe_load(text) or {}
        data["robot"] = robot
        text = yaml.safe_dump(data, sort_keys=False)
    return parse_world(text, file=f"<world {label}>", default_name=label)


def robot_from(value: str | dict[str, Any], label: str) -> Any:
    """Return the robot profile a name or a profile mapping describes."""
    from mdle.sim.world_robots import _robot as robot_section

    return robot_section(_Doc(f"<robot {label}>", ""), "robot", value)
