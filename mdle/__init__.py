"""mdle: an interpreter for MDLe, the extended Motion Description Language.

Text flows one way: ``.mdle`` source -> syntax tree -> checked program -> runtime ->
backend (simulated or real robot), with events out to traces and plots. Heavy
modules (numpy, shapely, matplotlib) are imported lazily by the stages that need them,
so ``mdle check`` starts fast.

The names in :data:`__all__` are the public API, what the README and the docs use:

>>> import mdle
>>> program = mdle.load_text("atom go1 = (go(0.5 m/s), never, 2 s)", "<example>")
>>> backend = mdle.SimBackend(mdle.load_world("empty"), seed=1)
>>> result = mdle.run_named(program, "go1", backend, rate=10)
>>> mdle.ended_how(result.termination.cause), result.termination.time
('ended by timer', 2.0)

Each name is imported from its module on first use (module ``__getattr__``): every
command imports this package, and ``mdle check`` would otherwise load the runtime, the
simulator's numpy and the drivers for a name it never reads.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from mdle.atoms import default_registry
    from mdle.atoms.registry import Context, Param, control_law, sensor
    from mdle.core.backend import STOP, Backend, ClockMode, Command, Observation, RobotLimits, Scan
    from mdle.core.errors import CheckError, MdleError
    from mdle.core.pose import Pose
    from mdle.drivers import open_backend
    from mdle.lang import Program, format_source, load_program, load_text, show_program
    from mdle.record.load import read_trace
    from mdle.record.trace import Trace, TraceWriter
    from mdle.runtime import (
        BaseObserver,
        Cause,
        RunResult,
        Sample,
        Scheduler,
        element_of,
        ended_how,
        run,
        run_named,
    )
    from mdle.sim import SimBackend, World, list_worlds, load_world

__version__ = "0.1.0"

__all__ = [
    "__version__",
    # the language
    "load_program",
    "load_text",
    "Program",
    "format_source",
    "show_program",
    "CheckError",
    "MdleError",
    # running a program
    "run",
    "run_named",
    "element_of",
    "ended_how",
    "Cause",
    "Scheduler",
    "RunResult",
    "Sample",
    "BaseObserver",
    # the seam to a robot
    "Backend",
    "Observation",
    "Scan",
    "Pose",
    "Command",
    "STOP",
    "RobotLimits",
    "ClockMode",
    # the simulator and real robots
    "SimBackend",
    "World",
    "load_world",
    "list_worlds",
    "open_backend",
    # traces
    "read_trace",
    "Trace",
    "TraceWriter",
    # control laws and sensor functions
    "control_law",
    "sensor",
    "Param",
    "Context",
    "default_registry",
]

#: The module each public name is imported from.
_HOME = {
    "load_program": "mdle.lang", "load_text": "mdle.lang", "Program": "mdle.lang",
    "format_source": "mdle.lang", "show_program": "mdle.lang",
    "CheckError": "mdle.core.errors", "MdleError": "mdle.core.errors",
    "run": "mdle.runtime", "run_named": "mdle.runtime", "element_of": "mdle.runtime",
    "ended_how": "mdle.runtime", "Cause": "mdle.runtime", "Scheduler": "mdle.runtime",
    "RunResult": "mdle.runtime", "Sample": "mdle.runtime", "BaseObserver": "mdle.runtime",
    "Backend": "mdle.core.backend", "Observation": "mdle.core.backend", "Scan": "mdle.core.backend",
    "Pose": "mdle.core.pose", "Command": "mdle.core.backend", "STOP": "mdle.core.backend",
    "RobotLimits": "mdle.core.backend", "ClockMode": "mdle.core.backend",
    "SimBackend": "mdle.sim", "World": "mdle.sim", "load_world": "mdle.sim",
    "list_worlds": "mdle.sim", "open_backend": "mdle.drivers",
    "read_trace": "mdle.record.load", "Trace": "mdle.record.trace",
    "TraceWriter": "mdle.record.trace",
    "control_law": "mdle.atoms.registry", "sensor": "mdle.atoms.registry",
    "Param": "mdle.atoms.registry", "Context": "mdle.atoms.registry",
    "default_registry": "mdle.atoms",
}


def __getattr__(name: str) -> Any:
    """Import a public name from its module on first use (see the module's docstring)."""
    home = _HOME.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(home), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """List the public names as well as those already imported."""
    return sorted(set(globals()) | set(__all__))
