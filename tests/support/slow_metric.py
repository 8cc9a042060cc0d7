"""A plug-in for the tests: the moving mass, computed slowly (a study long enough to interrupt).

Loaded with ``pkdyn design --plugin tests/support/slow_metric.py`` (a file: shipped to the
workers by value) or ``pkdyn.design.load_plugin``.
"""

import time

from pkdyn.design import metric

DELAY = 0.05
"""Seconds each evaluation sleeps."""


@metric("slow_mass", "kg", "moving mass, after a pause (tests)")
def slow_mass(robot, ctx):
    time.sleep(DELAY)
    return float(sum(robot.model.inertias[j].mass for j in range(1, robot.model.njoints)))
