"""Where a drawn figure goes when the user named no file: a window, or a PNG beside them.

``mdle plot`` and ``mdle worlds show`` without ``-o`` open a window when the session has a
display (X11 or Wayland on Linux; always on macOS and Windows) and matplotlib has an
interactive backend for it; otherwise, or when the window cannot be opened, they write
``NAME.png`` in the current folder and say where.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Callable, Iterator, Mapping
from typing import TYPE_CHECKING

from mdle.core.errors import Diagnostic, MdleError

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["PlotError", "has_display", "open_window", "WindowError", "show_or_write", "save_figure",
           "atomic_output"]


class PlotError(MdleError):
    """A plot cannot be made: unknown output format, or a trace with no samples."""

#: matplotlib backends that draw to files only (no window).
_FILE_BACKENDS = frozenset({"agg", "cairo", "pdf", "pgf", "ps", "svg", "template"})


class WindowError(RuntimeError):
    """No window could be opened for a figure (no interactive backend, or it failed)."""


def has_display(environ: Mapping[str, str] | None = None, platform: str | None = None) -> bool:
    """Tell whether this session can show a window.

    >>> has_display({"DISPLAY": ":0"}, "linux"), has_display({}, "linux")
    (True, False)
    """
    env = os.environ if environ is None else environ
    plat = sys.platform if platform is None else platform
    if plat in ("darwin", "win32"):
        return True
    return bool(env.get("DISPLAY") or env.get("WAYLAND_DISPLAY"))


def open_window(fig: "Figure", title: str) -> None:
    """Show ``fig`` in a window and wait until it is closed.

    Raises
    ------
    WindowError
        matplotlib has no interactive backend here, or the window failed to open.
    """
    import matplotlib

    try:
        import matplotlib.pyplot as plt

        backend = str(matplotlib.get_backend()).lower()
        if backend in _FILE_BACKENDS or backend.startswith("module://matplotlib_inline"):
            raise WindowError(f"matplotlib's backend `{backend}` cannot open a window")
        holder = plt.figure()  # a window of the interactive backend, then given our figure
        manager = holder.canvas.manager
        if manager is None:
            raise WindowError("matplotlib made no window")
        manager.canvas.figure = fig
        fig.set_canvas(manager.canvas)
        manager.set_window_title(title)
        plt.show()
    except WindowError:
        raise
    except Exception as exc:  # a toolkit that fails to start (no Tk, a dead X server...)
        raise WindowError(f"{type(exc).__name__}: {exc}") from None


@contextlib.contextmanager
def atomic_output(out: str) -> Iterator[str]:
    """Yield a temporary name beside ``out`` to write; it becomes ``out`` only when whole.

    The temporary name keeps ``out``'s extension (encoders pick the format from it).

    Raises
    ------
    PlotError
        The file cannot be written (the message names it and says why).
    """
    head, name = os.path.split(os.path.abspath(out))
    stem, ext = os.path.splitext(name)
    tmp = os.path.join(head, f".{stem}.{os.getpid()}.part{ext}")
    done = False
    try:
        yield tmp
        os.replace(tmp, out)
        done = True
    except OSError as exc:
        raise PlotError(Diagnostic(None, f"cannot write the plot `{out}`: "
                                         f"{exc.strerror or exc}")) from None
    finally:
        if not done:
            try:
                os.unlink(tmp)
            except OSError:
                pass


def save_figure(fig: "Figure", out: str, dpi: int = 130) -> None:
    """Write ``fig`` to ``out`` (.png, .svg or .pdf) whole or not at all.

    Raises
    ------
    PlotError
        The name has no known image extension, or the file cannot be written.
    """
    ext = os.path.splitext(out)[1].lower().lstrip(".")
    if ext not in ("png", "svg", "pdf"):
        raise PlotError(Diagnostic(None, f"cannot write a plot to `{out}`: the file name must "
                                         "end in .png, .svg or .pdf"))
    with atomic_output(out) as tmp, open(tmp, "wb") as f:  # the umask applies, as to any file
        fig.savefig(f, format=ext, dpi=dpi)


def show_or_write(fig: "Figure", name: str, *, display: bool | None = None,
                  window: Callable[["Figure", str], None] | None = None) -> str:
    """Show ``fig`` in a window, or write ``NAME.png`` here; return what was done, as a line.

    ``display`` overrides :func:`has_display`; ``window`` opens the window (tests swap it).
    """
    reason = "no display"
    if has_display() if display is None else display:
        try:
            (window or open_window)(fig, name)
            return f"plot of {name} shown in a window"
        except WindowError as exc:
            reason = f"cannot open a window ({exc})"
    out = os.path.abspath(f"{name}.png")
    save_figure(fig, out)
    return f"{reason}: plot written to {out}"
