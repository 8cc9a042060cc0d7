"""The min-max effort QP (solvers/minmax_effort.py) against an independent LP (HiGHS)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from scipy.optimize import linprog

from solvers import Actuation
from solvers.minmax_effort import MinMaxInverseDynamics

# The reduced equations E tau = f of the four-branch walker at t = 8.7 s of the 3 m cylinder
# plan (sample 174, PP mode, forces in N): proxqp's default infeasibility threshold declared this
# feasible, unbounded problem infeasible (`pkdyn tripod scenario --branches 4 --allocation max
# --surface-radius 3` stopped there).
E_WALKER = np.array(
    [
        [-0.366728207550872, -0.36182858374710075, -0.34800482373872643, -0.3459237635259721,
         -0.36269031459514856, -0.3616061692474043, -0.34211816943548157, -0.33833675894868787],
        [-0.0754588638692038, -0.14184418706597451, -0.48284431007690987, -0.47228881480346063,
         0.07390270723919794, 0.12223077719577279, 0.5054114256072498, 0.49208551282428364],
        [0.5047087333630524, 0.4885373096916198, -0.08783893050110644, -0.13840998167922416,
         -0.4835706072225022, -0.47551070489338276, 0.06203701465400185, 0.12620553451174155],
        [0.00484677220803199, 0.04439846497662216, -0.5043634542367217, 0.513040867962913,
         -0.05400466840649142, -0.01454180401346772, 0.49319586071786886, -0.4837785998101263],
        [0.07111412808548194, -0.06251916461063106, 0.2990863912038021, -0.32790557845291146,
         0.5228699575518048, -0.5248011215645312, 0.35701195808443803, -0.3432093371956505],
        [-0.5991841674054912, 0.6116718863816117, -0.1853828303686669, 0.11903506091323018,
         0.29103737930404205, -0.27197714753381014, -0.14888436124579646, 0.19354281041276986],
    ]
)  # fmt: skip
F_WALKER = np.array(
    [-157.07043228345597, 7.436488977577349, 12.058455607464976, -38.554052895354005,
     -13.498966299910238, -21.08283964539454]
)  # fmt: skip


def _solver(n: int, weights: np.ndarray, bound: float | None = None) -> MinMaxInverseDynamics:
    """A min-max solver with ``n`` actuators (a chain of prismatic joints; no closures)."""
    model = pin.Model()
    parent = 0
    for k in range(n):
        parent = model.addJoint(parent, pin.JointModelPZ(), pin.SE3.Identity(), f"j{k}")
        model.appendBodyToJoint(parent, pin.Inertia.FromSphere(1.0, 0.1), pin.SE3.Identity())
    lims = None if bound is None else np.full(n, bound)
    return MinMaxInverseDynamics(
        model, [], Actuation(np.arange(n)), None if lims is None else -lims, lims, weights
    )


def _lp_min_max(E: np.ndarray, f: np.ndarray, bound: float | None = None) -> float:
    """Least largest |tau_i| with E tau = f (HiGHS), optionally |tau_i| <= bound."""
    n = E.shape[1]
    eye, ones = np.eye(n), np.ones((n, 1))
    res = linprog(
        np.r_[np.zeros(n), 1.0],
        A_ub=np.vstack([np.hstack([eye, -ones]), np.hstack([-eye, -ones])]),
        b_ub=np.zeros(2 * n),
        A_eq=np.hstack([E, np.zeros((E.shape[0], 1))]),
        b_eq=f,
        bounds=[(-bound, bound) if bound else (None, None)] * n + [(0, None)],
        method="highs",
    )
    assert res.status == 0
    return float(res.fun)


@pytest.mark.parametrize("scale", [1.0, 1e-3, 1e3])
def test_min_max_on_the_walker_equations_matches_the_lp(scale):
    solver = _solver(8, np.full(8, 1.0 / 3000.0**2))
    tau, _ = solver._qp_solve(E_WALKER, scale * F_WALKER, scale * 517.86, None)
    assert np.max(np.abs(E_WALKER @ tau - scale * F_WALKER)) < 1e-8 * scale
    assert np.max(np.abs(tau)) == pytest.approx(_lp_min_max(E_WALKER, scale * F_WALKER), rel=1e-6)


def test_min_max_with_bounds_and_random_equations_matches_the_lp():
    rng = np.random.default_rng(7)
    for _ in range(20):
        E = np.linalg.qr(rng.normal(size=(8, 6)))[0].T  # orthonormal rows, as the reduction
        f = rng.normal(scale=rng.choice([1e-2, 1.0, 1e3]), size=6)
        best = _lp_min_max(E, f)
        solver = _solver(8, np.ones(8), bound=1.5 * best)
        tau, _ = solver._qp_solve(E, f, float(np.max(np.abs(f))), None)
        assert np.max(np.abs(E @ tau - f)) < 1e-8 * max(1.0, float(np.max(np.abs(f))))
        assert np.max(np.abs(tau)) == pytest.approx(best, rel=1e-6, abs=1e-9)
