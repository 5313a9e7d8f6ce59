"""YAML documents read with limits, remembering where each key path starts.

Every YAML input (world files, robot files, study specs, team files) is read by
:func:`_yaml_value` into plain Python values through :class:`_Builder`: ``yaml`` safe
loading only, nesting refused past :data:`MAX_YAML_DEPTH`, aliases shared rather than
copied. :class:`_Doc` keeps each key path's line and column, so a problem found later
is reported as a :class:`mdle.core.errors.WorldError` naming the file, line, column and path.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

from mdle.core.collector import collector_paused
from mdle.core.errors import Diagnostic, Span, WorldError

__all__ = ["MAX_YAML_DEPTH"]

#: Deepest nesting of lists and mappings in a world file (a world needs about 5).
MAX_YAML_DEPTH = 64


@dataclass
class _Doc:
    """The YAML text, its file name, and where each key path starts."""

    file: str
    text: str
    marks: dict[str, tuple[int, int, int]] = field(default_factory=dict)

    def fail(self, path: str, problem: str) -> WorldError:
        where = self.marks.get(path)
        probe = path
        while where is None and probe:   # fall back to the nearest enclosing key
            probe = probe.rpartition(".")[0] if "." in probe else (
                probe.rpartition("[")[0] if "[" in probe else "")
            where = self.marks.get(probe)
        span = None
        if where is not None:
            line, col, width = where
            span = Span(self.file, line, col, line, col + max(1, width))
        elif self.file:
            span = Span(self.file, 1, 1, 1, 1)
        msg = f"{path}: {problem}" if path and not path.startswith("<") else problem
        return WorldError(Diagnostic(span, msg), sources={self.file: self.text})


_STR_TAG = "tag:yaml.org,2002:str"
_YAML_INT = re.compile(r"[-+]?(?:0|[1-9][0-9]*)")
_YAML_FLOAT = re.compile(r"[-+]?(?:[0-9]+\.[0-9]*|\.[0-9]+)(?:[eE][-+][0-9]+)?")


def _events(text: str, fast: bool = True) -> Any:
    """Return the YAML event stream (libyaml's C parser when installed and ``fast``)."""
    import yaml

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader) if fast else yaml.SafeLoader
    return yaml.parse(text, Loader=loader)


class _Builder:
    """YAML events to Python values, with each key path's position recorded.

    Built from the event stream with an explicit stack (no recursion), so nesting is
    refused at the first level past :data:`MAX_YAML_DEPTH` instead of exhausting a
    stack. An alias is the very object its anchor made, never a copy, so aliases of
    aliases ("billion laughs") cost nothing; an alias of an anchor still open (a value
    containing itself) is refused. Plain numbers take a fast path; every other scalar is
    resolved and constructed by PyYAML's safe loader, as ``yaml.safe_load`` would.
    """

    def __init__(self, doc: _Doc, only: frozenset[str] | None = None) -> None:
        import yaml

        self.doc = doc
        # top-level keys whose values are built (None: all); the others are only parsed
        self.only = only
        self.skipped: set[str] = set()   # anchors inside values not built
        self.resolver = yaml.SafeLoader("")
        self.anchors: dict[str, Any] = {}
        self.open: set[str] = set()

    def fail_at(self, mark: Any, problem: str) -> WorldError:
        self.doc.marks["<yaml>"] = (mark.line + 1, mark.column + 1, 1)
        return self.doc.fail("<yaml>", problem)

    def scalar(self, ev: Any, path: str) -> Any:
        import yaml

        value = ev.value
        if ev.implicit[0] and ev.tag is None:
            if _YAML_INT.fullmatch(value):
                try:
                    return int(value)
                except ValueError as err:  # more digits than Python converts
                    raise self.doc.fail(path, f"cannot read the value: {err}") from None
            if _YAML_FLOAT.fullmatch(value):
                return float(value)
        tag = ev.tag
        if tag is None or tag == "!":
            tag = self.resolver.resolve(yaml.ScalarNode, value, ev.implicit)
            if tag == _STR_TAG:   # text (keys, `circle`): the loader would return it as is
                return value
        node = yaml.ScalarNode(tag, value, ev.start_mark, ev.end_mark, ev.style)
        try:
            return self.resolver.construct_object(node, deep=True)
        except (ValueError, OverflowError) as err:  # e.g. an integer of 5,000 digits
            raise self.doc.fail(path, f"cannot read the value: {err}") from None

    def build(self, events: Any) -> Any:
        """Return the document's value (None for an empty document)."""
        import yaml

        doc = self.doc
        marks = doc.marks
        # each open container: [value, path, start mark, anchor, pending key, key mark]
        stack: list[list[Any]] = []
        result: Any = None
        done = False
        scalar_event = yaml.ScalarEvent
        events = iter(events)
        for ev in events:
            # the common case first: a number in a list (the points of a polygon)
            if type(ev) is scalar_event and stack and ev.anchor is None \
                    and type(stack[-1][0]) is list:
                seq, where = stack[-1][0], stack[-1][1]
                path = f"{where}[{len(seq)}]"
                m, e = ev.start_mark, ev.end_mark
                marks[path] = (m.line + 1, m.column + 1,
                               max(1, e.index - m.index) if e.line == m.line else 1)
                seq.append(self.scalar(ev, path))
                continue
            if isinstance(ev, (yaml.StreamStartEvent, yaml.StreamEndEvent,
                               yaml.DocumentEndEvent)):
                continue
            if isinstance(ev, yaml.DocumentStartEvent):
                if done:
                    raise self.fail_at(ev.start_mark, "a world file holds one YAML document, "
                                                      "found a second")
                continue
            if isinstance(ev, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
                value, path, start, anchor, _, _ = stack.pop()
                end = ev.end_mark
                width = end.index - start.index if end.line == start.line else 1
                marks[path] = (start.line + 1, start.column + 1, max(1, width))
                if anchor is not None:
                    self.open.discard(anchor)
                    self.anchors[anchor] = value
                self._place(stack, value, path)
                if not stack:
                    result, done = value, True
                continue
            # a node: where does it go?
            top = stack[-1] if stack else None
            if self.only is not None and len(stack) == 1 and top is not None \
                    and top[4] is not _NO_KEY and top[4] not in self.only:
                self._skip(ev, events)
                self._place(stack, None, f"{top[4]}")
                continue
            if top is None:
                path = ""
            elif isinstance(top[0], list):
                path = f"{top[1]}[{len(top[0])}]" if top[1] else f"[{len(top[0])}]"
            elif top[4] is _NO_KEY:
                path = "<key>"
            else:
                path = f"{top[1]}.{top[4]}" if top[1] else str(top[4])
            if isinstance(ev, yaml.AliasEvent):
                if ev.anchor in self.open:
                    marks.setdefault(path, (ev.start_mark.line + 1, ev.start_mark.column + 1,
                                            1))
                    raise doc.fail(path, f"the alias `*{ev.anchor}` refers to itself (it "
                                         "stands inside its own anchor)")
                if ev.anchor in self.skipped:
                    raise _Unskip
                if ev.anchor not in self.anchors:
                    raise self.fail_at(ev.start_mark, f"not valid YAML: unknown alias "
                                                      f"`*{ev.anchor}`")
                value = self.anchors[ev.anchor]
            elif isinstance(ev, yaml.ScalarEvent):
                m, e = ev.start_mark, ev.end_mark
                marks[path] = (m.line + 1, m.column + 1,
                               max(1, e.index - m.index) if e.line == m.line else 1)
                value = self.scalar(ev, path)
                if ev.anchor is not None:
                    self.anchors[ev.anchor] = value
            else:  # a mapping or sequence starts
                if len(stack) >= MAX_YAML_DEPTH:
                    raise self.fail_at(ev.start_mark, f"the YAML nests more than "
                                                      f"{MAX_YAML_DEPTH} levels deep here; a "
                                                      "world needs a handful")
                marks[path] = (ev.start_mark.line + 1, ev.start_mark.column + 1, 1)
                if ev.anchor is not None:
                    self.open.add(ev.anchor)
                container: Any = [] if isinstance(ev, yaml.SequenceStartEvent) else {}
                stack.append([container, path, ev.start_mark, ev.anchor, _NO_KEY, None])
                continue
            if path == "<key>":
                assert top is not None
                self._key(top, value, (ev.start_mark.line + 1, ev.start_mark.column + 1))
                continue
            self._place(stack, value, path)
            if not stack:
                result, done = value, True
        return result

    def _skip(self, ev: Any, events: Any) -> None:
        """Read past one top-level value (``ev`` its first event) without building it.

        Its YAML is still parsed and its nesting still limited.
        """
        import yaml

        level = 0
        while True:
            if not isinstance(ev, yaml.AliasEvent) and getattr(ev, "anchor", None) is not None:
                self.skipped.add(ev.anchor)
            if isinstance(ev, (yaml.SequenceStartEvent, yaml.MappingStartEvent)):
                level += 1
                if 1 + level > MAX_YAML_DEPTH:
                    raise self.fail_at(ev.start_mark, f"the YAML nests more than "
                                                      f"{MAX_YAML_DEPTH} levels deep here; a "
                                                      "world needs a handful")
            elif isinstance(ev, (yaml.SequenceEndEvent, yaml.MappingEndEvent)):
                level -= 1
            if level == 0:
                return
            ev = next(events)

    def _key(self, top: list[Any], key: Any, km: tuple[int, int]) -> None:
        import reprlib

        doc = self.doc
        if not isinstance(key, str):
            doc.marks["<key>"] = (*km, 1)
            where = f"in `{top[1]}`: " if top[1] else ""
            short = reprlib.Repr()
            short.maxlevel, short.maxlist, short.maxdict, short.maxstring = 2, 4, 4, 40
            raise doc.fail("<key>", f"{where}keys must be names, got {short.repr(key)}")
        sub = f"{top[1]}.{key}" if top[1] else key
        if key in top[0]:
            doc.marks[sub] = (*km, len(key))
            raise doc.fail(sub, "key given twice")
        doc.marks.setdefault(sub + "#key", (*km, len(key)))
        top[4], top[5] = key, km

    def _place(self, stack: list[list[Any]], value: Any, path: str) -> None:
        if not stack:
            return
        top = stack[-1]
        if isinstance(top[0], list):
            top[0].append(value)
        elif top[4] is _NO_KEY:  # a mapping or sequence where a key belongs
            line, column, _ = self.doc.marks.get(path, (1, 1, 1))
            self._key(top, value, (line, column))
        else:
            top[0][top[4]] = value
            top[4] = _NO_KEY


_NO_KEY = object()


class _Unskip(Exception):
    """A built value refers to an anchor inside a value that was not built."""


def _yaml_value(doc: _Doc, only: frozenset[str] | None = None) -> Any:
    """Return the value of a YAML document (None if empty); WorldError on bad YAML.

    Also used by other YAML inputs (study specs), so they get the same limits. With
    ``only``, a top-level mapping's other keys hold None: their values are parsed but not
    built (reading a world's robot need not build 200,000 obstacles).
    """
    import yaml

    try:
        with collector_paused():  # plain lists and dicts that live on
            try:
                data = _Builder(doc, only).build(_events(doc.text))
            except _Unskip:   # an alias into a value skipped: build everything
                data = _Builder(doc).build(_events(doc.text))
    except yaml.MarkedYAMLError as fast:
        # libyaml words some errors differently: the pure-Python parser's words are the
        # documented ones (the parse is redone only on this error path)
        err = fast
        try:
            for _ in _events(doc.text, fast=False):
                pass
        except yaml.MarkedYAMLError as slow:
            err = slow
        except yaml.YAMLError:
            pass
        mark = err.problem_mark or err.context_mark
        line, col = (mark.line + 1, mark.column + 1) if mark else (1, 1)
        doc.marks["<yaml>"] = (line, col, 1)
        problem = err.problem or err.context or "malformed YAML"
        raise doc.fail("<yaml>", f"not valid YAML: {problem}") from None
    except yaml.YAMLError as err:
        raise doc.fail("", f"not valid YAML: {err}") from None
    return data
