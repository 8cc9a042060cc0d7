"""Output step and integration step: recording at the output rate, the bare Euler loop, the
Euler gains, projections only where the closures drift past the tolerance."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.dynamics import simulate
from solvers import Actuation, ForwardDynamics


@pytest.fixture(scope="module")
def delta() -> pkdyn.Robot:
    return pkdyn.load("delta", geometry=False)


def _raw_euler(robot, q, v, h, n, gains):
    """The plainest Euler loop: constraintDynamics + integrate, the given Baumgarte gains."""
    model = robot.model
    data = model.createData()
    cms = pin.StdVec_RigidConstraintModel()
    cds = pin.StdVec_RigidConstraintData()
    for cm in robot.constraint_models:
        c = pin.RigidConstraintModel(cm)
        c.setBaumgarteCorrectorParameters(pin.BaumgarteCorrectorParameters(*gains))
        cms.append(c)
        cds.append(c.createData())
    pin.initConstraintDynamics(model, data, cms, cds)
    prox = pin.ProximalSettings(1e-12, 1e-12, 1e-6, 30)
    zero = np.zeros(model.nv)
    for _ in range(n):
        v = v + h * pin.constraintDynamics(model, data, q, v, zero, cms, cds, prox)
        q = pin.integrate(model, q, h * v)
    return q, v


def test_euler_substeps_are_the_raw_loop_and_records_follow_the_output_step(delta):
    """20 output steps of 1 ms, 50 Euler steps each, no projection: the same states as the
    raw loop with the automatic gains (critically damped at 0.5 / h), 21 records; a torque
    function that returns zeros (the general inner loop) gives the same states too."""
    h, dt = 2e-5, 1e-3
    fd = ForwardDynamics(delta.model, delta.constraint_models, integrator="euler", project=False)
    res = fd.simulate(delta.q_home, np.zeros(delta.nv), 0.02, dt, step=h)
    assert res.t.size == 21 and res.extras["substeps"] == 1000
    np.testing.assert_allclose(np.diff(res.t), dt, rtol=1e-12)
    w = 0.5 / h
    assert fd.constraint_models[0].m_baumgarte_parameters.Kp == pytest.approx(w * w)
    assert fd.constraint_models[0].m_baumgarte_parameters.Kd == pytest.approx(2 * w)
    q_raw, v_raw = _raw_euler(delta, delta.q_home, np.zeros(delta.nv), h, 1000, (w * w, 2 * w))
    assert np.max(np.abs(pin.difference(delta.model, q_raw, res.q[-1]))) < 1e-12
    assert np.max(np.abs(v_raw - res.v[-1])) < 1e-10
    act = Actuation(delta.actuated_v)
    general = ForwardDynamics(
        delta.model, delta.constraint_models, act, integrator="euler", project=False
    ).simulate(delta.q_home, np.zeros(delta.nv), 0.02, dt, tau=lambda t, q, v: np.zeros(3), step=h)
    np.testing.assert_allclose(general.q[-1], res.q[-1], rtol=0, atol=1e-12)


def test_euler_at_small_steps_keeps_closures_and_energy(delta):
    """Passive fall from home, 0.5 s: Euler at 1e-5 s steps, 1 ms output. The Baumgarte gains
    hold most of the drift; the state is projected only at output steps where the residual
    exceeds 1e-9 (not at all of them), every recorded residual is below it, and the mechanical
    energy is kept to 0.1 % up to the crossing of the parallelograms' singularity (0.26 s;
    recorded: 8e-5)."""
    with pytest.warns(UserWarning, match="parallel singularity"):
        res = simulate(delta, 0.5, 1e-3, integrator="euler", step=1e-5)
    assert res.t.size == 501
    assert np.max(res.closure_residual) <= 1e-9
    assert 0 < res.projections < 500
    assert 0.2 < res.valid_until < 0.5
    assert res.energy_drift(res.valid_until) < 1e-3
    assert np.max(res.kinetic) > 0.05  # it did fall


def test_dopri5_substeps_bounded_by_step(delta):
    """``step`` caps the adaptive substeps of dopri5: a tenth of the output step gives at least
    ten substeps per output step."""
    res = simulate(delta, 0.01, 1e-3, step=1e-4)
    assert res.t.size == 11 and res.extras["substeps"] >= 100


def test_bad_step_is_refused(delta):
    with pytest.raises(pkdyn.PkdynError, match="step"):
        simulate(delta, 0.01, 1e-3, step=0.0)
