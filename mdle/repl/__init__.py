"""``mdle repl``: compose MDLe atoms and try them on a simulated robot, interactively.

* :mod:`mdle.repl.session`: the state (definitions, robot, path, trace) and what it can do;
* :mod:`mdle.repl.reports`: the records it returns (run reports, ``:step`` rows, loaded runs);
* :mod:`mdle.repl.runs`: each run's recorder, and the runs since a reset written as one trace;
* :mod:`mdle.repl.commands`: the interpreter of one input (definition, element, ``:`` command);
* :mod:`mdle.repl.views`: the text it prints (run reports, scan, map, ticks);
* :mod:`mdle.repl.prompt`: the prompt_toolkit front end (history, completion, highlighting),
  with :mod:`mdle.repl.completion` and :mod:`mdle.repl.highlight`;
* :mod:`mdle.repl.plain`: the front end for piped input (scripts, tests).
"""

from __future__ import annotations

from mdle.repl.commands import COMMANDS, Repl
from mdle.repl.reports import RunReport
from mdle.repl.session import DEFAULT_UNTIL, Session

__all__ = ["COMMANDS", "DEFAULT_UNTIL", "Repl", "RunReport", "Session"]
