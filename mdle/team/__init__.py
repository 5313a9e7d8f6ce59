"""Several robots in one world.

The team file (:mod:`~mdle.team.file`), the checks across the robots' plans
(:mod:`~mdle.team.check`), and one tick loop for all of them (:mod:`~mdle.team.run`).
"""
