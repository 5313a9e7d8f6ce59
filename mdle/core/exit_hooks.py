"""A robot backend's hooks that stop the robot however the program ends.

A backend that can move a real robot (the Pioneer over ARCOS, a ROS 2 robot) registers these
once the motors may move: at interpreter exit it is closed (which stops the robot), and an
unhandled SIGTERM becomes ``SystemExit(143)``, so that ``finally`` blocks run and stop it.
"""

from __future__ import annotations

import atexit
import signal
import threading
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from types import FrameType
from typing import Any, Protocol

__all__ = ["ClosableRobot", "ExitHooks", "register_exit_hooks"]


class ClosableRobot(Protocol):
    """What the hooks need of a backend: whether it is closed, and a way to close it."""

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` has run."""

    def close(self) -> None:
        """Stop the robot and let go of it."""


@dataclass
class ExitHooks:
    """The hooks one backend registered; :meth:`release` takes them back."""

    at_exit: Callable[[], None] | None
    """The function registered with :mod:`atexit`, None once released."""
    old_sigterm: Any = None
    """The SIGTERM handler replaced (None: SIGTERM was left alone)."""

    def release(self) -> None:
        """Unregister the exit hook and give SIGTERM its earlier handler back."""
        old, self.old_sigterm = self.old_sigterm, None
        if old is not None and threading.current_thread() is threading.main_thread():
            try:
                signal.signal(signal.SIGTERM, old)
            except (ValueError, TypeError):
                pass
        hook, self.at_exit = self.at_exit, None
        if hook is not None:
            atexit.unregister(hook)


def register_exit_hooks(robot: ClosableRobot, handle_sigterm: bool) -> ExitHooks:
    """Close ``robot`` at interpreter exit and, if asked, take an unhandled SIGTERM.

    The hooks hold the backend weakly: a backend dropped without closing is not kept alive
    by them. One owner of SIGTERM: a handler already there (mdle's command-line guard, an
    application's) keeps it, and must end the program through ``finally`` blocks, which
    stop and close the robot. Only an unhandled SIGTERM (``SIG_DFL``) is taken.
    """
    ref = weakref.ref(robot)

    def _close_at_exit() -> None:
        backend = ref()
        if backend is not None:
            backend.close()

    atexit.register(_close_at_exit)
    hooks = ExitHooks(_close_at_exit)
    if (handle_sigterm
            and threading.current_thread() is threading.main_thread()
            and signal.getsignal(signal.SIGTERM) in (signal.SIG_DFL, None)):

        def _sigterm_to_exit(signum: int, frame: FrameType | None) -> None:
            # SIGTERM as SystemExit(143): ``finally`` blocks run and stop the robot; a
            # second one while the goodbye is under way must not cut it short
            backend = ref()
            if backend is None or not backend.closed:
                raise SystemExit(128 + signum)

        hooks.old_sigterm = signal.signal(signal.SIGTERM, _sigterm_to_exit)
    return hooks
