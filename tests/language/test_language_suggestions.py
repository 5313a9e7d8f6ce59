"""'Did you mean' stays cheap: each unknown name is compared with a few candidates.

4,000 unknown names among 4,000 definitions once cost 16 million difflib ratios (24 s);
the candidates are now indexed by length once and capped per name. The cost is pinned
by counting the candidates handed to difflib, not by timing.
"""

from __future__ import annotations

import difflib
from typing import Any

import pytest

from mdle.atoms import default_registry
from mdle.core.errors import CheckError
from mdle.lang import check_names as compile_module
from mdle.lang import load_text


def test_many_unknown_names_compare_with_few_candidates(monkeypatch: pytest.MonkeyPatch) -> None:
    compared = [0]
    real = difflib.get_close_matches

    def counting(word: str, possibilities: Any, *args: Any, **kwargs: Any) -> list[str]:
        pool = list(possibilities)
        compared[0] += len(pool)
        return real(word, pool, *args, **kwargs)

    monkeypatch.setattr(compile_module.difflib, "get_close_matches", counting)
    n = 2000
    text = "\n".join(f"atom a{i} = (go(0.3 m/s), unknown_thing_{i} < 1 m, 1 s)"
                     for i in range(n)) + "\n"
    with pytest.raises(CheckError) as err:
        load_text(text, "t.mdle", default_registry())
    assert len(err.value.diagnostics) == n
    assert compared[0] <= n * (compile_module._MAX_CANDIDATES + 50), compared[0]


def test_suggestions_still_found() -> None:
    text = "atom cruise = (go(0.3 m/s), never, 1 s)\nbehavior b = ((cruse), never, inf)\n"
    with pytest.raises(CheckError) as err:
        load_text(text, "t.mdle", default_registry())
    assert err.value.diagnostics[0].hint == "did you mean `cruise`?"
    text = "atom a = (go(0.3 m/s), stalld, 1 s)\n"
    with pytest.raises(CheckError) as err:
        load_text(text, "t.mdle", default_registry())
    assert err.value.diagnostics[0].hint == "did you mean `stalled`?"
