"""Robot profiles fitted to recorded runs (``mdle robots fit``).

A recording (:mod:`~mdle.fit.recording`: a CSV log or an mdle trace) gives the speeds,
commands and scan ages of a real robot's run; :mod:`~mdle.fit.profile` fits the
simulator's timing model to it, with :mod:`~mdle.fit.cycle` for a cycled robot's server
loop and :mod:`~mdle.fit.scans` for stretches of scans at half rate.
"""
