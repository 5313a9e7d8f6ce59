"""The REPL without a terminal: input piped from a file, a here-document or a test.

Lines are read plainly (no line editing, no colours, no control codes); an input goes on
over several lines until it is complete, as at the prompt. A line that is not UTF-8 text
is reported (with its number) and skipped; the session goes on. The exit code is 0 when every
input succeeded and 1 when any failed (a bad definition, an unknown name, a run that
collided, an input left unfinished at the end), so a session can be scripted::

    mdle repl --world ellipse < tune.txt
"""

from __future__ import annotations

from typing import IO

from mdle.repl.commands import Repl

__all__ = ["CONTINUATION", "PROMPT", "run_plain"]

PROMPT = "mdle> "
CONTINUATION = "  ... "


def run_plain(repl: Repl, stream: IO[str], *, echo: bool = False) -> int:
    """Read inputs from ``stream`` until its end or ``:quit``; returns the exit code.

    Parameters
    ----------
    repl : Repl
    stream : text stream
        Where the inputs come from.
    echo : bool
        Print each input after the prompt, so the output reads as a transcript.
    """
    buffer: list[str] = []
    for number, line in enumerate(stream, 1):
        line = line.rstrip("\r\n")
        bad = _undecodable(line)
        if bad is not None:  # bytes that are not UTF-8 (kept as surrogates): skip the line
            repl.complain(f"input line {number} is not UTF-8 text (byte 0x{bad[1]:02x} at "
                          f"column {bad[0] + 1}); the line is skipped")
            repl.failures += 1
            continue
        if echo:
            repl.say((CONTINUATION if buffer else PROMPT) + line)
        buffer.append(line)
        text = "\n".join(buffer)
        if not repl.is_complete(text):
            continue
        buffer = []
        repl.handle(text)
        if repl.quit_requested:
            break
    if buffer and any(b.strip() for b in buffer):
        repl.complain("the input ended in the middle of an unfinished statement",
                      hint="close its brackets, or remove the trailing `=`, comma or operator")
        repl.failures += 1
    return 1 if repl.failures else 0


def _undecodable(line: str) -> tuple[int, int] | None:
    """(column, byte) of the first byte that was not UTF-8, None for clean text.

    The stream decodes with ``surrogateescape``, which turns each such byte into a lone
    surrogate U+DC80..U+DCFF.
    """
    for i, ch in enumerate(line):
        if "\udc80" <= ch <= "\udcff":
            return i, ord(ch) - 0xDC00
    return None
