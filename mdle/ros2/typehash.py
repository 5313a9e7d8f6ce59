"""ROS 2 type hashes (REP-2016, ``RIHS01_<sha256>``) derived from the message definitions.

A ROS 2 Jazzy node announces each topic's type hash in its endpoints' USER_DATA
(``typehash=RIHS01_<hex>;``); ROS tools warn about endpoints without one. The hash is the
SHA-256 of a canonical JSON text of the type's description: its fields (name, type id,
array capacity, string capacity, nested type name; no default values, no constants) and
those of every type it uses, sorted by name. This module computes it from the same
``ros2msg`` field lists mdle writes into recordings, so nothing is copied from a ROS
installation; the tests compare the results with hashes a real Jazzy announced.
"""

from __future__ import annotations

import hashlib
import json
import re
from collections.abc import Mapping
from typing import Any

from mdle.rosmsg.msgdefs import DEFINITIONS

__all__ = ["ROS2_DEFINITIONS", "type_description", "type_hash"]

#: The types the ROS 2 backend and ``mdle sim serve --ros2`` use that recordings do not.
ROS2_DEFINITIONS: dict[str, str] = {
    **DEFINITIONS,
    "geometry_msgs/msg/TwistStamped": "std_msgs/Header header\nTwist twist\n",
    "rosgraph_msgs/msg/Clock": "builtin_interfaces/Time clock\n",
}

# type_description_interfaces/msg/FieldType: the ids of the primitive types; an array
# adds 48, a bounded sequence 96, an unbounded sequence 144.
_TYPE_IDS = {"nested": 1, "int8": 2, "uint8": 3, "int16": 4, "uint16": 5, "int32": 6,
             "uint32": 7, "int64": 8, "uint64": 9, "float32": 10, "float64": 11,
             "char": 13, "bool": 15, "byte": 16, "string": 17}
_ARRAY, _BOUNDED_SEQUENCE, _SEQUENCE = 48, 96, 144
_FIELD = re.compile(r"^(?P<type>[A-Za-z][\w/]*)(?P<array>\[(?P<bound><=)?(?P<size>\d*)\])?"
                    r"\s+(?P<name>\w+)")


def _fields(full: str, definitions: Mapping[str, str]) -> list[dict[str, Any]]:
    """Return the fields of type ``full`` as the hash describes them (no defaults)."""
    package = full.partition("/")[0]
    out = []
    for line in definitions[full].splitlines():
        words = line.split(None, 2)
        if len(words) < 2 or "=" in words[1]:  # blank, or a constant (not in the hash)
            continue
        m = _FIELD.match(line)
        if m is None:
            raise ValueError(f"{full}: cannot read the field `{line}`")
        base = m["type"]
        nested = ""
        if base in _TYPE_IDS:
            type_id = _TYPE_IDS[base]
        else:
            pkg, _, name = base.rpartition("/")
            nested = f"{pkg or package}/msg/{name}"
            type_id = _TYPE_IDS["nested"]
        capacity = 0
        if m["array"]:
            if m["size"] and not m["bound"]:
                type_id += _ARRAY
                capacity = int(m["size"])
            elif m["bound"]:
                type_id += _BOUNDED_SEQUENCE
                capacity = int(m["size"])
            else:
                type_id += _SEQUENCE
        out.append({"name": m["name"], "type": {"type_id": type_id, "capacity": capacity,
                                                "string_capacity": 0,
                                                "nested_type_name": nested}})
    return out


def type_description(name: str, definitions: Mapping[str, str] = ROS2_DEFINITIONS
                     ) -> dict[str, Any]:
    """Return the hashed form of ``type_description_interfaces/TypeDescription`` of ``name``.

    ``name`` is a full ROS type name (``geometry_msgs/msg/Twist``); every type it uses
    must be in ``definitions``.
    """
    referenced: dict[str, list[dict[str, Any]]] = {}
    todo = [name]
    while todo:
        full = todo.pop()
        for f in _fields(full, definitions):
            nested = f["type"]["nested_type_name"]
            if nested and nested != name and nested not in referenced:
                referenced[nested] = _fields(nested, definitions)
                todo.append(nested)
    return {"type_description": {"type_name": name, "fields": _fields(name, definitions)},
            "referenced_type_descriptions": [
                {"type_name": n, "fields": referenced[n]} for n in sorted(referenced)]}


def type_hash(name: str, definitions: Mapping[str, str] = ROS2_DEFINITIONS) -> str:
    """Return the RIHS01 hash of the ROS type ``name`` (``RIHS01_`` and 64 hex digits).

    >>> type_hash("geometry_msgs/msg/Twist")[:23]
    'RIHS01_9c45bf16fe0983d8'
    """
    text = json.dumps(type_description(name, definitions), ensure_ascii=True,
                      separators=(", ", ": "), sort_keys=False)
    return "RIHS01_" + hashlib.sha256(text.encode("utf-8")).hexdigest()
