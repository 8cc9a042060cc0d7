"""A plug-in for the tests: the moving mass, computed slowly (a study long enough to interrupt).

Loaded with ``pkdyn design --plugin tests/support/slow_metric.py`` (a file: shipped to the
workers by value) or ``pkdyn.design.load_plugin``.
"""

import os
import time

from pkdyn.design import metric

CALLS = [0]
"""Evaluations in this process."""


@metric("slow_mass", "kg", "moving mass, after a pause (tests)")
def slow_mass(robot, ctx):
    CALLS[0] += 1
    time.sleep(float(os.environ.get("PKDYN_TEST_DELAY", "0.05")))  # seconds
    return float(sum(robot.model.inertias[j].mass for j in range(1, robot.model.njoints)))
