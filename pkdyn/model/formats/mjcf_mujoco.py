"""Actuator efforts from MuJoCo's inverse dynamics of an exported robot.

MuJoCo is an optional dependency (the ``dev`` extra): the function imports it when called. The
compiled export itself is :func:`pkdyn.model.formats.mjcf.mujoco_model`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from solvers.numerics import lstsq, machine_rtol

__all__ = ["actuator_efforts"]


def actuator_efforts(model: Any, data: Any) -> np.ndarray:
    """Actuator forces that explain MuJoCo's inverse dynamics through the closures.

    The least-squares solution of ``[moment^T  J_eq^T] [tau; lambda] = qfrc_inverse`` after
    ``mujoco.mj_inverse``, with ``J_eq`` the rows of MuJoCo's constraint Jacobian that belong to
    equality constraints (the closures) and ``moment`` the actuator moment arm (the gears).
    Unique when the actuation is not redundant, whatever the redundancy of the closure rows.

    Args:
        model: The ``mujoco.MjModel``.
        data: Its ``mujoco.MjData`` after ``mj_inverse``.

    Returns:
        Actuator forces (nu,) in actuation space (motor-side efforts for geared motors).

    """
    import mujoco

    nv, nefc = model.nv, data.nefc
    if mujoco.mj_isSparse(model):
        J = np.zeros((nefc, nv))
        mujoco.mju_sparse2dense(
            J, data.efc_J, data.efc_J_rownnz, data.efc_J_rowadr, data.efc_J_colind
        )
    else:
        J = np.asarray(data.efc_J).reshape(-1)[: nefc * nv].reshape(nefc, nv)
    eq = np.asarray(data.efc_type[:nefc]) == mujoco.mjtConstraint.mjCNSTR_EQUALITY
    moment = np.zeros((model.nu, nv))
    mujoco.mju_sparse2dense(
        moment, data.actuator_moment, data.moment_rownnz, data.moment_rowadr, data.moment_colind
    )
    A = np.hstack([moment.T, J[eq].T])
    x = lstsq(A, np.asarray(data.qfrc_inverse), machine_rtol(A))
    return np.asarray(x[: model.nu])
