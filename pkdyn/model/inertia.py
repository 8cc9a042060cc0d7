"""Physically valid inertias: the nearest valid tensor, and how a load reports and repairs them.

A rigid body's rotational inertia about its centre of mass, ``I = R diag(l1, l2, l3) R^T``, is
physical when its principal moments satisfy the triangle inequalities ``l_j + l_k >= l_i`` (they
are then >= 0 too: adding two of them gives ``2 l_k >= 0``), i.e. when ``I = tr(S) 1 - S`` for a
positive semi-definite second-moment matrix ``S`` (whose eigenvalues are ``(l_j + l_k - l_i) /
2``). :func:`pkdyn.model.validate.inertia_problem` is the test every importer applies.

**Repair** (``pkdyn.load(..., repair_inertias=True)``, ``--repair-inertias``): the nearest
valid tensor in the Frobenius norm. The valid tensors form a convex set invariant under rotations,
so the nearest one keeps the principal axes ``R`` and replaces the principal moments by their
Euclidean projection onto the cone ``{l : l_j + l_k - l_i >= 0 for every i}``
(:func:`nearest_valid_moments`, an exact active-set solution of the 3-variable problem), lifted
by :data:`MARGIN` of their sum inside the cone so that rounding cannot undo it. A tensor that is
already valid is left unchanged, bit for bit; the mass and the centre of mass are
never changed; a negative or non-finite mass cannot be repaired and stays an error.

A body with rotational inertia and no mass is accepted as it is (a rotor whose mass the link it
turns in carries, as legged-robot descriptions model their motors): its dynamics are well
defined; the load says which links are read so.
"""

from __future__ import annotations

import itertools

import numpy as np

from pkdyn.model.warn import warn

__all__ = ["MARGIN", "massless_rotor", "nearest_valid_inertia", "nearest_valid_moments", "report"]

_G = np.array([[-1.0, 1.0, 1.0], [1.0, -1.0, 1.0], [1.0, 1.0, -1.0]])  # rows: l_j + l_k - l_i
_SHOWN = 4


MARGIN = 1e-9
"""A repaired tensor's principal moments are lifted by this fraction of their sum above the
cone's boundary (each triangle inequality then holds by that much): rounding in another tool's
eigen-decomposition (MuJoCo checks ``A + B >= C`` exactly) cannot make it invalid again."""


def nearest_valid_moments(moments: np.ndarray) -> np.ndarray:
    """Euclidean projection of principal moments onto the triangle-inequality cone.

    Args:
        moments: Principal moments (3,) [kg m^2], any order.

    Returns:
        The nearest ``l`` (3,) with ``l_j + l_k >= l_i`` for every ``i`` (``moments`` itself when
        it satisfies them).

    """
    lam = np.asarray(moments, dtype=float)
    if np.all(_G @ lam >= 0.0):
        return lam.copy()
    for k in (1, 2, 3):  # active sets: x = lam + G_S^T mu, mu >= 0, G x >= 0
        for rows in itertools.combinations(range(3), k):
            G = _G[list(rows)]
            mu = -np.linalg.solve(G @ G.T, G @ lam)
            x = lam + G.T @ mu
            scale = max(float(np.abs(lam).max()), 1e-300)
            if np.all(mu >= 0.0) and np.all(_G @ x >= -1e-12 * scale):
                return np.asarray(x)
    return np.zeros(3)  # the apex: reached above (all three active) but for rounding


def nearest_valid_inertia(inertia: np.ndarray) -> np.ndarray:
    """The nearest physically valid rotational inertia (Frobenius norm), same principal axes.

    Args:
        inertia: Rotational inertia about the centre of mass (3, 3) [kg m^2], symmetric.

    Returns:
        The repaired tensor (3, 3) (symmetric, satisfying the triangle inequalities); the input
        itself when it is valid.

    """
    I = np.asarray(inertia, dtype=float)
    S = 0.5 * (I + I.T)
    scale = float(np.abs(S).max())
    if scale == 0.0:
        return S
    lam, R = np.linalg.eigh(S / scale)
    fixed = nearest_valid_moments(lam)
    if np.array_equal(fixed, lam):
        return I
    fixed = fixed + MARGIN * max(float(fixed.sum()), 1.0)  # strictly inside, whatever rounds
    out = (R * fixed) @ R.T * scale
    return np.asarray(0.5 * (out + out.T))


def massless_rotor(mass: float, inertia: np.ndarray) -> bool:
    """A body with rotational inertia and no mass (a rotor whose mass its carrier holds)."""
    return mass == 0.0 and bool(np.any(np.asarray(inertia) != 0.0))


def _moments(I: np.ndarray) -> str:
    scale = float(np.abs(I).max())
    ev = np.linalg.eigvalsh(I / scale) * scale if scale > 0.0 else np.zeros(3)
    return " ".join(f"{v:.4g}" for v in ev)


def report(
    source: str,
    invalid: list[tuple[str, str]],
    repaired: list[tuple[str, np.ndarray, np.ndarray]],
    rotors: list[str],
    what: str = "link",
) -> None:
    """The warnings of a load about its inertias (nothing when all are valid).

    Args:
        source: File or robot name.
        invalid: ``(body, problem)`` of the tensors left as they are (no repair asked).
        repaired: ``(body, before, after)`` tensors (3, 3) of the repaired ones.
        rotors: Bodies with rotational inertia and no mass (accepted).
        what: How the format calls its bodies (``link``, ``body``).

    """

    def names(items: list[str]) -> str:
        more = f" and {len(items) - _SHOWN} more" if len(items) > _SHOWN else ""
        return ", ".join(items[:_SHOWN]) + more

    if invalid:
        warn(
            f"{source}: {len(invalid)} inertia tensor(s) no rigid body has, the dynamics are "
            "not physical: "
            + names([f"{what} '{b}' ({p})" for b, p in invalid])
            + "; load with repair_inertias=True (--repair-inertias) for the nearest valid ones"
        )
    if repaired:
        warn(
            f"{source}: {len(repaired)} inertia tensor(s) repaired to the nearest valid one "
            "(same principal axes, principal moments projected onto the triangle inequalities): "
            + names(
                [
                    f"{what} '{b}' ({_moments(before)} -> {_moments(after)} kg m^2)"
                    for b, before, after in repaired
                ]
            )
        )
    if rotors:
        warn(
            f"{source}: {len(rotors)} {what}(s) with rotational inertia and no mass, read as "
            "rotors whose mass their carrier holds: " + names([f"'{b}'" for b in rotors])
        )
