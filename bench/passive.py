"""Passive elements: the cost of springs, dampers and friction in the dynamics.

Delta with a balancing spring per arm (two-frame springs), a joint spring and damper on each
arm and dampers on the ball joints: ``PassiveForces.evaluate`` (generalized force and dissipated
power) against the raw ``pin.constraintDynamics`` call it accompanies in every dynamics
evaluation, and a forward Euler step with the elements against the same step without them.

Run ``python bench/passive.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from timing import Row, consistent_state, paired, print_table, us

import pkdyn
from pkdyn.dynamics.balancing import delta_balancing_springs
from pkdyn.model.description import PassiveSpec, SpringSpec
from pkdyn.model.passive import with_passive
from solvers import Actuation, ForwardDynamics


def rows(n: int = 1000) -> list[Row]:
    plain = pkdyn.load("delta", geometry=False)
    springs = [
        SpringSpec(s.name, s.frame1, s.frame2, 600.0, 0.0) for s in delta_balancing_springs(plain)
    ]
    joints = [PassiveSpec(f"arm{i}", (2.0,), (0.3,), damping=(0.05,)) for i in (1, 2, 3)]
    joints += [PassiveSpec(f"bar{i}{s}_upper", damping=(0.01,)) for i in (1, 2, 3) for s in "ab"]
    robot = with_passive(plain, joints, springs)
    assert robot.passive is not None
    passive = robot.passive
    model = robot.model
    q, v = consistent_state(robot)
    act = Actuation(robot.actuated_v)
    fd0 = ForwardDynamics(model, robot.constraint_models, act, integrator="euler", project=False)
    fd = ForwardDynamics(
        model, robot.constraint_models, act, passive=passive, integrator="euler", project=False
    )
    data, cms, cds, prox = fd0.data, fd0.constraint_models, fd0.constraint_datas, fd0.prox
    zero = np.zeros(model.nv)

    def raw() -> None:
        pin.constraintDynamics(model, data, q, v, zero, cms, cds, prox)

    t_p, t_raw, r_p = paired(lambda: passive.evaluate(q, v), raw, n)
    t_s, t_s0, r_s = paired(lambda: fd.step(0.0, q, v, 1e-3), lambda: fd0.step(0.0, q, v, 1e-3), n)
    return [
        (
            "delta: `PassiveForces.evaluate` (3 two-frame springs, 3 joint springs, 9 dampers) "
            "vs raw `pin.constraintDynamics`",
            f"{us(t_p)} vs {us(t_raw)}: {r_p:.2f}x",
            "-",
        ),
        (
            "delta: forward step `euler` with these passive elements vs without",
            f"{us(t_s)} vs {us(t_s0)}: {r_s:.2f}x",
            "-",
        ),
    ]


if __name__ == "__main__":
    print_table(rows())
