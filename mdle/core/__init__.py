"""What every layer of mdle shares, below everything else.

The seam between the runtime and a robot (:mod:`~mdle.core.backend`: observations,
scans, commands, the ``Backend`` protocol; :mod:`~mdle.core.messages`: a team's channels
and inboxes), errors as data (:mod:`~mdle.core.errors`), units and dimensions
(:mod:`~mdle.core.units`), safe reading and writing of the files a user names
(:mod:`~mdle.core.userfile`), checked number ranges (:mod:`~mdle.core.ranges`), the robot a
plan is checked against (:mod:`~mdle.core.motion_limits`), and the hooks that stop a
robot however the program ends (:mod:`~mdle.core.exit_hooks`). It imports nothing else
of mdle.
"""
