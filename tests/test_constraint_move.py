"""Closures moved in place (:meth:`solvers.constraints.ConstraintSet.move_closures`).

A set whose rows do not depend on the frames' placements (points and welds on bodies a ball or
free joint turns) takes other placements in place: its residuals, Jacobians and drifts are then
those of a set made anew from the moved closures, bit for bit, at any configuration; a set whose
rows depend on them (planar loops, hinges) refuses, as do closures that are not its own. The
perturbed robots of the Monte Carlo (:func:`pkdyn.precision.perturbation.perturbed` with
``shared``) are those made anew.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.model.assembly import forward_geometry
from pkdyn.precision.parameters import parameter_model
from pkdyn.precision.perturbation import perturbed
from solvers.constraints import ConstraintSet

pytestmark = pytest.mark.filterwarnings("ignore")


def _moved(cs: ConstraintSet, rng: np.random.Generator, size: float) -> list:
    """The set's closures with both frames moved by random placements of about ``size``."""
    out = []
    for c in cs.closure_specs:
        d1 = pin.exp6(rng.uniform(-size, size, 6))
        d2 = pin.exp6(rng.uniform(-size, size, 6))
        out.append(
            dataclasses.replace(c, placement1=c.placement1 * d1, placement2=c.placement2 * d2)
        )
    return out


@pytest.mark.parametrize("name", ["delta", "gough_stewart"])
def test_closures_moved_in_place_are_a_new_set(name: str) -> None:
    robot = pkdyn.load(name, geometry=False)
    model = robot.model
    rng = np.random.default_rng(3)
    cs = ConstraintSet(model, robot.constraints.closure_specs, robot.constraints.coupling_specs)
    assert cs.movable
    data_a, data_b = model.createData(), model.createData()
    qs = [pin.integrate(model, robot.q_home, rng.uniform(-0.2, 0.2, model.nv)) for _ in range(3)]
    v = rng.uniform(-1.0, 1.0, model.nv)
    for _ in range(3):
        moved = _moved(cs, rng, 1e-2)
        cs.local_residual(data_a, qs[0])  # (the LOCAL copies made before the move)
        cs.move_closures(moved)
        fresh = ConstraintSet(model, moved, robot.constraints.coupling_specs)
        assert cs.n == fresh.n and cs.names == fresh.names
        for q in qs:
            assert np.array_equal(cs.residual(data_a, q), fresh.residual(data_b, q))
            assert np.array_equal(cs.jacobian(data_a, q), fresh.jacobian(data_b, q))
            ra, rb = cs.local_residual(data_a, q), fresh.local_residual(data_b, q)
            assert np.array_equal(ra, rb)
            assert np.array_equal(
                cs.local_jacobian_after_residual(data_a, q),
                fresh.local_jacobian_after_residual(data_b, q),
            )
            assert np.array_equal(cs.drift(data_a, q, v), fresh.drift(data_b, q, v))
        for a, b in zip(cs.closure_specs, moved, strict=True):
            assert a.placement1 == b.placement1 and a.placement2 == b.placement2


@pytest.mark.parametrize("name", ["five_bar", "planar_3rrr", "tripod"])
def test_sets_whose_rows_depend_on_the_placements_refuse(name: str) -> None:
    robot = pkdyn.load(name, geometry=False)
    cs = robot.constraints
    assert not cs.movable
    with pytest.raises(ValueError, match="make a new set"):
        cs.move_closures(list(cs.closure_specs))


def test_move_takes_the_set_s_own_closures() -> None:
    robot = pkdyn.load("delta", geometry=False)
    cs = ConstraintSet(robot.model, robot.constraints.closure_specs)
    specs = list(cs.closure_specs)
    with pytest.raises(ValueError, match="same closures"):
        cs.move_closures(specs[1:])
    with pytest.raises(ValueError, match="same closures"):
        cs.move_closures([dataclasses.replace(specs[0], joint1=specs[3].joint1)] + specs[1:])


@pytest.mark.parametrize(
    ("name", "kind"),
    [("delta", "shortcuts"), ("gough_stewart", "placements"), ("five_bar", "placements")],
)
def test_shared_perturbed_robots_are_the_robots_made_anew(name: str, kind: str) -> None:
    robot = pkdyn.load(name, geometry=False)
    model = parameter_model(robot, kind)
    q = robot.q_home
    rng = np.random.default_rng(5)
    planar = name == "five_bar"
    for _ in range(4):
        p = rng.uniform(-1e-4, 1e-4, len(model.names))
        a = perturbed(robot, model, p, assemble=False, shared=True)
        b = perturbed(robot, model, p, assemble=False, shared=False)
        assert a.robot.length_scale == b.robot.length_scale
        assert np.array_equal(a.robot.actuator_scale, b.robot.actuator_scale)
        for ca, cb in zip(a.robot.constraint_models, b.robot.constraint_models, strict=True):
            assert ca.joint1_placement == cb.joint1_placement
            assert ca.joint2_placement == cb.joint2_placement
        for x, y in zip(a.robot.closures, b.robot.closures, strict=True):
            assert x.frame1.placement == y.frame1.placement
            assert x.frame2.placement == y.frame2.placement
        assert a.robot.constraints.n == b.robot.constraints.n
        if planar:  # (out-of-plane errors open the loop: no assembly, the same refusal)
            continue
        qa = a.joint_coordinates(q[robot.actuated_q])
        ra = forward_geometry(a.robot, qa, q_init=q, check_limits=False)
        rb = forward_geometry(b.robot, qa, q_init=q, check_limits=False)
        assert np.array_equal(ra.q, rb.q)
        assert ra.placement == rb.placement
