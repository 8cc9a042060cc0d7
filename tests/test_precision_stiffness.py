"""Stiffness by the virtual-joint method, checked against physics (issue 26, items 1, 6, 8).

- Gosselin's ``K = J^T K_a J`` with ``J`` the inverse kinematic Jacobian of the kinematic models
  (a different computation: relations ``A x_dot = B qa_dot`` eliminated by left null spaces);
- the published cubic hexapod ``K = k diag(2, 2, 2, 1.5 Hc^2, 1.5 Hc^2, 6 Hc^2)`` and its
  transport to another point;
- deflections ``K^-1 F`` against nonlinear static equilibria solved with the actuators replaced by
  stiff joint springs (the existing statics and direct geometric model, scipy's root finder);
- the loaded mode's tangent stiffness against increments of those nonlinear equilibria;
- the links' beams against the closed form of legs in series and Castigliano's theorem.
"""

import dataclasses

import numpy as np
import pinocchio as pin
import pytest
import scipy.optimize
from conftest import random_configs

import pkdyn
from pkdyn.analysis.kinematics import kinematic_models
from pkdyn.analysis.statics import static_equilibrium
from pkdyn.exceptions import InvalidInputError, SingularConfigurationError
from pkdyn.library.gough_stewart import Params as GSParams
from pkdyn.model.description import PassiveSpec
from pkdyn.model.passive import with_passive
from pkdyn.precision import (
    CARBON,
    STEEL,
    Material,
    Section,
    elastic_model,
    stiffness,
    tip_compliance,
    transport,
)
from pkdyn.precision.modes import mass_matrix
from solvers import PassiveForces


def _world_J_inv(robot, q):
    """``J_inv`` of the kinematic models with the angular rates in world axes (precision)."""
    km = kinematic_models(robot, q)
    T = np.eye(km.m)
    rot = [k for k, t in enumerate(km.task) if t.startswith("r")]
    if len(rot) == 3:  # angular velocity in the platform frame: omega_p = R^T omega_w
        T[np.ix_(rot, rot)] = robot.platform_placement(q).rotation.T
    return km.J_inv @ T


@pytest.mark.parametrize(
    "name, params",
    [
        ("delta", {}),
        ("delta", {"arms": 4}),  # redundant actuation: K = J^T K_a J with J (4, 3)
        ("delta", {"parallelogram": "hinge"}),  # over-constrained closures
        ("gough_stewart", {}),
        ("planar_3rrr", {}),
        ("five_bar", {}),
        ("four_bar_knee", {}),
        ("tripod", {}),
    ],
)
def test_actuators_alone_give_gosselin(name, params):
    robot = pkdyn.load(name, **params)
    rng = np.random.default_rng(3)
    for q in [robot.q_home, *random_configs(robot, 1, seed=5, spread=(0.02, 0.05))]:
        k = rng.uniform(1e4, 5e4, len(robot.actuators))
        J = _world_J_inv(robot, q)
        K_ref = J.T @ np.diag(k) @ J
        S = stiffness(robot, q, k)
        assert np.abs(S.K - K_ref).max() <= 1e-9 * np.abs(K_ref).max()
        assert np.allclose(S.compliance @ S.K, np.eye(len(S.task)), atol=1e-9)


def test_principal_stiffnesses_and_internal_mobilities(delta):
    S = stiffness(delta, delta.q_home, 2e4)
    w = np.linalg.eigvalsh(S.K)
    assert np.allclose(np.sort(S.translation.stiffness), w, rtol=1e-10)
    for k, d in zip(S.translation.stiffness, S.translation.directions, strict=True):
        assert np.allclose(S.K @ d, k * d, rtol=1e-8, atol=1e-6 * k)
    assert S.internal == 6  # the six bars' spin
    assert S.rotation is None and S.K6 is None  # rotations held by the rigid parallelograms
    universal = pkdyn.load("delta", bar_joint="universal")
    assert stiffness(universal, universal.q_home, 2e4).internal == 0


def _cubic_hexapod(a=0.5):
    """Gough-Stewart whose legs are six edges of a cube of side ``a``, diagonal vertical."""
    d = np.ones(3) / np.sqrt(3.0)
    axis = np.cross(d, [0.0, 0.0, 1.0])
    R = pin.exp3(axis / np.linalg.norm(axis) * np.arccos(d[2]))
    A, B = [], []
    for top in ((1, 1, -1), (1, -1, 1), (-1, 1, 1)):  # the vertices next to the top one
        for i in range(3):
            if top[i] == 1:
                low = np.array(top, dtype=float)
                low[i] = -1.0
                A.append(R @ (low * a / 2))
                B.append(R @ (np.array(top, dtype=float) * a / 2))
    Hc = a / np.sqrt(3.0)  # height between the base and the platform joints
    A = np.array(A) + [0.0, 0.0, Hc / 2]  # base joints in z = 0, cube centre at Hc / 2
    p = GSParams(
        A=tuple(map(tuple, A)),
        B=tuple(map(tuple, B)),  # platform frame at the cube centre
        rho_min=(0.6 * a,) * 6,
        rho_max=(1.4 * a,) * 6,
        z_home=Hc / 2,
        cylinder_length=0.5 * a,
    )
    return pkdyn.load("gough_stewart", **dataclasses.asdict(p)), Hc


def test_cubic_hexapod_matches_the_published_stiffness_and_transports():
    robot, Hc = _cubic_hexapod()
    k = 3e6
    S = stiffness(robot, robot.q_home, k)
    K_pub = k * np.diag([2, 2, 2, 1.5 * Hc**2, 1.5 * Hc**2, 6 * Hc**2])
    assert np.abs(S.K6 - K_pub).max() <= 1e-12 * np.abs(K_pub).max()
    # at another point of the platform (a tool 0.1 m above and aside): K' = T^-T K T^-1
    p = np.array([0.05, -0.03, 0.1])
    S2 = stiffness(robot, robot.q_home, k, point=p)
    assert np.allclose(S2.K6, transport(K_pub, p), rtol=1e-12, atol=1e-9 * k)
    # the force stiffness is the same at any point; couplings appear away from the centre
    assert np.allclose(S2.K6[:3, :3], K_pub[:3, :3], rtol=1e-12)
    assert np.abs(S2.K6[:3, 3:]).max() > 1e-2 * k * Hc


def _springs(robot, q, k):
    """The robot with its actuators replaced by joint springs held at the values of ``q``."""
    qa = q[robot.actuated_q]
    specs = [
        PassiveSpec(a.joint, stiffness=(float(ki),), rest=(float(x),))
        for a, ki, x in zip(robot.actuators, np.broadcast_to(k, qa.shape), qa, strict=True)
    ]
    return with_passive(robot, specs)


def _nonlinear(robot, q0, k, w, point=None):
    """Equilibrium under the dead wrench ``w`` (world, moment about ``point``), by statics.

    Unknowns: the actuated coordinates; the direct geometric model gives the configuration, and
    the existing statics the actuator efforts that would still be needed with the springs in
    place: zero at equilibrium.
    """
    point = np.zeros(3) if point is None else point
    sp = _springs(robot, q0, k)
    state = {"q": q0}

    def residual(qa):
        q = pkdyn.forward_geometry(sp, qa, q_init=state["q"], check_limits=False).q
        state["q"] = q
        M = sp.platform_placement(q)
        arm = M.rotation @ point
        F = np.concatenate([w[:3], M.rotation.T @ (w[3:] + np.cross(arm, w[:3]))])
        return static_equilibrium(sp, q, F).tau

    sol = scipy.optimize.root(residual, q0[robot.actuated_q], tol=1e-13)
    assert np.abs(residual(sol.x)).max() < 1e-9 * max(1.0, float(np.abs(w).max()))
    q = pkdyn.forward_geometry(sp, sol.x, q_init=state["q"], check_limits=False).q
    return q


def _displacement(robot, q0, q1, point=None):
    point = np.zeros(3) if point is None else point
    M0, M1 = robot.platform_placement(q0), robot.platform_placement(q1)
    return np.concatenate(
        [
            M1.act(point) - M0.act(point),
            pin.log3(M1.rotation @ M0.rotation.T),
        ]
    )


@pytest.mark.parametrize("name", ["gough_stewart", "delta"])
def test_deflection_and_loaded_tangent_match_nonlinear_equilibria(name):
    robot = pkdyn.load(name)
    q0 = robot.q_home
    k = 2e5 if name == "gough_stewart" else 2e3
    m = len(robot.task_rows)
    rng = np.random.default_rng(11)
    F = np.zeros(6)
    F[robot.task_rows] = rng.uniform(-1.0, 1.0, m) * (100.0 if m == 6 else 20.0)
    F[3:] *= 0.05  # moments [N m]
    # small load: K^-1 F is the nonlinear deflection to first order
    for scale in (1e-2, 1e-1):
        d_nl = _displacement(robot, q0, _nonlinear(robot, q0, k, scale * F))
        d_lin = stiffness(robot, q0, k, wrench=scale * F).deflection
        err = np.linalg.norm(d_lin - d_nl) / np.linalg.norm(d_nl)
        assert err < 2e-2 * scale  # second order: error proportional to the load
    # large load: the loaded mode's equilibrium is the same nonlinear one ...
    S = stiffness(robot, q0, k, wrench=F, loaded=True)
    q_nl = _nonlinear(robot, q0, k, F)
    d_nl = _displacement(robot, q0, q_nl)
    assert np.allclose(S.deflection, d_nl, rtol=0, atol=1e-9 * np.abs(d_nl).max())
    # ... and its tangent predicts the increment under a further small wrench
    dF = 1e-3 * np.where(F != 0.0, rng.uniform(-1.0, 1.0, 6), 0.0) * np.abs(F).max()
    inc = _displacement(robot, q_nl, _nonlinear(robot, q0, k, F + dF))
    tangent = np.linalg.norm(S.compliance6 @ dF - inc) / np.linalg.norm(inc)
    unloaded = np.linalg.norm(stiffness(robot, q0, k).compliance6 @ dF - inc) / np.linalg.norm(inc)
    assert tangent < 1e-3 and unloaded > 10 * tangent  # the geometric terms matter here


def test_leg_beams_in_series_with_the_actuators(gough_stewart):
    """A U-P-S leg carries axial force only: its beams add ``L / (E A)`` to each actuator.

    The cylinder over its length, the rod over its part outside the cylinder, which follows
    the stroke: ``rho - cylinder_length`` (issue 35 item 4), at poses across the stroke.
    """
    robot = gough_stewart
    k_a = 1e6
    p = robot.params
    A = Section(p.leg_radius).area
    home = robot.platform_placement(robot.q_home).translation
    for dz in (-0.08, 0.0, 0.08):
        q = pkdyn.inverse_geometry(robot, [0.01, -0.02, home[2] + dz]).q
        rho = q[robot.actuated_q]
        S = stiffness(robot, q, k_a, material=STEEL)
        outside = rho - p.cylinder_length
        assert np.all(outside > 0.0)
        k_leg = 1.0 / (1.0 / k_a + (p.cylinder_length + outside) / (STEEL.E * A))
        K_ref = stiffness(robot, q, k_leg, links=False).K
        assert np.abs(S.K - K_ref).max() <= 1e-10 * np.abs(K_ref).max()


def test_beam_compliance_by_castigliano():
    """Tip compliance = Hessian of the strain energy integrated along the beam."""
    L, sec, mat = 0.4, Section(0.01, 0.006), CARBON
    E, G, A, I, J = mat.E, mat.G, sec.area, sec.second_moment, sec.polar_moment
    kappa = sec.shear_coefficient(mat.poisson)
    s = np.linspace(0.0, L, 4001)

    def energy(w):
        F, M0 = w[:3], w[3:]
        # section at s carries the tip wrench moved to it: moment M0 + (tip - s) x F
        arm = np.zeros((s.size, 3))
        arm[:, 2] = L - s
        M = M0 + np.cross(arm, F)
        dens = (
            (M[:, 0] ** 2 + M[:, 1] ** 2) / (2 * E * I)
            + M[:, 2] ** 2 / (2 * G * J)
            + F[2] ** 2 / (2 * E * A)
            + (F[0] ** 2 + F[1] ** 2) / (2 * kappa * G * A)
        )
        return np.trapezoid(dens, s)

    C = np.empty((6, 6))  # U = w.C w / 2 is quadratic: exact Hessian by polarisation
    for i in range(6):
        for j in range(6):
            ei, ej = np.eye(6)[i], np.eye(6)[j]
            C[i, j] = (energy(ei + ej) - energy(ei - ej)) / 2.0
    assert np.allclose(tip_compliance(L, sec, mat), C, rtol=1e-6, atol=1e-15)


def test_extended_model_keeps_the_robot(delta):
    """Undeformed, the virtual-joint robot is the robot: placements and mass matrix."""
    em = elastic_model(delta, 2e4, material=CARBON)
    q = em.embed(delta.q_home)
    assert len(em.links) == 9  # three arms, six bars
    assert np.allclose(
        em.robot.platform_placement(q).homogeneous,
        delta.platform_placement(delta.q_home).homogeneous,
    )
    M = mass_matrix(em.robot, q)[np.ix_(em.v_index, em.v_index)]
    assert np.allclose(M, mass_matrix(delta, delta.q_home), atol=1e-12)
    assert np.max(np.abs(em.robot.closure_set.residual(em.robot.data, q))) < 1e-12


@pytest.mark.parametrize(
    "name, params, F",
    [
        ("gough_stewart", {}, [200.0, -100.0, -400.0, 10.0, 5.0, -8.0]),
        # hinged parallelograms: redundant closures, a hyperstatic mechanism once links deform
        ("delta", {"parallelogram": "hinge"}, [15.0, -10.0, -20.0, 0.3, -0.2, 0.4]),
    ],
)
def test_loaded_equilibrium_with_links_is_a_static_equilibrium(name, params, F):
    """The loaded solve on the virtual-joint robot: virtual work vanishes on every motion."""
    from pkdyn.precision.equilibrium import loaded_equilibrium

    robot = pkdyn.load(name, **params)
    k = 5e5 if name == "gough_stewart" else 2e3
    F = np.array(F)
    em = elastic_model(robot, k, material=Material("alloy", 4e10, 1.5e10, 2000.0))
    S = stiffness(em, robot.q_home, wrench=F, loaded=True)
    assert S.K6 is not None  # the links' compliance bounds every platform motion
    # a dead force is conservative; a moment fixed in world axes is not: the tangent's
    # antisymmetric part is -[m]x on the rotations, nothing else
    m = F[3:]
    skew = np.array([[0.0, -m[2], m[1]], [m[2], 0.0, -m[0]], [-m[1], m[0], 0.0]])
    expected = np.zeros((6, 6))
    expected[3:, 3:] = -skew
    assert np.allclose(S.K6 - S.K6.T, expected, atol=1e-6 * np.abs(S.K6).max())
    assert np.linalg.eigvalsh(0.5 * (S.K6 + S.K6.T))[0] > 0.0
    lin = stiffness(em, robot.q_home, wrench=F).deflection
    assert 0.0 < np.linalg.norm(S.deflection - lin) < 0.2 * np.linalg.norm(lin)
    q0 = em.embed(robot.q_home)
    q = loaded_equilibrium(em, q0, np.zeros(3), F).q
    # the springs' generalized force (joint, link and actuator springs) and the load's
    ext, P = em.robot, em.robot.passive
    stiff, rest = P.stiffness.copy(), P.rest.copy()
    stiff[ext.actuated_v] += k
    rest[ext.actuated_q] = q0[ext.actuated_q]
    f = PassiveForces(ext.model, stiffness=stiff, rest=rest).conservative_force(q)
    pin.computeJointJacobians(ext.model, ext.data, q)
    pin.updateFramePlacements(ext.model, ext.data)
    J = pin.getFrameJacobian(
        ext.model, ext.data, ext.platform_frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    )
    f += J.T @ F
    # ... does no work on the motions the closures allow: f = -Jc^T lambda for some lambda
    Jc = ext.closure_set.jacobian(ext.data, q)
    lam = np.linalg.lstsq(Jc.T, -f, rcond=None)[0]
    assert np.linalg.norm(Jc.T @ lam + f) < 1e-9 * np.linalg.norm(f)


def test_compliant_links_soften_the_hyperstatic_delta():
    robot = pkdyn.load("delta", parallelogram="hinge")
    S = stiffness(robot, robot.q_home, 2e4, material=STEEL)
    rigid = stiffness(robot, robot.q_home, 2e4, links=False)
    assert np.all(np.linalg.eigvalsh(rigid.K - S.K) > 0.0)
    assert S.K6 is not None and rigid.K6 is None


def test_described_compliance_is_the_beams(tmp_path):
    """``<pkdyn:compliance>`` and ``<pkdyn:stiffness>`` read back as the same model."""
    robot = pkdyn.load("five_bar")
    em = elastic_model(robot, 3e3, material=STEEL)
    xml = pkdyn.library.five_bar.build_urdf(robot.params)
    extra = []
    for lc in em.links:
        xyz = " ".join(f"{x:.17g}" for x in lc.placement.translation)
        rpy = " ".join(f"{x:.17g}" for x in pin.rpy.matrixToRpy(lc.placement.rotation))
        c = " ".join(f"{x:.17g}" for x in lc.compliance)
        extra.append(
            f'<pkdyn:compliance link="{lc.link}" compliance="{c}" xyz="{xyz}" rpy="{rpy}"/>'
        )
    xml = xml.replace("</robot>", "\n".join(extra) + "</robot>")
    xml = xml.replace(
        "<mechanicalReduction>", '<pkdyn:stiffness value="3e3"/><mechanicalReduction>'
    )
    path = tmp_path / "five_bar.urdf"
    path.write_text(xml)
    described = pkdyn.load(str(path))
    assert [a.stiffness for a in described.actuators] == [3e3, 3e3]
    q = described.q_home
    S1 = stiffness(described, q)
    S0 = stiffness(em, q)
    assert np.allclose(
        S1.compliance6, S0.compliance6, rtol=1e-9, atol=1e-12 * np.abs(S0.compliance6).max()
    )


def test_bad_input_names_the_value(gough_stewart, delta):
    robot, q = gough_stewart, gough_stewart.q_home
    for bad, word in ((-1.0, "-1"), (np.nan, "nan"), (0.0, "0"), ([1e6] * 4, "4 values")):
        with pytest.raises(InvalidInputError, match=word):
            stiffness(robot, q, bad)
    with pytest.raises(InvalidInputError, match="wrench.*5 values"):
        stiffness(robot, q, 1e6, wrench=[1, 2, 3, 4, 5])
    with pytest.raises(InvalidInputError, match="no stiffness described for actuator 'motor1'"):
        stiffness(robot, q)
    with pytest.raises(InvalidInputError, match="unknown material 'wood'"):
        stiffness(robot, q, 1e6, material="wood")
    bad_q = q.copy()
    bad_q[robot.actuated_q[0]] += 0.01
    with pytest.raises(InvalidInputError, match="not an assembled configuration"):
        stiffness(robot, bad_q, 1e6)
    # a serial singularity of the five-bar: its first chain stretched
    five = pkdyn.load("five_bar")
    phi = np.deg2rad(70.0)
    E = np.array([-0.1 + 0.5 * np.cos(phi), 0.5 * np.sin(phi)])
    qa2 = pkdyn.closed_form.five_bar.inverse(five.params, E)[0][0, 1]
    q_s = pkdyn.forward_geometry(five, [phi, qa2], check_limits=False).q
    with pytest.raises(SingularConfigurationError, match="unbounded"):
        stiffness(five, q_s, 1e3)
    # a parallel one: both elbows at the same point, the distal links free to turn about it
    q_p = pkdyn.forward_geometry(five, [np.pi / 3, 2 * np.pi / 3], check_limits=False).q
    with pytest.raises(SingularConfigurationError, match="undefined"):
        stiffness(five, q_p, 1e3)
