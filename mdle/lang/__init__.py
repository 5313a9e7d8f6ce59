"""The MDLe language: text to a checked program, and a checked program back to text.

Everything outside this package (runtime, REPL, CLI, experiments, sweeps, teams) imports
the language from here, never from its modules, so the modules can be reorganised freely.

Inside, the stages run one way: :mod:`~mdle.lang.parser` (text to the syntax tree of
:mod:`~mdle.lang.syntax`, built by :mod:`~mdle.lang.treebuild` as lark parses; the
grammar's words for messages and the REPL from :mod:`~mdle.lang.vocabulary`),
:mod:`~mdle.lang.resolve` (one namespace), the checker (:mod:`~mdle.lang.check`: names,
dimensions, structure) building the program IR of :mod:`~mdle.lang.program`, and
:mod:`~mdle.lang.loader` tying files and imports together. :mod:`~mdle.lang.format` and
:mod:`~mdle.lang.show` turn trees and programs back into text; :mod:`~mdle.lang.workspace`
is the REPL's incremental program.
"""

from __future__ import annotations

from mdle.lang.check import check_program, missing_entry
from mdle.lang.dimensions import Quantity, dim_words, same_kind, show_value
from mdle.lang.format import format_source, format_statement
from mdle.lang.hints import yaml_as_plan
from mdle.lang.loader import Loaded, load_program, load_text, plan_bundle, read_source
from mdle.lang.parser import parse_expression, parse_module
from mdle.lang.program import (
    INF,
    NEVER,
    AtomNode,
    Element,
    Interrupt,
    LiveArg,
    LiveArgs,
    MessageUse,
    Program,
    Send,
    StringKind,
    StringNode,
)
from mdle.lang.show import show_program, structure
from mdle.lang.syntax import DefKind
from mdle.lang.vocabulary import keywords, operator_keywords, statement_keywords
from mdle.lang.workspace import Workspace

__all__ = [
    "INF",
    "NEVER",
    "AtomNode",
    "DefKind",
    "Element",
    "Interrupt",
    "LiveArg",
    "LiveArgs",
    "Loaded",
    "MessageUse",
    "Program",
    "Quantity",
    "Send",
    "StringKind",
    "StringNode",
    "Workspace",
    "check_program",
    "dim_words",
    "format_source",
    "format_statement",
    "keywords",
    "load_program",
    "load_text",
    "missing_entry",
    "operator_keywords",
    "parse_expression",
    "parse_module",
    "plan_bundle",
    "read_source",
    "same_kind",
    "show_program",
    "statement_keywords",
    "show_value",
    "structure",
    "yaml_as_plan",
]
