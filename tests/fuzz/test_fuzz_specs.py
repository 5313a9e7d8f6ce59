"""Hostile team files, study specs and parameterised plans: a message, bounded work.

Numbers at every key that takes one (huge, tiny, negative, not finite, integers of
hundreds of digits, counts that would allocate gigabytes up front), names too long for
a file, wrong types: a team file or a study either parses or raises mdle's own error,
never anything else, and never allocates in proportion to a count it was given. Chains
of parameterised definitions with random argument expressions check, or are refused
at the expansion budget, without making more instances than the budget allows.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mdle.core.errors import MdleError
from tests.fuzz.conftest import examples
from tests.language.conftest import count_instances

#: Numbers as YAML may carry them, hostile first.
NUMBERS = st.one_of(
    st.sampled_from([0, -1, 1, 2**31, 2**63, 2**64, 3 * 10**20, 10**40, 10**400, 1e308,
                     -1e308, 5e-324, 1e-308, 0.05, 1000, 1001, 1e6]),
    st.integers(-(2**70), 2**70), st.floats(allow_nan=False, allow_infinity=False))
#: Anything a key might hold instead of what it takes.
VALUES = st.recursive(
    st.one_of(NUMBERS, st.booleans(), st.none(), st.text(max_size=8),
              st.sampled_from([".inf", "-.inf", ".nan", "1e309", "w" * 300, "1 m", "10 Hz"])),
    lambda inner: st.one_of(st.lists(inner, max_size=3),
                            st.dictionaries(st.sampled_from(["count", "first", "seed", "x",
                                                             "y", "theta", "ranges", "kf"]),
                                            inner, max_size=3)),
    max_leaves=6)


def _yaml(data: dict[str, Any]) -> str:
    # JSON is YAML: every value above is written exactly (no YAML type guessing)
    return json.dumps(data)


TEAM_KEYS = st.sampled_from(["seed", "rate", "until", "messages"])


@settings(max_examples=examples(60), deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(top=st.dictionaries(TEAM_KEYS, VALUES, max_size=3),
       messages=st.dictionaries(st.sampled_from(["range", "loss", "seed"]), NUMBERS,
                                max_size=3))
def test_team_files_parse_or_say_why(top: dict[str, Any], messages: dict[str, Any],
                                     tmp_path: Path) -> None:
    from mdle.team.file import parse_team

    data: dict[str, Any] = {"world": "duel.world.yaml", "robots": {"red": "red.mdle"}, **top}
    if messages and "messages" not in top:
        data["messages"] = messages
    try:
        spec = parse_team(_yaml(data), str(tmp_path / "team.yaml"))
    except MdleError:
        return
    if spec.rate is not None:  # what was accepted is in range, as --rate is
        assert 0.001 <= spec.rate <= 1000


STUDY_KEYS = st.sampled_from(["rates", "seeds", "starts", "worlds", "duration", "parameters"])
PLAN = "atom follow(kf = 0.5) = (go(0.3 m/s), never, 1 s)\\n"


@settings(max_examples=examples(80), deadline=None)
@given(st.dictionaries(STUDY_KEYS, VALUES, max_size=3),
       st.sampled_from(["seeds", "starts.random", "parameters.random", "worlds.generated"]),
       NUMBERS)
def test_study_specs_parse_or_say_why_without_allocating_their_counts(
        top: dict[str, Any], counted: str, count: Any) -> None:
    from mdle.sweep import parse_study

    data: dict[str, Any] = {"plan": {"text": PLAN.replace("\\n", "\n")}, "entry": "follow",
                            **top}
    # one count always at a hostile size: it must be refused before anything is made
    if counted == "seeds":
        data["seeds"] = {"count": count}
    elif counted == "starts.random":
        data["starts"] = {"random": {"count": count}}
    elif counted == "parameters.random":
        data["parameters"] = {"random": {"count": count, "ranges": {"kf": [0.1, 1]}}}
    else:
        data["worlds"] = [{"generated": {"seed": 1, "count": count}}]
    try:
        study = parse_study(_yaml(data), file="s.yaml")
    except MdleError as err:
        assert err.diagnostics and err.diagnostics[0].message
        return
    assert study.size() <= 10_000_000
    assert all(0 <= s < 2**63 for s in study.seeds)
    assert all(0.001 <= r <= 1000 for r in study.rates)


STEPS = st.sampled_from(["a", "a + 1 cm", "a - 1 cm", "a * 2", "a * 3 + 1 cm", "-a",
                         "a * 0", "a + a", "2 * a - 1 cm"])


@settings(max_examples=examples(40), deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(steps=st.lists(st.tuples(STEPS, STEPS), min_size=1, max_size=30),
       default=st.sampled_from([" = 0 m", " = 1 m", ""]), used=st.booleans())
def test_parameterised_chains_check_within_the_budget(
        steps: list[tuple[str, str]], default: str, used: bool,
        monkeypatch: pytest.MonkeyPatch) -> None:
    from mdle.lang import load_text
    from mdle.lang.expansion import MAX_EXPANSION

    made = count_instances(monkeypatch)
    lines = [f"interrupt i0(a{default}) = range(0 deg) < a"]
    lines += [f"interrupt i{k}(a{default}) = i{k - 1}({x}) or i{k - 1}({y})"
              for k, (x, y) in enumerate(steps, 1)]
    if used:
        arg = "" if default else "(1 m)"
        lines.append(f"atom go1 = (go(0.3 m/s), i{len(steps)}{arg}, 5 s)")
    try:
        load_text("\n".join(lines) + "\n", "chain.mdle")
    except MdleError:
        pass
    # every instance but each definition's first costs at least two syntax nodes
    assert made[0] <= len(steps) + 2 + MAX_EXPANSION // 2, made[0]
