"""The terminal that the command line and the REPL share.

How diagnostics and exit codes are printed (:mod:`~mdle.console.output`), and how
signals end a command or a session (:mod:`~mdle.console.signals`).
"""
