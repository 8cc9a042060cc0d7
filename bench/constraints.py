"""The constraint layer's cost: a planar loop closed by hinges against the same loop by points.

A planar ladder of 27 four-bar loops (81 velocity coordinates, every axis along ``z``): two
serial rails and, on each rung of the first, a crank whose tip the loop closes onto the second
rail, by a ``hinge`` (about ``z``) or by a ``point``. The same mechanism either way: the hinge's
out-of-plane rows vanish by construction.

- Pinocchio's ``constraintDynamics`` on the hinge as two points (the former representation,
  6 rows per hinge, rank 5 spatially, 2 in the plane) against the points (3 rows each);
- pkdyn's forward evaluation (``ForwardDynamics``: the hinge reduced to its planar rows, given
  to Pinocchio as one point) on the two robots;
- the constraint layer's residual and Jacobian (the planar rows: 2 per closure) against the
  former closure set of the hinge robot (6 rows per closure).

Run ``python bench/constraints.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from timing import Row, consistent_state, paired, print_table, us

import pkdyn
from solvers.forward_dynamics import ForwardDynamics

RUNGS = 27
"""Loops of the ladder: 3 coordinates each, 81 in all."""


def ladder(kind: str, rungs: int = RUNGS) -> str:
    """The ladder's description, its loops closed by ``kind`` (``hinge`` or ``point``)."""
    inertia = '<inertia ixx="1e-3" iyy="1e-3" izz="1e-3" ixy="0" ixz="0" iyz="0"/>'

    def link(name: str, com: str) -> str:
        return (
            f'<link name="{name}"><inertial><origin xyz="{com}"/><mass value="0.2"/>{inertia}'
            "</inertial></link>"
        )

    def joint(name: str, parent: str, child: str, xyz: str) -> str:
        return (
            f'<joint name="{name}" type="revolute"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{xyz}"/><axis xyz="0 0 1"/>'
            '<limit lower="-3" upper="3" effort="10" velocity="10"/></joint>'
        )

    parts = ['<link name="base"/>']
    axis = ' axis="0 0 1"' if kind == "hinge" else ""
    for k in range(rungs):
        pa = "base" if k == 0 else f"a{k - 1}"
        pb = "base" if k == 0 else f"b{k - 1}"
        step = "0 0 0" if k == 0 else "0 0.1 0"
        parts += [
            link(f"a{k}", "0 0.05 0"),
            link(f"b{k}", "0 0.05 0"),
            link(f"r{k}", "0.15 0 0"),
            joint(f"ja{k}", pa, f"a{k}", step),
            joint(f"jb{k}", pb, f"b{k}", "0.3 0 0" if k == 0 else step),
            joint(f"jr{k}", f"a{k}", f"r{k}", "0 0 0"),
            f'<pkdyn:closure name="loop{k}" type="{kind}"{axis}>'
            f'<pkdyn:frame link="r{k}" xyz="0.3 0 0"/><pkdyn:frame link="b{k}" xyz="0 0 0"/>'
            "</pkdyn:closure>",
        ]
    return '<robot name="ladder" xmlns:pkdyn="urn:pkdyn:urdf:1">' + "".join(parts) + "</robot>"


def rows(n: int = 300) -> list[Row]:
    hinge = pkdyn.load_string(ladder("hinge"), "ladder (hinges)")
    point = pkdyn.load_string(ladder("point"), "ladder (points)")
    model = hinge.model
    assert model.nv == 3 * RUNGS
    q, v = consistent_state(point)
    zero = np.zeros(model.nv)

    def raw(robot: pkdyn.Robot) -> object:
        fd = ForwardDynamics(model, list(robot.constraint_models))  # Pinocchio's models
        data, cms, cds, prox = fd.data, fd.constraint_models, fd.constraint_datas, fd.prox
        return lambda: pin.constraintDynamics(model, data, q, v, zero, cms, cds, prox)

    t_h, t_p, r_raw = paired(raw(hinge), raw(point), n)  # type: ignore[arg-type]
    fd_h = ForwardDynamics(model, hinge.constraints)
    fd_p = ForwardDynamics(model, point.constraints)
    a_h = fd_h.acceleration(q, v, zero)
    a_p = fd_p.acceleration(q, v, zero)
    agree = float(np.abs(a_h - a_p).max() / max(np.abs(a_p).max(), 1e-300))
    former = np.array(raw(hinge)())  # type: ignore[operator]
    agree_former = float(np.abs(a_h - former).max() / max(np.abs(a_p).max(), 1e-300))
    p_h, p_p, r_fd = paired(lambda: fd_h._accel(q, v, zero), lambda: fd_p._accel(q, v, zero), n)
    _, _, r_vs_raw = paired(lambda: fd_h._accel(q, v, zero), raw(hinge), n)  # type: ignore[arg-type]
    kin = model.createData()
    new, old = hinge.constraints, hinge.closure_set
    c_new, c_old, r_c = paired(
        lambda: new.residual_and_jacobian(kin, q), lambda: old.residual_and_jacobian(kin, q), n
    )
    return [
        (
            f"planar ladder, {RUNGS} loops, nv = {model.nv}: `pin.constraintDynamics`, hinges as "
            "two points (6 rows each, the former representation) vs points (3 rows each)",
            f"{us(t_h)} vs {us(t_p)}: {r_raw:.2f}x",
            "issue 37: 2x",
        ),
        (
            "... pkdyn forward evaluation (`ForwardDynamics`: a planar hinge is one point for "
            "Pinocchio), hinges vs points (accelerations agree to "
            f"{agree:.1e}; with the former two-point call to {agree_former:.1e})",
            f"{us(p_h)} vs {us(p_p)}: {r_fd:.2f}x; hinges {r_vs_raw:.2f}x the former call",
            "~1x",
        ),
        (
            f"... constraint rows (residual and Jacobian): the layer's {new.n} planar rows vs the "
            f"former closure set's {old.n}",
            f"{us(c_new)} vs {us(c_old)}: {r_c:.2f}x",
            "-",
        ),
    ]


if __name__ == "__main__":
    print_table(rows())
