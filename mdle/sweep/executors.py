"""Where runs execute: local worker processes, or a Dask distributed cluster.

Both executors take an iterable of tasks (:class:`~mdle.sweep.tasks.RunTask`, or any
:class:`Task` with the function that runs it) and yield an
:class:`~mdle.sweep.worker.Outcome` per task as runs finish (any order). A task whose
worker is lost (the process died, the Dask worker vanished) is retried once, then
reported as a ``lost`` row. Closing the iterator early (Ctrl-C) cancels what has not
started and stops the workers.
"""

from __future__ import annotations

import os
import signal
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import replace
from typing import Any, Protocol

from mdle.core.errors import MdleError
from mdle.sweep.worker import Outcome, execute

__all__ = ["Executor", "LocalExecutor", "DaskExecutor", "Task", "lost_outcome", "default_jobs"]


class Task(Protocol):
    """What an executor runs: picklable, keyed by content, with its descriptive columns."""

    @property
    def key(self) -> str:
        """Return the hash of what decides the run's outcome."""
        ...

    @property
    def attempt(self) -> int:
        """Return 0 on the first try, 1 on the retry after a lost worker."""
        ...

    def row(self) -> dict[str, Any]:
        """Return the columns that describe the run (known before it runs)."""
        ...


class Executor(Protocol):
    """Runs tasks and yields their outcomes as they finish."""

    name: str

    def run(self, tasks: Iterable[Any]) -> Iterator[Outcome]:
        """Yield one outcome per task, as runs finish."""
        ...


def default_jobs() -> int:
    """Return the number of cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def lost_outcome(task: Task, why: str) -> Outcome:
    """Return the row of a run whose worker was lost on both attempts."""
    row = task.row()
    row.update(status="lost", cause=f"worker lost twice: {why}", attempts=task.attempt + 1)
    return Outcome(row)


def _process_state(pid: int) -> tuple[str, str] | None:
    """Return a process's state letter and start time from /proc, None when it is gone."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rpartition(")")[2].split()
    except OSError:
        return None
    return fields[0], fields[19]


def _worker_setup(sweep_pid: int) -> None:
    """Leave Ctrl-C to the sweep, and end this worker when the sweep process is gone.

    Ctrl-C reaches every process of the terminal's group: the sweep cancels and stops
    its workers itself. A sweep killed outright (SIGKILL) cannot: a watchdog thread ends
    the orphaned worker within half a second (a dead sweep may linger as a zombie, or its
    pid be reused: /proc tells both apart; elsewhere a signal 0 probe has to do).
    """
    import threading

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    first = _process_state(sweep_pid)

    def alive() -> bool:
        if first is None:
            try:
                os.kill(sweep_pid, 0)
            except OSError:
                return False
            return True
        now = _process_state(sweep_pid)
        return now is not None and now[0] not in ("Z", "X") and now[1] == first[1]

    def watch() -> None:
        while alive():
            time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, name="mdle-sweep-watchdog", daemon=True).start()


class LocalExecutor:
    """Run tasks in ``jobs`` worker processes on this machine.

    Workers start from a fork server that has already imported mdle, so a worker costs
    no import time and never inherits the parent's threads (the progress bar's).
    """

    name = "local"

    def __init__(self, jobs: int | None = None,
                 function: Callable[[Any], Outcome] = execute) -> None:
        self.jobs = max(1, jobs or default_jobs())
        self.function = function
        self._workers: dict[int, Any] = {}

    def worker_pids(self) -> list[int]:
        """Return the process ids of the live workers (for monitoring)."""
        return [pid for pid, p in dict(self._workers).items() if p.is_alive()]

    def start(self) -> None:
        """Start the fork server now: it imports mdle while the caller reads its study.

        Optional (:meth:`run` starts it otherwise). The server imports what a run needs
        (:mod:`mdle.sweep.preload`) once, before any worker forks from it, so no worker
        spends its first run importing: that would be paid once per worker, a part of
        the sweep that more workers do not shorten. The server is this process's own
        and outlives the executor (a later one reuses it).
        """
        import multiprocessing
        from multiprocessing import forkserver

        multiprocessing.get_context("forkserver").set_forkserver_preload(["mdle.sweep.preload"])
        forkserver.ensure_running()

    def _pool(self) -> Any:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        # started now, before the first submit holds signals while the server loads mdle
        self.start()
        return ProcessPoolExecutor(self.jobs, mp_context=multiprocessing.get_context("forkserver"),
                                   initializer=_worker_setup, initargs=(os.getpid(),))

    def run(self, tasks: Iterable[Any]) -> Iterator[Outcome]:
        """Yield outcomes as runs finish; retry a run once when its worker dies."""
        from concurrent.futures import FIRST_COMPLETED, Future, wait
        from concurrent.futures.process import BrokenProcessPool

        todo: Iterator[Any] = iter(tasks)
        retry: deque[Any] = deque()
        window = 2 * self.jobs          # few queued runs: Ctrl-C has little to cancel
        pool = self._pool()
        running: dict[Future[Outcome], Any] = {}
        try:
            while True:
                while len(running) < window:
                    task = retry.popleft() if retry else next(todo, None)
                    if task is None:
                        break
                    with _signals_held():  # a worker is started whole, or not at all
                        running[pool.submit(self.function, task)] = task
                        self._workers = getattr(pool, "_processes", None) or {}
                if not running:
                    return
                done, _ = wait(running, return_when=FIRST_COMPLETED)
                broken = False
                for fut in done:
                    task = running.pop(fut)
                    try:
                        yield fut.result()
                    except BrokenProcessPool:
                        broken = True
                        lost = self._again(task, retry, "the worker process died")
                        if lost is not None:
                            yield lost
                    except Exception as exc:  # the task could not be sent or returned
                        yield _failed(task, exc)
                if broken:
                    # Every run still on the broken pool is lost with it: retry them all.
                    for task in running.values():
                        lost = self._again(task, retry, "the worker process died")
                        if lost is not None:
                            yield lost
                    running.clear()
                    _stop(pool)
                    pool = self._pool()
        finally:
            _stop(pool)

    @staticmethod
    def _again(task: Any, retry: deque[Any], why: str) -> Outcome | None:
        if task.attempt == 0:
            retry.append(replace(task, attempt=1))
            return None
        return lost_outcome(task, why)


@contextmanager
def _signals_held() -> Iterator[None]:
    """Hold SIGINT, SIGTERM and SIGHUP for the block; the first one is raised after it.

    A submit may start a worker process. Interrupted halfway, the pool would not know the
    worker, could not stop it, and would let go of the queues it is still opening (it
    then prints multiprocessing's traceback). The handlers are swapped, not the signal
    mask: a signal sent to the process may land on any of its threads. Off the main
    thread (no handlers can be set there) the block runs as it is.
    """
    held = [s for s in (getattr(signal, n, None) for n in ("SIGINT", "SIGTERM", "SIGHUP"))
            if s is not None]
    came: list[int] = []

    def record(signum: int, frame: Any) -> None:
        came.append(signum)

    old: dict[int, Any] = {}
    try:
        for sig in held:
            old[sig] = signal.signal(sig, record)
    except ValueError:  # not the main thread
        pass
    try:
        yield
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)
        if came:
            signal.raise_signal(came[0])  # to the handler that was there before


def _failed(task: Task, exc: BaseException) -> Outcome:
    row = task.row()
    row.update(status="error", cause=f"internal error: {type(exc).__name__}: {exc}",
               attempts=task.attempt + 1)
    return Outcome(row)


def _stop(pool: Any) -> None:
    """Cancel what has not started and end the worker processes now."""
    workers = dict(getattr(pool, "_processes", None) or {})   # no public handle on them
    # The workers end before the pool lets its queues go: a worker still starting (an
    # interruption soon after the sweep began) would otherwise open a semaphore the pool
    # had just removed and print multiprocessing's traceback (SemLock._rebuild).
    for proc in workers.values():
        if proc.is_alive():
            proc.terminate()
    for proc in workers.values():
        proc.join(timeout=5)
    pool.shutdown(wait=False, cancel_futures=True)


class DaskExecutor:
    """Run tasks on a Dask distributed cluster (``pip install 'mdle[dask]'``).

    Parameters
    ----------
    cluster : str or distributed.Client or cluster object
        A scheduler address (``tcp://host:8786``), a client, or a cluster
        (``LocalCluster``). Workers need only mdle installed: tasks carry their texts.
    function : callable
        What runs a task (default :func:`mdle.sweep.worker.execute`).
    timeout : float
        How long to try to reach the scheduler, s.
    """

    name = "dask"

    def __init__(self, cluster: Any, function: Callable[[Any], Outcome] = execute,
                 timeout: float = 20.0) -> None:
        self.function = function
        try:
            import distributed
        except ImportError:

            raise MdleError("--dask needs dask.distributed: pip install 'mdle[dask]'") from None
        self._own = not isinstance(cluster, distributed.Client)
        if self._own:
            try:
                self.client = distributed.Client(cluster, timeout=f"{timeout}s")
            except (OSError, TimeoutError) as err:

                raise MdleError(f"--dask {cluster}: cannot reach the scheduler ({err})"
                                ) from None
        else:
            self.client = cluster

    def threads(self) -> int:
        """Return the cluster's total worker threads (at least 1)."""
        info = self.client.scheduler_info()
        return max(1, sum(w.get("nthreads", 1) for w in info.get("workers", {}).values()))

    def run(self, tasks: Iterable[Any]) -> Iterator[Outcome]:
        """Yield outcomes as runs finish; retry a run once when its worker is lost."""
        from distributed import KilledWorker, as_completed
        from distributed.comm.core import CommClosedError

        todo: Iterator[Any] = iter(tasks)
        window = 2 * self.threads() + 2
        running: dict[Any, Any] = {}
        done_stream = as_completed()

        def submit(task: Any) -> None:
            fut = self.client.submit(self.function, task, pure=False,
                                     key=f"mdle-run-{task.key}-{task.attempt}-{task.index}")
            running[fut] = task
            done_stream.add(fut)

        try:
            for task in todo:
                submit(task)
                if len(running) >= window:
                    break
            for fut in done_stream:
                task = running.pop(fut)
                if fut.status == "finished":
                    yield fut.result()
                elif not isinstance(exc := fut.exception(), (KilledWorker, CommClosedError)):
                    yield _failed(task, exc)     # the function raised: not a lost worker
                else:
                    why = f"{type(exc).__name__}: {exc}"
                    if task.attempt == 0:
                        submit(replace(task, attempt=1))
                    else:
                        yield lost_outcome(task, why)
                fut.release()
                nxt = next(todo, None)
                if nxt is not None:
                    submit(nxt)
        finally:
            if running:
                self.client.cancel(list(running))
            if self._own:
                self.client.close()
