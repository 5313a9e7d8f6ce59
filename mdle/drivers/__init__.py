"""Hardware drivers: real robots and sensors behind the :class:`mdle.core.backend.Backend` seam.

* :mod:`mdle.drivers.arcos`: the Pioneer ARCOS packet codec (framing, commands, SIPs).
* :mod:`mdle.drivers.arcos_laser`: the Pioneer simulators' laser packets.
* :mod:`mdle.drivers.lms200`: the SICK LMS-200 telegram codec.
* :mod:`mdle.drivers.transport`: byte streams over TCP and serial lines, from URLs.
* :mod:`mdle.drivers.pioneer`: :class:`PioneerBackend`, a Pioneer (or MobileSim/AMRISim).
* :mod:`mdle.drivers.lms200_driver`: a reader thread for a SICK LMS-200 on a serial line.

:func:`open_backend` is what ``mdle run --backend pioneer`` calls.
"""

from __future__ import annotations

__all__ = ["BACKEND_KINDS", "open_backend"]

from dataclasses import replace
from typing import TYPE_CHECKING

from mdle.core.errors import BackendError

if TYPE_CHECKING:
    from mdle.core.backend import Backend, RobotLimits

#: The kinds :func:`open_backend` knows.
BACKEND_KINDS: tuple[str, ...] = ("pioneer",)

_CONNECT_TIMEOUT = 5.0
#: Bytes of a 181-value 0xB0 telegram with its ACK (the facts note's figure).
_LMS_SCAN_BYTES = 372


def open_backend(kind: str, connect: str, laser: str | None = None, *, rate: float = 10.0,
                 limits: RobotLimits | None = None, options: object | None = None,
                 laser_options: object | None = None) -> Backend:
    """Connect to a robot and return it as a wall-clock backend.

    Parameters
    ----------
    kind : str
        ``"pioneer"``: an ARCOS robot or MobileSim/AMRISim.
    connect : str
        ``tcp://HOST:PORT`` (simulators; port 8101 by default) or
        ``serial:///dev/ttyUSB0?baud=9600`` (a robot; without ``baud`` the driver probes
        9600 then 115200). Query options: ``model=p3dx`` (force a model's parameters)
        and any :class:`~mdle.drivers.arcos.RobotParams` field, e.g. ``dist_conv=0.485``.
    laser : str or None
        ``sim`` (the simulators' laser over the robot connection; ``sim?max_range=8``
        sets the no-return value in metres, 32.767 by default), ``lms200:///dev/ttyUSB1?baud=38400``
        (a SICK LMS-200 on its own serial line) or None (no laser).
    rate : float
        The control rate the runtime ticks at, Hz.
    limits : RobotLimits or None
        Clamp commands to these; None takes the model's.
    options, laser_options : PioneerOptions, Lms200Options or None
        Timeouts and choices (tests shorten them).

    Returns
    -------
    Backend
        A :class:`~mdle.drivers.pioneer.PioneerBackend` (``clock = ClockMode.WALL``);
        close it when done (it also stops the robot on SIGTERM and at exit).

    Raises
    ------
    BackendError
        Unknown kind, malformed URL, an option unknown or out of its range (checked
        before anything is opened), nothing answering, missing pyserial, ...
    """
    from mdle.drivers.arcos import ROBOT_PARAMS
    from mdle.drivers.limits import LASER_MAX_RANGE, ROBOT_PARAM_RANGES, read_number
    from mdle.drivers.lms200_driver import Lms200Driver, Lms200Options
    from mdle.drivers.pioneer import PioneerBackend, PioneerOptions
    from mdle.drivers.transport import open_transport, parse_url

    if kind not in BACKEND_KINDS:
        raise BackendError(f"unknown hardware backend `{kind}`; known: "
                           f"{', '.join(BACKEND_KINDS)}")
    robot = parse_url(connect)
    if robot.scheme not in ("tcp", "serial"):
        raise BackendError(f"--connect `{connect}`: a Pioneer is reached at tcp://HOST:PORT "
                           f"(MobileSim/AMRISim) or serial:///dev/DEVICE?baud=9600 (a robot)")
    opt = options if isinstance(options, PioneerOptions) else PioneerOptions(
        handle_sigterm=True)
    robot_opts = dict(robot.options)
    model = robot_opts.pop("model", None)
    if model is not None and model.strip().lower() not in ROBOT_PARAMS:
        raise BackendError(f"--connect `{connect}`: unknown Pioneer model `{model}`; known: "
                           f"{', '.join(sorted(ROBOT_PARAMS))}")
    overrides = []
    for key, raw in robot_opts.items():
        allowed = ROBOT_PARAM_RANGES.get(key)
        if allowed is None:
            raise BackendError(f"--connect `{connect}`: unknown option `{key}`; known: model, "
                               f"{', '.join(sorted(ROBOT_PARAM_RANGES))}")
        overrides.append((key, read_number("--connect", connect, key, raw, allowed)))
    opt = replace(opt, model=model.strip() if model else opt.model,
                  param_overrides=tuple(overrides) or opt.param_overrides)
    if robot.scheme == "serial" and not opt.bauds:
        opt = replace(opt, bauds=(robot.baud,) if robot.baud else (9600, 115200))

    laser_source = None
    sim_laser = False
    if laser is not None:
        lep = parse_url(laser)
        if lep.scheme == "sim":
            sim_laser = True
            extra = dict(lep.options)
            if "max_range" in extra:
                metres = read_number("--laser", laser, "max_range", extra.pop("max_range"),
                                     LASER_MAX_RANGE)
                opt = replace(opt, laser_max_range_mm=round(metres * 1000))
            if extra:
                raise BackendError(f"--laser `{laser}`: unknown option(s) "
                                   f"{', '.join(sorted(extra))}; known: max_range")
        elif lep.scheme == "lms200":
            if lep.options:
                raise BackendError(f"--laser `{laser}`: unknown option(s) "
                                   f"{', '.join(sorted(lep.options))}; known: baud")
            lopt = laser_options if isinstance(laser_options, Lms200Options) else Lms200Options()
            if lep.baud is not None:
                lopt = replace(lopt, baud=lep.baud)
            # a slow line delivers scans less often: allow 2.5 scan transfer times of age
            transfer = _LMS_SCAN_BYTES * 10.0 / lopt.baud
            opt = replace(opt, max_scan_age=max(opt.max_scan_age, 2.5 * transfer))
            laser_source = Lms200Driver(open_transport(lep, baud=9600), lopt)
        else:
            raise BackendError(f"--laser `{laser}`: expected `sim` or "
                               f"lms200:///dev/DEVICE?baud=38400")
    try:
        transport = open_transport(robot, connect_timeout=_CONNECT_TIMEOUT)
        return PioneerBackend(transport, laser="sim" if sim_laser else laser_source,
                              limits=limits, rate=rate, options=opt)
    except BaseException:
        if laser_source is not None:
            laser_source.close()
        raise
