"""The grammar is MDLe's only syntax definition: the words and precedence elsewhere are its own.

Keywords, statement keywords and operators are read from lark's objects of
``grammar/mdle.lark`` (:mod:`mdle.lang.vocabulary`); the precedence table of the tree
builder is checked here against the grammar's order; the parser's tables are cached per
user, and a cache that is corrupt, stale or unwritable changes nothing but speed.
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import re
from collections.abc import Iterator
from pathlib import Path

import pytest

from mdle.core.units import UNITS
from mdle.lang import load_text
from mdle.lang import syntax as st
from mdle.lang.check_structure import _replaced
from mdle.lang.parser import parse_expression, parse_module
from mdle.lang.program import AtomNode
from mdle.lang.syntax_errors import EXAMPLES, terminal_words
from mdle.lang.treebuild import POWERS, PREFIX_POWERS, lark_parser
from mdle.lang.vocabulary import (
    binary_operators,
    definition_keywords,
    keywords,
    operator_keywords,
    prefix_operators,
    statement_keywords,
)
from mdle.repl.commands import DEFINITION_KEYWORDS, KEYWORDS, classify
from mdle.repl.highlight import MdleLexer

GRAMMAR = importlib.resources.files("mdle.grammar").joinpath("mdle.lark").read_text("utf-8")


def _grammar_keywords() -> set[str]:
    """The words of the grammar's string terminals that are words (read from its text)."""
    return {m.group(1) for m in re.finditer(r'^[A-Z_]+:\s*"([A-Za-z_]+)"\s*$', GRAMMAR, re.M)}


def test_keywords_are_the_grammar_s_word_terminals() -> None:
    assert set(keywords()) == _grammar_keywords()
    assert set(keywords()) >= {"atom", "run", "never", "xor"}
    # each keyword is lexed as its own terminal wherever it stands
    for word, terminal in keywords().items():
        (token,) = list(lark_parser().lex(word))
        assert token.type == terminal


def test_the_number_pattern_refuses_every_keyword_as_a_unit() -> None:
    # NUMBER's pattern holds its own copy of the keyword list (a unit is any word that is
    # not a keyword); it must be the grammar's list, no more, no less.
    (listed,) = re.findall(r"\(\?!\(\?:([a-z|]+)\)", GRAMMAR)
    assert set(listed.split("|")) == set(keywords())


def test_the_number_pattern_joins_the_unit_table_s_units_after_a_spaced_slash() -> None:
    # `0.3 m / s` is a unit only when a unit of the table follows the spaced `/`; the
    # pattern lists those units itself, and they must be the table's.
    (listed,) = re.findall(r"\\/\[ \\t\]\*\(\?:([a-z|]+)\)", GRAMMAR)
    assert set(listed.split("|")) == set(UNITS)


def test_statement_and_definition_keywords() -> None:
    assert definition_keywords() == tuple(k.value for k in st.DefKind)
    assert set(statement_keywords()) == set(definition_keywords()) | {"import", "run"}
    assert statement_keywords()[:len(definition_keywords())] == definition_keywords()
    # the one message that lists them in its text lists exactly these
    label = next(lb for lb in EXAMPLES if lb.message.startswith("expected a statement"))
    assert re.findall(r"`([a-z]+)`", label.message) == list(statement_keywords())


def test_precedence_follows_the_grammar() -> None:
    binary = binary_operators()
    assert set(POWERS) == set(binary)
    assert sorted(binary, key=POWERS.__getitem__) == list(binary)  # listed loosest first
    assert len(set(POWERS.values())) == len(POWERS)
    assert set(PREFIX_POWERS) == set(prefix_operators()) == {"NOT", "ADD_OP"}
    # `not` between `and` and the comparisons, a sign above every binary operator
    assert POWERS["AND"] < PREFIX_POWERS["NOT"] < POWERS["COMPARE"]
    assert PREFIX_POWERS["ADD_OP"] > max(POWERS.values())


def test_precedence_as_parsed() -> None:
    e = parse_expression("not x < 1 m and - y * 2 > 0 m or z")
    assert isinstance(e, st.Binary) and e.op == "or"
    conj = e.left
    assert isinstance(conj, st.Binary) and conj.op == "and"
    assert isinstance(conj.left, st.Unary) and conj.left.op == "not"
    assert isinstance(conj.left.operand, st.Binary) and conj.left.operand.op == "<"
    right = conj.right
    assert isinstance(right, st.Binary) and right.op == ">"
    assert isinstance(right.left, st.Binary) and right.left.op == "*"
    assert isinstance(right.left.left, st.Unary) and right.left.left.op == "-"


def test_every_terminal_has_words() -> None:
    terminals = {t.name for t in lark_parser().terminals} - {"COMMENT", "WHITESPACE"}
    words = terminal_words()
    assert terminals <= set(words)
    assert all(words[keywords()[k]] == f"`{k}`" for k in keywords())


def test_the_repl_uses_the_grammar_s_words() -> None:
    assert DEFINITION_KEYWORDS == statement_keywords()
    assert set(KEYWORDS) == set(keywords())
    assert set(operator_keywords()) == {"and", "or", "xor", "not"}
    assert classify("interrupt far = x > 1 m") == "definition"
    assert classify("interrupted") == "element"
    kinds = {text: str(kind) for kind, text in MdleLexer().get_tokens(
        "plan p = (a, never and not b, inf)")}
    assert kinds["plan"] == "Token.Keyword.Declaration"
    assert kinds["never"] == kinds["inf"] == "Token.Keyword.Constant"
    assert kinds["and"] == kinds["not"] == "Token.Operator.Word"


def test_a_misspelt_field_of_a_copied_node_is_an_error() -> None:
    program = load_text("atom a = (go(0.2 m/s), never, 2 s)\nrun a\n")
    node = program.elements["a"]
    assert isinstance(node, AtomNode)
    assert _replaced(node, timer=5.0).timer == 5.0
    assert _replaced(node, timer=5.0) == dataclasses.replace(node, timer=5.0)
    with pytest.raises(TypeError, match="timr"):
        _replaced(node, timr=5.0)


PLAN = "atom a = (go(0.2 m/s), x > 1 m, 2 s)\nrun a\n"


def _fresh_parser(monkeypatch: pytest.MonkeyPatch, cache: Path) -> None:
    """Make the next parse build (or load) the parser with ``cache`` as the user's cache."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(cache))
    lark_parser.cache_clear()


@pytest.fixture
def own_parser() -> Iterator[None]:
    """Forget the test's parser after it: the next test builds one from the user's cache."""
    yield None
    lark_parser.cache_clear()


@pytest.mark.parametrize("damage", ["corrupt", "truncated", "stale"])
def test_a_damaged_cache_is_rebuilt(own_parser: None, monkeypatch: pytest.MonkeyPatch,
                                    tmp_path: Path, damage: str) -> None:
    _fresh_parser(monkeypatch, tmp_path)
    good = parse_module(PLAN, "f.mdle")
    (cache,) = (tmp_path / "mdle").iterdir()
    data = cache.read_bytes()
    cache.write_bytes({"corrupt": b"\x00garbage\n" + bytes(range(256)),
                       "truncated": data[:len(data) // 2],
                       "stale": b"0" * 64 + b"\n" + data.split(b"\n", 1)[1]}[damage])
    _fresh_parser(monkeypatch, tmp_path)
    assert parse_module(PLAN, "f.mdle").statements == good.statements
    rewritten = cache.read_bytes()  # written again, whole (pickles differ run to run)
    assert rewritten.split(b"\n", 1)[0] == data.split(b"\n", 1)[0]
    _fresh_parser(monkeypatch, tmp_path)
    assert parse_module(PLAN, "f.mdle").statements == good.statements
    assert cache.read_bytes() == rewritten  # loaded, not built again


def test_an_unwritable_cache_folder_is_only_slower(own_parser: None,
                                                   monkeypatch: pytest.MonkeyPatch,
                                                   tmp_path: Path) -> None:
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    _fresh_parser(monkeypatch, blocked)  # `mdle` cannot be made inside a file
    assert [type(s) for s in parse_module(PLAN, "f.mdle").statements] == [st.Definition, st.Run]
