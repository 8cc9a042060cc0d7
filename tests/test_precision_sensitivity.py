"""Pose sensitivities through the loops against finite differences of rebuilt robots (issue 26).

The truth is independent of :mod:`pkdyn.precision`: a description whose numbers are edited as
text (:mod:`support.urdf_edit`) or a family built with other parameters, loaded by
:func:`pkdyn.load`, and its forward geometry solved at the same actuator coordinates.
"""

import numpy as np
import pinocchio as pin
import pytest
from support.urdf_edit import edited, family_xml, load_like, pose_error, twist

import pkdyn
from pkdyn.analysis.kinematics import kinematic_models
from pkdyn.exceptions import AssemblyError, InvalidInputError, SingularConfigurationError
from pkdyn.precision.parameters import (
    family_parameters,
    family_shortcuts,
    parameter_model,
    placement_parameters,
    placements,
)
from pkdyn.precision.perturbation import perturbed
from pkdyn.precision.sensitivity import pose_sensitivity

FAMILIES = ("delta", "gough_stewart", "five_bar", "tripod", "planar_3rrr")


@pytest.fixture(scope="module")
def robots():
    return {name: pkdyn.load(name, geometry=False) for name in FAMILIES}


def _q(robot, shift=0.03):
    """An assembled configuration away from home (actuators moved)."""
    qa = robot.q_home[robot.actuated_q] + shift * robot.actuator_scale * np.linspace(
        -1, 1, len(robot.actuators)
    )
    return pkdyn.forward_geometry(robot, qa, check_limits=False).q


@pytest.mark.parametrize("name", FAMILIES)
def test_actuator_sensitivity_is_the_kinematic_jacobian(robots, name):
    robot = robots[name]
    q = _q(robot)
    s = pose_sensitivity(robot, q)
    km = kinematic_models(robot, q)
    np.testing.assert_allclose(s.J[robot.task_rows], km.J, atol=1e-9)
    # and a finite difference of the forward geometry, all six pose rows
    h = 1e-6
    M0 = robot.platform_placement(q)
    for k in range(len(robot.actuators)):
        d = np.zeros(len(robot.actuators))
        d[k] = h
        plus = pkdyn.forward_geometry(robot, q[robot.actuated_q] + d, q_init=q, check_limits=False)
        minus = pkdyn.forward_geometry(robot, q[robot.actuated_q] - d, q_init=q, check_limits=False)
        fd = (pose_error(M0, plus.placement) - pose_error(M0, minus.placement)) / (2 * h)
        np.testing.assert_allclose(s.J[:, k], fd, atol=1e-6 * max(1.0, np.abs(fd).max()))


# (placement, translation in the parent frame, rotation vector in the placed frame)
EDITS = {
    "delta": [
        ("joint:arm2", (0, 0, 1), None),
        ("joint:arm1", None, (0, 1, 0)),  # the arm's offset
        ("joint:bar3b_upper", (1, 0, 0), None),
        ("closure:loop1a:1", (0, 0, 1), None),
        ("closure:loop2b:2", (1, -1, 0), None),
        ("platform", (0, 1, 0), (1, 0, 0)),
    ],
    "gough_stewart": [
        ("joint:leg1_U", (1, 0, 0), None),
        ("joint:leg4_U", None, (0, 0, 1)),
        ("joint:leg2", (0, 0, 1), None),  # the leg's offset
        ("closure:S5:2", (0, 1, 0), None),
        ("closure:S3:1", (1, 0, 1), (0, 1, 0)),
        ("platform", (0, 0, 1), (0, 0, 1)),
    ],
    "five_bar": [
        ("joint:proximal1", (1, 0, 0), None),
        ("joint:distal2", None, (0, 0, 1)),
        ("closure:loop:2", (0, 1, 0), None),
        ("platform", (1, 0, 0), None),
    ],
    "tripod": [
        ("joint:branch1_qL", (1, 0, 0), None),
        ("joint:branch2_q6", (0, 1, 0), (1, 0, 0)),
        ("closure:branch3_foothold:2", (0, 0, 1), (0, 0, 1)),
        ("closure:branch1_A:1", (0, 1, 0), None),
    ],
}


def _placement_index(robot, where):
    kind, _, rest = where.partition(":")
    name = rest.replace(":1", "/1").replace(":2", "/2") if kind == "closure" else rest
    name = "platform" if kind == "platform" else name
    return next(k for k, pl in enumerate(placements(robot)) if pl.name == name)


@pytest.mark.parametrize("name", list(EDITS))
def test_placement_sensitivity_against_rebuilt_descriptions(robots, name):
    robot = robots[name]
    model = placement_parameters(robot)
    q = _q(robot)
    qa = q[robot.actuated_q]
    s = pose_sensitivity(robot, q, model)
    xml = family_xml(robot)
    M0 = load_like(xml, robot).platform_placement(q)  # (the text's own rounding)
    h = 1e-6
    for where, dxyz, drot in EDITS[name]:
        res = []
        for sign in (1.0, -1.0):
            d = None if dxyz is None else sign * h * np.asarray(dxyz, float)
            w = None if drot is None else sign * h * np.asarray(drot, float)
            xml1 = edited(xml, {where: (d, w)})
            r1 = load_like(xml1, robot)
            g = pkdyn.forward_geometry(r1, qa, q_init=q, check_limits=False)
            res.append(pose_error(M0, g.placement))
            if sign > 0:
                xi = twist(xml, xml1, where) / h  # the edit as a placement twist
        fd = (res[0] - res[1]) / (2 * h)
        k = _placement_index(robot, where)
        rows = model.E[6 * k : 6 * k + 6]  # parameters of that placement
        predicted = s.K @ np.linalg.lstsq(rows, xi, rcond=None)[0]
        assert np.abs(s.closure_gap @ np.linalg.lstsq(rows, xi, rcond=None)[0]).max() < 1e-9
        np.testing.assert_allclose(
            predicted, fd, atol=2e-6 * max(1.0, np.abs(fd).max()), err_msg=where
        )


@pytest.mark.parametrize("name", ["delta", "gough_stewart"])
def test_family_parameter_sensitivity_against_the_builder(robots, name):
    robot = robots[name]
    model = family_parameters(robot)
    q = _q(robot)
    qa = q[robot.actuated_q]
    s = pose_sensitivity(robot, q, model)
    picks = ["la", "lb", "ra", "rb", "bar_spacing"] if name == "delta" else ["A2x", "B5z", "A6y"]
    p = robot.params
    for pname in picks:
        k = model.index(pname)
        h = 1e-6
        res = []
        for sign in (1.0, -1.0):
            if name == "delta":
                r1 = pkdyn.load(name, geometry=False, **{pname: getattr(p, pname) + sign * h})
            else:
                field, i, c = pname[0], int(pname[1]) - 1, "xyz".index(pname[2])
                arr = np.array(getattr(p, field), dtype=float)
                arr[i, c] += sign * h
                r1 = pkdyn.load(name, geometry=False, **{field: tuple(map(tuple, arr))})
            g = pkdyn.forward_geometry(r1, qa, check_limits=False)
            res.append(g.placement)
        fd = pose_error(res[1], res[0]) / (2 * h)
        np.testing.assert_allclose(
            s.K[:, k], fd, atol=1e-5 * max(1.0, np.abs(fd).max()), err_msg=pname
        )


def test_gains_and_sensitivity_at_a_perturbed_robot():
    """The Jacobian at a perturbed robot (``at``) is exact: Gauss-Newton steps need it."""
    robot = pkdyn.load("gough_stewart", geometry=False)
    model = family_shortcuts(robot, gains=True)
    rng = np.random.default_rng(1)
    p0 = rng.uniform(-1, 1, model.size) * model.tolerances(2e-3, 0.0087, 1e-3)
    P0 = perturbed(robot, model, p0)
    readings = robot.q_home[robot.actuated_q] + 0.02
    g0 = pkdyn.forward_geometry(P0.robot, P0.joint_coordinates(readings), q_init=P0.robot.q_home)
    s = pose_sensitivity(P0.robot, g0.q, model, at=p0)
    h = 1e-6
    for k in rng.choice(model.size, 12, replace=False):
        res = []
        for sign in (1.0, -1.0):
            dp = np.zeros(model.size)
            dp[k] = sign * h
            P = perturbed(robot, model, p0 + dp)
            g = pkdyn.forward_geometry(P.robot, P.joint_coordinates(readings), q_init=g0.q)
            res.append(pose_error(g0.placement, g.placement))
        fd = (res[0] - res[1]) / (2 * h)
        np.testing.assert_allclose(s.K[:, k], fd, atol=1e-6 * max(1.0, np.abs(fd).max()))


def test_an_error_the_planar_loop_cannot_absorb_is_reported_and_does_not_assemble(robots):
    robot = robots["five_bar"]
    model = placement_parameters(robot)
    q = _q(robot)
    s = pose_sensitivity(robot, q, model)
    k = model.index("distal2.rx")  # tilts a hinge axis out of the plane
    assert np.abs(s.closure_gap[:, k]).max() > 1e-3
    assert np.abs(s.closure_gap[:, model.index("distal2.tx")]).max() < 1e-12
    xml = edited(family_xml(robot), {"joint:distal2": (None, (1e-3, 0, 0))})
    r1 = load_like(xml, robot, moved=True)  # (absorbed at home as CAD rounding: < tolerance)
    with pytest.raises(AssemblyError):
        pkdyn.forward_geometry(r1, q[robot.actuated_q] + 0.3, q_init=q, tol=1e-12)


def test_a_parallel_singularity_is_refused():
    """Proximal tips on one point (the five-bar's elbows meet): the effector turns freely."""
    from pkdyn.analysis.singularity import classify

    robot = pkdyn.load("five_bar", geometry=False)  # d = l1 = 0.2: tips meet at 60 / 120 deg
    q = pkdyn.forward_geometry(
        robot, [np.pi / 3, 2 * np.pi / 3], check_limits=False, keep_mode=False
    ).q
    assert classify(robot, q).kind == "parallel"
    with pytest.raises(SingularConfigurationError, match="parallel singularity"):
        pose_sensitivity(robot, q)


def test_parameter_models_by_name_and_bad_names(robots):
    delta = robots["delta"]
    assert parameter_model(delta).kind == "family shortcuts"
    assert parameter_model(robots["five_bar"]).kind == "placements"
    assert family_parameters(delta).names == ("ra", "rb", "la", "lb", "bar_spacing")
    with pytest.raises(InvalidInputError, match="shortcuts exist for"):
        family_shortcuts(robots["five_bar"])
    with pytest.raises(InvalidInputError, match="unknown model"):
        parameter_model(delta, "nope")
    with pytest.raises(InvalidInputError, match="not a parameter"):
        family_shortcuts(delta).index("ra9")
    model = placement_parameters(delta)
    assert "motor1.offset" in model.names and "arm1.ry" not in model.names
    assert pin.SE3  # (pinocchio imported for the helpers)
