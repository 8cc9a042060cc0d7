"""Precision benchmarks (issue 26): stiffness and frequency maps, closed forms and general path.

- Closed forms (:mod:`pkdyn.precision.vectorised`): the library Gough-Stewart's and Delta's
  smallest translational stiffness and deflection (and the Delta's lowest frequency) over
  100,000 poses at once, poses per CPU second; target >= 1e5 /s.
- General path, per assembled configuration: :func:`pkdyn.precision.maps` 's lean evaluation
  (the virtual-joint condensation: closure and platform Jacobians, a null space, the compliance)
  against the floor of the same computation in raw Pinocchio and numpy (closure Jacobian by
  ``getConstraintsJacobian``, frame Jacobian, SVD null space, ``J_z K_z^-1 J_z^T``); target
  >= 2e3 /s. The public :func:`pkdyn.precision.stiffness` (checks, principal stiffnesses, ``K6``)
  and :func:`pkdyn.precision.modes.modes` are given beside.
- General path, whole map: inverse geometric model (warm-started) plus stiffness per pose.

Run ``python bench/precision.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from timing import Row, median_us, paired, print_table, us

import pkdyn
from pkdyn.precision import elastic_model, stiffness
from pkdyn.precision.maps import pose_figures, translational
from pkdyn.precision.modes import modes

N_MAP = 100_000


def closed_forms() -> list[Row]:
    out: list[Row] = []
    rng = np.random.default_rng(0)
    for name, k, spread, frequency in (
        ("gough_stewart", 2e6, 0.03, False),
        ("delta", 2e4, 0.08, False),
        ("delta", 2e4, 0.08, True),
    ):
        robot = pkdyn.load(name, geometry=False)
        home = robot.platform_placement(robot.q_home).translation
        P = home + rng.uniform(-spread, spread, (N_MAP, 3))
        w = np.array([10.0, 0.0, -50.0, 0.0, 0.0, 0.0])

        def run(robot=robot, P=P, k=k, frequency=frequency, w=w) -> None:
            pose_figures(robot, P, None, k, wrench=w, frequency=frequency, method="closed")

        t = median_us(run, 1, repeats=5)
        what = "stiffness, deflection" + (", lowest frequency" if frequency else "")
        out.append(
            (
                f"{name}: closed-form {what} of {N_MAP:,} poses, vectorised",
                f"**{N_MAP / (t * 1e-6):.3g} poses/s** ({t / 1e3:.0f} ms)",
                ">= 1e5/s",
            )
        )
    return out


def _raw_floor(robot: pkdyn.Robot, q: np.ndarray, k: float) -> None:
    """The same condensation with raw Pinocchio calls and numpy (rigid links)."""
    model, data = robot.model, robot.data
    pin.computeJointJacobians(model, data, q)
    cds = pin.StdVec_RigidConstraintData()
    for cm in robot.constraint_models:
        cds.append(cm.createData())
    for cm, cd in zip(robot.constraint_models, cds, strict=True):
        cm.calc(model, data, cd)
    Jc = pin.getConstraintsJacobian(model, data, robot.constraint_models, cds)
    pin.updateFramePlacements(model, data)
    Jp = pin.getFrameJacobian(
        model, data, robot.platform_frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    )
    _, s, Vt = np.linalg.svd(Jc)
    N = Vt[int(np.sum(s > 1e-9 * s[0])) :].T
    Kz = (N[robot.actuated_v].T * k) @ N[robot.actuated_v]
    w, V = np.linalg.eigh(Kz)
    keep = w > 1e-12 * w[-1]
    JV = Jp @ N @ V[:, keep]
    C = (JV / w[keep]) @ JV.T
    np.linalg.eigvalsh(C[:3, :3])


def general_path() -> list[Row]:
    out: list[Row] = []
    for name, k, material in (
        ("gough_stewart", 2e6, None),
        ("delta", 2e4, None),
        ("gough_stewart", 2e6, "steel"),
    ):
        robot = pkdyn.load(name, geometry=material is not None)
        em = elastic_model(robot, k, material=material)
        q = robot.q_home
        label = f"{name}" + (f", {material} links ({len(em.links)} beams)" if material else "")
        if material is None:
            t, t_raw, ratio = paired(
                lambda em=em, q=q: translational(em, q, np.zeros(3), None),
                lambda robot=robot, q=q, k=k: _raw_floor(robot, q, k),
                200,
            )
            out.append(
                (
                    f"{label}: stiffness per configuration, general path (virtual-joint "
                    "condensation) / raw Pinocchio + numpy floor",
                    f"**{1e6 / t:.3g} poses/s** ({us(t)}) vs {us(t_raw)}: {ratio:.2f}x",
                    ">= 2e3/s",
                )
            )
        else:
            t = median_us(lambda em=em, q=q: translational(em, q, np.zeros(3), None), 50)
            out.append((f"{label}: stiffness per configuration", f"{1e6 / t:.3g} poses/s", "-"))
        t_pub = median_us(lambda em=em, q=q: stiffness(em, q), 50)
        t_modes = median_us(lambda em=em, q=q: modes(em, q), 20, repeats=5)
        out.append(
            (
                f"{label}: public `stiffness()` (checks, principal stiffnesses, K6) / "
                "`modes()`, per configuration",
                f"{us(t_pub)} / {us(t_modes)}",
                "-",
            )
        )
    # a whole map on the general path: the inverse geometric model for each pose, then stiffness
    robot = pkdyn.load("gough_stewart", geometry=False)
    home = robot.platform_placement(robot.q_home).translation
    P = home + np.random.default_rng(1).uniform(-0.02, 0.02, (200, 3))
    P = P[np.argsort(P[:, 0])]  # neighbours near each other: warm starts

    def general_map() -> None:
        pose_figures(robot, P, None, 2e6, method="general", progress=False)

    t = median_us(general_map, 1, repeats=3)
    out.append(
        (
            "gough_stewart: general-path map, inverse geometric model + stiffness per pose",
            f"{len(P) / (t * 1e-6):.3g} poses/s",
            "-",
        )
    )
    return out


def rows() -> list[Row]:
    return closed_forms() + general_path()


if __name__ == "__main__":
    print_table(rows())
