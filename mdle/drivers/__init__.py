"""Hardware drivers: real robots and sensors behind the :class:`mdle.backend.Backend` seam.

* :mod:`mdle.drivers.arcos`: the Pioneer ARCOS packet codec (framing, commands, SIPs).
* :mod:`mdle.drivers.arcos_laser`: the Pioneer simulators' laser packets.
* :mod:`mdle.drivers.lms200`: the SICK LMS-200 telegram codec.
* :mod:`mdle.drivers.transport`: byte streams over TCP and serial lines, from URLs.
* :mod:`mdle.drivers.pioneer`: :class:`PioneerBackend`, a Pioneer (or MobileSim/AMRISim).
* :mod:`mdle.drivers.lms200_driver`: a reader thread for a SICK LMS-200 on a serial line.

:func:`open_backend` is what ``mdle run --backend pioneer`` calls.
"""

from __future__ import annotations

__all__ = ["open_backend", "BACKEND_KINDS"]
