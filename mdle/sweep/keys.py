"""The canonical text of a value, which run keys and world texts are hashed from.

Its own module because the spec, the worlds it generates and the tasks all hash with it,
and must agree byte for byte.
"""

from __future__ import annotations

import json
from typing import Any

__all__ = ["canonical"]


def canonical(value: Any) -> str:
    """Return the canonical JSON text of ``value`` (sorted keys; what run keys hash)."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=True)
