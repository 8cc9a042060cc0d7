"""Calibration truth: robots with geometric errors written into their text, and measurements.

Each truth robot is the nominal description with its numbers edited as text
(:mod:`support.urdf_edit`) and loaded by :func:`pkdyn.load_string`; its forward geometry at
actuator readings inside the workspace, plus Gaussian noise, is the measurement.
"""

from __future__ import annotations

import numpy as np

import pkdyn
from pkdyn.calibration import Measurements
from support.urdf_edit import family_xml, load_like, where_of, with_twists

MM, DEG = 2e-3, np.deg2rad(0.5)


def readings(robot, n, seed, spread=0.3):
    """Actuator readings around home that the nominal robot assembles within its limits."""
    rng = np.random.default_rng(seed)
    home = robot.q_home[robot.actuated_q]
    lo = robot.model.lowerPositionLimit[robot.actuated_q]
    hi = robot.model.upperPositionLimit[robot.actuated_q]
    out = []
    while len(out) < n:
        qa = home + spread * robot.actuator_scale * rng.uniform(-1, 1, home.size)
        if np.any(qa < lo) or np.any(qa > hi):
            continue
        try:
            pkdyn.forward_geometry(robot, qa)
        except pkdyn.PkdynError:
            continue
        out.append(qa)
    return np.array(out)


def measure(truth, readings, kind, sigma, rng, sigma_rot=None, gains=0.0):
    poses = [
        pkdyn.forward_geometry(
            truth, (1.0 + gains) * r, q_init=truth.q_home, check_limits=False
        ).placement
        for r in readings
    ]
    m = Measurements.from_placements(readings, poses, kind)
    m.position = m.position + rng.normal(0.0, sigma, m.position.shape)
    if kind == "pose":
        m.rpy = m.rpy + rng.normal(0.0, sigma_rot, m.rpy.shape)
    return m, poses


def truth_of(robot, model, p_true):
    """The nominal description with every placement moved by its error, loaded from text.

    ``p_true`` (errors of ``model``'s parameters) is written as ``M exp(xi)`` into the numbers
    of the URDF; the loader builds the truth robot from that text. Gains are returned apart:
    the truth's joint coordinate is ``(1 + gain) * reading``.
    """
    xml = family_xml(robot)
    xi = model.twists(p_true)
    twists = {where_of(pl): x for pl, x in zip(model.placements, xi, strict=True) if np.any(x)}
    return load_like(with_twists(xml, twists), robot), model.gains(p_true)


def draw(model, rng, names=None):
    """Errors within +-2 mm, +-0.5 deg (gains +-1e-3) of the named parameters (default all)."""
    t = model.tolerances(MM, DEG, 1e-3)
    p = rng.uniform(-1.0, 1.0, model.size) * t
    if names is not None:
        keep = np.array([any(n.endswith(s) for s in names) for n in model.names])
        p = np.where(keep, p, 0.0)
    return p
