"""How the ``mdle`` process ends (mdle/console/ending.py): at once, nothing lost.

The console script keeps what a command built until the process ends, and ends it with
``os._exit`` after every exit hook and a flush of the standard streams: a checked plan
of 200,000 lines is never freed object by object (half a second in which no signal was
answered). Each test runs a real process. A weak-reference finalizer on a loaded
program says whether it was ever freed: it prints ``freed`` when it is.
"""

from __future__ import annotations

import signal
import subprocess
import sys
from pathlib import Path

import pytest

#: Runs ``mdle`` as the console script does, with a finalizer on each loaded program.
#: ``HOOK`` (argv[1]): ``none``; ``slow`` (a command's exit hook that takes 1 s and
#: then writes a file); ``interrupt`` (a signal to itself while the program is held).
SCRIPT = """
import atexit, os, signal, sys, time, weakref
import mdle.lang
from mdle.cli import main

hook, mark = sys.argv[1], sys.argv[2]
load = mdle.lang.load_program

def load_program(*args, **kwargs):
    program = load(*args, **kwargs)
    freed = weakref.finalize(program, print, "freed", file=sys.stderr, flush=True)
    freed.atexit = False  # "freed" only if it is freed, not because the process exits
    if hook == "slow":
        def goodbye():
            print("goodbye", file=sys.stderr, flush=True)
            time.sleep(1.0)
            open(mark, "w").write("hook done")
        atexit.register(goodbye)
    if hook == "interrupt":
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(60)  # the signal is raised here, with the program held by this frame
    return program

mdle.lang.load_program = load_program
sys.argv = ["mdle", *sys.argv[3:]]
sys.exit(main())
"""


def _mdle(tmp_path: Path, hook: str, *argv: str) -> subprocess.Popen[str]:
    script = tmp_path / "run_mdle.py"
    script.write_text(SCRIPT)
    return subprocess.Popen([sys.executable, str(script), hook, str(tmp_path / "mark"), *argv],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)


@pytest.fixture
def plans(tmp_path: Path) -> list[str]:
    names = []
    for i in range(40):  # several files: much for stdout to carry through the end
        (tmp_path / f"p{i}.mdle").write_text(
            f"atom a = (go(9 m/s), never, {i + 1} s)\nrun a\n")  # 9 m/s: one warning each
        names.append(f"p{i}.mdle")
    return names


def test_a_command_s_output_is_whole_and_what_it_built_is_never_freed(
        tmp_path: Path, plans: list[str]) -> None:
    proc = _mdle(tmp_path, "none", "check", *plans)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert out.count("warning:") == 40 and out.rstrip().endswith("0 errors, 40 warnings")
    assert "freed" not in err  # the programs went with the process, not one by one


def test_a_command_called_from_python_still_frees_what_it_built(
        tmp_path: Path, plans: list[str]) -> None:
    # main(argv) from Python (tests, tools) leaves the end to its caller
    script = tmp_path / "call.py"
    script.write_text(SCRIPT.replace('sys.argv = ["mdle", *sys.argv[3:]]\nsys.exit(main())',
                                     "code = main(sys.argv[3:])\nprint('returned', code, "
                                     "file=sys.stderr, flush=True)"))
    done = subprocess.run([sys.executable, str(script), "none", "mark", "check", *plans[:2]],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stderr.count("freed") == 2
    assert done.stderr.index("freed") < done.stderr.index("returned 0")


def test_every_exit_hook_runs_before_the_end_and_a_signal_meanwhile_changes_nothing(
        tmp_path: Path) -> None:
    # a hook the command registered (a robot's goodbye takes this long) runs to its end;
    # the signals are held from the command's end, so its code stands
    (tmp_path / "p.mdle").write_text("atom a = (go(0.3 m/s), never, 1 s)\nrun a\n")
    proc = _mdle(tmp_path, "slow", "check", "p.mdle")
    assert proc.stderr is not None
    assert proc.stderr.readline() == "goodbye\n"
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert (tmp_path / "mark").read_text() == "hook done"
    assert "checked 1 file: 0 errors, 0 warnings" in out
    assert "freed" not in err and "Traceback" not in err


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_an_interrupted_command_says_so_and_ends_without_freeing_what_it_held(
        tmp_path: Path, signum: signal.Signals) -> None:
    (tmp_path / "p.mdle").write_text("atom a = (go(0.3 m/s), never, 1 s)\nrun a\n")
    script = tmp_path / "run_mdle.py"
    script.write_text(SCRIPT.replace("signal.SIGINT)", f"signal.{signum.name})"))
    done = subprocess.run([sys.executable, str(script), "interrupt", "mark", "run", "p.mdle",
                           "-q", "--trace", "t.jsonl"], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 128 + signum, done.stderr
    assert "interrupted by" in done.stderr and "Traceback" not in done.stderr
    # the interruption's frames (which hold the program) are kept to the end
    assert "freed" not in done.stderr
    from mdle.record.load import read_trace

    trace = read_trace(tmp_path / "t.jsonl")
    assert trace.end is not None and not trace.truncated
