"""Every option of a --connect or --laser URL is checked before anything is opened.

Regression: ``?max_speed=-1`` sent VEL -1000 mm/s for ``go(100 m/s)`` (the robot drove
backwards); ``1e9``, ``nan``, ``inf`` and ``tcp://[::1`` ended in internal errors (exit 70).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from mdle.core.errors import BackendError
from mdle.drivers import open_backend
from mdle.drivers.arcos import ROBOT_PARAMS, RobotParams
from mdle.drivers.limits import LASER_MAX_RANGE, ROBOT_PARAM_RANGES, Range, check_robot_params
from mdle.drivers.pioneer import PioneerBackend, PioneerOptions

if TYPE_CHECKING:
    from tests.drivers.conftest import FakeArcos

    FakeRobot = Callable[..., FakeArcos]

BAD_NUMBERS = ["-1", "0", "1e9", "nan", "inf", "-inf", "NaN", "", "fast", "1e999", "0x10"]


@pytest.mark.parametrize("raw", BAD_NUMBERS)
@pytest.mark.parametrize("key", ["max_speed", "max_turn_rate", "dist_conv", "radius"])
def test_robot_options_out_of_range_are_refused_before_connecting(
        fake_robot: FakeRobot, fast: PioneerOptions, key: str, raw: str) -> None:
    fake = fake_robot()
    allowed = ROBOT_PARAM_RANGES[key]
    with pytest.raises(BackendError) as info:
        open_backend("pioneer", f"{fake.url}?{key}={raw}", options=fast)
    message = str(info.value)
    assert f"`{key}` must be {allowed.describe()}, got `{raw}`" in message
    assert "--connect" in message
    assert fake.received == []  # refused before a byte went out


@pytest.mark.parametrize("raw", ["-1", "0", "0.01", "inf", "nan", "65.6", "1e9", "far", ""])
def test_laser_max_range_out_of_range(fake_robot: FakeRobot, fast: PioneerOptions,
                                      raw: str) -> None:
    fake = fake_robot()
    with pytest.raises(BackendError, match=r"--laser `sim\?max_range=.*`: `max_range` must "
                                           r"be a number of m in \[0.1, 65.535\]"):
        open_backend("pioneer", fake.url, f"sim?max_range={raw}", options=fast)
    assert fake.received == []


def test_a_negative_speed_limit_never_reaches_the_wire(fake_robot: FakeRobot,
                                                      fast: PioneerOptions) -> None:
    # the case that drove a robot backwards; even through the Python API (limits and
    # parameter overrides given directly), the backend refuses before any motor command
    from dataclasses import replace

    from mdle.core.backend import RobotLimits
    from mdle.drivers.arcos import Cmd

    fake = fake_robot()
    with pytest.raises(BackendError, match=r"`max_speed` must be a number of m/s in \(0, 2\], "
                                           r"got -1"):
        open_backend("pioneer", fake.url, options=fast,
                     limits=RobotLimits(max_speed=-1.0, max_reverse_speed=0.5,
                                        max_turn_rate=1.0))
    fake2 = fake_robot()
    with pytest.raises(BackendError, match="`max_speed` must be"):
        open_backend("pioneer", fake2.url,
                     options=replace(fast, param_overrides=(("max_speed", math.inf),)))
    for f in (fake, fake2):
        assert not f.commands(Cmd.ENABLE) and set(f.args(Cmd.VEL)) <= {0}


def test_every_shipped_model_is_inside_the_ranges() -> None:
    for name, params in ROBOT_PARAMS.items():
        assert check_robot_params(params) is None, name
    assert check_robot_params(RobotParams(max_speed=-1.0)) is not None


def test_the_limits_keep_commands_inside_the_firmware_fields(fake_robot: FakeRobot,
                                                             fast: PioneerOptions) -> None:
    from mdle.core.backend import Command
    from mdle.drivers.arcos import Cmd

    fake = fake_robot()
    top = ROBOT_PARAM_RANGES["max_speed"].high
    backend = open_backend("pioneer", f"{fake.url}?max_speed={top}&max_turn_rate=6.28",
                           options=fast)
    assert isinstance(backend, PioneerBackend)
    try:
        backend.command(Command(100.0, -100.0))  # go(100 m/s): clamped, never negative
        assert fake.wait_for(lambda: bool(fake.commands(Cmd.RVEL)))
        assert fake.args(Cmd.VEL)[-1] == 2000 and fake.args(Cmd.RVEL)[-1] == -360
    finally:
        backend.close()


@pytest.mark.parametrize("url,message", [
    ("tcp://[::1", "cannot use connection `tcp://\\[::1`: Invalid IPv6 URL"),
    ("tcp://h:0", "port is not a number in 1..65535"),
    ("tcp://h:-5", "port is not a number in 1..65535"),
    ("serial:///dev/x?baud=1e20", "baud `1e20` is not a whole number"),
    ("serial:///dev/x?baud=99999999999", "baud must be at most 4000000"),
    ("tcp://h:1?max_speed=1&max_speed=2", "`max_speed` given twice"),
    ("tcp://h:1?maxspeed=1", "unknown option `maxspeed`; known: model, angle_conv"),
    ("tcp://h:1?model=", "unknown Pioneer model ``"),
    ("tcp://h:1?model=p9", "unknown Pioneer model `p9`"),
])
def test_malformed_connect_urls(url: str, message: str) -> None:
    with pytest.raises(BackendError, match=message):
        open_backend("pioneer", url)


def test_range_membership() -> None:
    r = Range(0.0, 2.0, "m/s")
    assert 1.0 in r and 2.0 in r and 0.0 not in r and -1.0 not in r
    assert math.nan not in r and math.inf not in r and "1" not in r
    assert 0.0 in Range(0.0, 1.0, "", open_low=False)
    assert LASER_MAX_RANGE.describe() == "a number of m in [0.1, 65.535]"


@pytest.mark.parametrize("connect,laser,needle", [
    ("{url}?max_speed=-1", None, "`max_speed` must be a number of m/s in (0, 2], got `-1`"),
    ("{url}?max_speed=1e9", None, "got `1e9`"),
    ("{url}?max_speed=nan", None, "got `nan`"),
    ("{url}?max_speed=inf", None, "got `inf`"),
    ("tcp://[::1", None, "Invalid IPv6 URL"),
    ("{url}", "sim?max_range=inf", "`max_range` must be a number of m in [0.1, 65.535]"),
    ("{url}", "sim?fov=90", "unknown option(s) fov"),
])
def test_mdle_run_reports_bad_urls_with_exit_1(fake_robot: FakeRobot, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str],
                                               connect: str, laser: str | None,
                                               needle: str) -> None:
    from mdle.cli import main

    fake = fake_robot()
    plan = tmp_path / "p.mdle"
    plan.write_text("atom fwd = (go(100 m/s), never, 1 s)\nrun fwd\n")
    argv = ["run", str(plan), "--backend", "pioneer", "--connect",
            connect.format(url=fake.url), "--quiet"]
    if laser is not None:
        argv += ["--laser", laser]
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 1, err
    assert needle in err and "Traceback" not in err and "internal error" not in err
    assert fake.received == []


def test_random_urls_give_messages_never_crashes() -> None:
    # whatever is typed after --connect or --laser: a BackendError with a message, or (for
    # a well-formed URL) a refused connection to a closed local port; never anything else
    import socket

    from hypothesis import given, settings
    from hypothesis import strategies as st

    from mdle.drivers.transport import parse_url

    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    closed = f"tcp://127.0.0.1:{s.getsockname()[1]}"
    s.close()
    keys = st.sampled_from(["model", "baud", "max_range", *ROBOT_PARAM_RANGES, "x", ""])
    values = st.one_of(st.text(max_size=12), st.floats().map(repr),
                       st.integers(-10**30, 10**30).map(str))
    queries = st.lists(st.tuples(keys, values), max_size=3).map(
        lambda kv: "&".join(f"{k}={v}" for k, v in kv))
    texts = st.one_of(st.text(max_size=40),
                      st.builds(lambda scheme, rest: f"{scheme}://{rest}",
                                st.sampled_from(["tcp", "serial", "lms200", "sim", "http"]),
                                st.text(max_size=30)))

    @settings(max_examples=150, deadline=None, database=None)
    @given(text=texts, query=queries, laser=st.booleans())
    def check(text: str, query: str, laser: bool) -> None:
        try:
            parse_url(text)
        except BackendError as exc:
            assert str(exc)
        connect, laser_url = (closed, f"sim?{query}") if laser else (f"{closed}?{query}", None)
        with pytest.raises(BackendError) as info:
            open_backend("pioneer", connect, laser_url, options=PioneerOptions(
                sync_timeout=0.05, sync_retries=1))
        assert str(info.value)

    check()
