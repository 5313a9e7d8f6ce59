"""Run one task wherever it lands and return its row: never raises for a failing run.

:func:`execute` is what local worker processes and Dask workers call. It loads the plan
from the task's texts, builds the world and robot from theirs, runs the plan on a
seeded :class:`sim.SimBackend` and measures it. A plan that does not check, a collision,
a fault or any error inside mdle becomes a row whose ``status`` and ``cause`` say so.
"""

from __future__ import annotations

import gzip
import math
import os
import socket
import tempfile
import time
import traceback
from dataclasses import dataclass
from typing import Any

from mdle.core.errors import MdleError
from mdle.sim import SimBackend
from mdle.sweep.spec import SAMPLE_FIELDS
from mdle.sweep.tasks import RunTask

__all__ = ["Outcome", "execute", "STATUSES"]

#: What ``status`` can say: ran cleanly, collided, failed (cause in ``cause``), or its
#: worker was lost twice.
STATUSES = ("ok", "collision", "error", "lost")


@dataclass(frozen=True)
class Outcome:
    """A finished run: its table row and, on request, its gzipped JSON-lines trace."""

    row: dict[str, Any]
    trace: bytes | None = None


def execute(task: RunTask) -> Outcome:
    """Run ``task`` and measure it; every failure is reported in the row, not raised."""
    start, cpu = time.perf_counter(), time.process_time()
    row = task.row()
    trace: bytes | None = None
    try:
        metrics, trace = _run(task)
        row.update(metrics)
    except Exception as exc:  # a run's failure is a row, never the end of the sweep

        row["status"] = "error"
        if isinstance(exc, MdleError):
            row["cause"] = " / ".join(d.message for d in exc.diagnostics[:3])
        else:
            where = traceback.extract_tb(exc.__traceback__)[-1:]
            at = f" at {os.path.basename(where[0].filename)}:{where[0].lineno}" if where else ""
            row["cause"] = f"internal error: {type(exc).__name__}: {exc}{at}"
    row["attempts"] = task.attempt + 1
    row["worker"] = f"{socket.gethostname()}:{os.getpid()}"
    row["wall_time"] = time.perf_counter() - start
    row["cpu_time"] = time.process_time() - cpu
    return Outcome(row, trace)


def _world(task: RunTask) -> Any:
    from mdle.sweep.worlds import build_world

    return build_world(task.world_text, task.labels.get("world", "world"), task.robot)


def _run(task: RunTask) -> tuple[dict[str, Any], bytes | None]:
    import numpy as np

    from mdle.core.pose import Pose
    from mdle.lang import load_text
    from mdle.runtime import run
    from mdle.runtime.api import element_of
    from mdle.runtime.observer import Recorder
    from mdle.sweep.metrics import field_summary, follow_atoms, follow_metrics

    program = load_text(task.plan_text, task.labels.get("plan", "<plan>"),
                        settings=dict(task.settings), files=dict(task.plan_files),
                        base_dir="/")
    element = element_of(program, task.entry)
    world = _world(task)
    backend = SimBackend(world, seed=task.seed, sensing=task.sensing)
    if task.pose is not None:
        backend.reset(Pose(*task.pose))
    recorder = Recorder()
    observers: list[Any] = [recorder]
    tmp = None
    if task.keep_trace:
        from mdle.record.trace import TraceWriter

        tmp = tempfile.NamedTemporaryFile(prefix="mdle-sweep-", suffix=".jsonl", delete=False)
        tmp.close()
        header = {"program": {"file": task.labels.get("plan", ""), "element": element.label},
                  "world": {"name": world.name}, "seed": task.seed, "rate": task.rate,
                  "sensing": task.sensing, "settings": dict(task.settings), "key": task.key}
        observers.append(TraceWriter(tmp.name, header, flush_period=0.0))
    try:
        result = run(element, backend, rate=task.rate, until=task.until, observers=observers)
    finally:
        backend.close()
        trace = None
        if tmp is not None:
            for o in observers[1:]:
                o.close()
            with open(tmp.name, "rb") as f:
                trace = gzip.compress(f.read())
            os.unlink(tmp.name)
    samples = recorder.samples
    status = ("collision" if result.collided else
              "error" if result.fault is not None or result.cause.value == "error" else "ok")
    out: dict[str, Any] = {
        "status": status, "ended": result.cause.value,
        "cause": "; ".join(w for w in ("the robot collided" if result.collided else "",
                                       result.fault or "") if w),
        "duration": result.duration, "collided": bool(result.collided),
        "collisions": sum(e.kind == "collision" for e in backend.events),
        "min_clearance": result.min_clearance, "distance": None, "ticks": result.ticks,
    }
    if samples:
        tx = np.array([s.true_x for s in samples], dtype=float)
        ty = np.array([s.true_y for s in samples], dtype=float)
        th = np.array([s.true_theta for s in samples], dtype=float)
        t = np.array([s.time for s in samples], dtype=float)
        out["distance"] = float(np.sum(np.hypot(np.diff(tx), np.diff(ty))))
        specs = follow_atoms(element)
        if specs:
            rc = np.array([specs[s.path].rc if s.path in specs else math.nan
                           for s in samples])
            right = np.array([specs[s.path].side == "right" if s.path in specs else True
                              for s in samples])
            following = np.isfinite(rc)
            near = world.nearest_boundary(np.column_stack((tx, ty)))
            clear = np.array([math.nan if s.clearance is None else s.clearance
                              for s in samples], dtype=float)
            out.update(follow_metrics(t, tx, ty, th, np.asarray(near.distance, dtype=float),
                                      np.asarray(near.point, dtype=float).reshape(-1, 2),
                                      clear, rc, right, following))
    out.update(field_summary(samples, task.trace_fields, SAMPLE_FIELDS))
    return out, trace
