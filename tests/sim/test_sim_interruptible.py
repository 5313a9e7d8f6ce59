"""Long calls into C run so that Ctrl-C still cuts them (sim/interruptible.py)."""

from __future__ import annotations

import signal
import subprocess
import sys
import time

import pytest

from mdle.sim.interruptible import call_interruptibly


def test_the_call_s_value_and_its_exception_come_back() -> None:
    assert call_interruptibly(lambda: 6 * 7) == 42
    with pytest.raises(ZeroDivisionError):
        call_interruptibly(lambda: 1 / 0)


def test_a_signal_is_acted_on_while_the_call_goes_on() -> None:
    # time.sleep in the worker stands for GEOS: C code without the GIL, 30 s long
    code = ("import sys, time\n"
            "from mdle.sim.interruptible import call_interruptibly\n"
            "print('ready', flush=True)\n"
            "try:\n"
            "    call_interruptibly(lambda: time.sleep(30))\n"
            "except KeyboardInterrupt:\n"
            "    print('interrupted', flush=True)\n"
            "    sys.exit(130)\n")
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None and proc.stdout.readline() == "ready\n"
        time.sleep(0.3)
        sent = time.monotonic()
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=25)
        waited = time.monotonic() - sent
    finally:
        proc.kill()
        proc.wait()
    assert proc.returncode == 130 and out == "interrupted\n"
    assert waited < 10.0  # not the call's 30 s


def test_a_large_map_is_outlined_the_same_way() -> None:
    import numpy as np

    from mdle.sim.maps import outline

    occupied = np.zeros((60, 80), dtype=bool)
    occupied[5:20, 10:70] = True
    occupied[30:50, 20:25] = True
    geom = outline(occupied, 0.1, (0.0, 0.0, 0.0))
    assert geom.area == pytest.approx((15 * 60 + 20 * 5) * 0.01)
