"""What the fuzz tests share: how many examples each draws, a few in CI, many at scale.

Every fuzz test names its CI count through :func:`examples`; ``MDLE_FUZZ_SCALE=N``
multiplies them all (``tests/fuzz/at_scale.py`` sets it and runs the tier on every
core). CI leaves it unset: each test draws its base count and the tier stays within a
few minutes.
"""

from __future__ import annotations

import os

__all__ = ["examples", "scale"]


def scale() -> int:
    """Return the multiplier from ``MDLE_FUZZ_SCALE`` (1 when unset or not a number >= 1)."""
    try:
        factor = int(os.environ.get("MDLE_FUZZ_SCALE", "1"))
    except ValueError:
        return 1
    return max(1, factor)


def examples(base: int) -> int:
    """Return ``base`` examples times the scale."""
    return base * scale()
