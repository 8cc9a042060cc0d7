r"""Beam model of a link: the 6x6 compliance of a straight rod or tube clamped at one end.

A link of length ``L`` along its local ``z`` axis, clamped at its root (``z = 0``), loaded at its
tip (``z = L``) by a wrench ``w = [F; M]`` (force; moment about the tip), tip frame axes. Its tip
moves by ``d = [delta; phi]`` (translation; rotation vector), ``d = C w``, with (Euler-Bernoulli
bending, Timoshenko shear, Saint-Venant torsion, circular section: ``I_x = I_y = I``)

.. math::

    C = \begin{bmatrix}
      \frac{L^3}{3EI} + \frac{L}{\kappa G A} & 0 & 0 & 0 & \frac{L^2}{2EI} & 0 \\
      0 & \frac{L^3}{3EI} + \frac{L}{\kappa G A} & 0 & -\frac{L^2}{2EI} & 0 & 0 \\
      0 & 0 & \frac{L}{EA} & 0 & 0 & 0 \\
      0 & -\frac{L^2}{2EI} & 0 & \frac{L}{EI} & 0 & 0 \\
      \frac{L^2}{2EI} & 0 & 0 & 0 & \frac{L}{EI} & 0 \\
      0 & 0 & 0 & 0 & 0 & \frac{L}{GJ}
    \end{bmatrix}

(``kappa``: Cowper's shear coefficient of a circular tube, with the material's Poisson ratio
when it is isotropic, else from the section alone: :meth:`Section.shear_coefficient`; no shear
term with ``shear=False``: the Euler-Bernoulli beam). Expressed at the beam's **elastic
centre** (its mid-point, the tip body's
motion taken there) the coupling terms vanish: the compliance is diagonal,
``diag(L^3/(12EI) + L/(kappa G A), same, L/(EA), L/(EI), L/(EI), L/(GJ))``. pkdyn's virtual-joint
model (:mod:`pkdyn.precision.elastic`) puts each link's 6-DOF virtual spring there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.arguments import public
from pkdyn.precision.material import Material

__all__ = ["Section", "centre_compliance", "tip_compliance"]


@dataclass(frozen=True)
class Section:
    """A circular cross-section, solid or hollow.

    Attributes:
        radius: Outer radius [m].
        inner_radius: Bore radius [m] (0: a solid rod).

    Raises:
        InvalidInputError: Radii not finite, ``radius <= 0`` or ``inner_radius`` outside
            ``[0, radius)``.

    """

    radius: float
    inner_radius: float = 0.0

    def __post_init__(self) -> None:
        from pkdyn.inputs import non_negative, positive

        r = positive("radius", self.radius, "m")
        ri = non_negative("inner_radius", self.inner_radius, "m")
        if not ri < r:
            raise InvalidInputError("inner_radius", f"must lie in [0, radius = {r:g}) m, got {ri}")

    @property
    def area(self) -> float:
        """Cross-section area ``A`` [m^2]."""
        return math.pi * (self.radius**2 - self.inner_radius**2)

    @property
    def second_moment(self) -> float:
        """Second moment of area about a diameter ``I`` [m^4]."""
        return math.pi / 4.0 * (self.radius**4 - self.inner_radius**4)

    @property
    def polar_moment(self) -> float:
        """Torsion constant ``J = 2 I`` of a circular section [m^4]."""
        return 2.0 * self.second_moment

    def shear_coefficient(self, poisson: float | None = None) -> float:
        """Cowper's shear coefficient ``kappa`` of a circular tube.

        ``6 (1 + nu) (1 + m^2)^2 / ((7 + 6 nu) (1 + m^2)^2 + (20 + 12 nu) m^2)`` with
        ``m = inner_radius / radius`` (0.886 for a solid steel rod, ``nu = 0.3``). Without a
        Poisson ratio (a material that is not isotropic, e.g. a carbon-fibre tube, whose
        ``E / (2 G) - 1`` is no Poisson ratio), the coefficient of the section alone,
        ``nu = 0``: ``6 (1 + m^2)^2 / (7 (1 + m^2)^2 + 20 m^2)`` (6/7 for a solid rod, 1/2 for
        a thin tube), with the shear modulus ``G`` as given.

        Args:
            poisson: Poisson's ratio of an isotropic material, in ``[0, 0.5]``; ``None``: the
                section alone.

        Returns:
            ``kappa`` [-].

        """
        from pkdyn.inputs import real

        # (an equivalent isotropic laminate's may exceed 0.5)
        nu = 0.0 if poisson is None else real("poisson", poisson)
        m2 = (self.inner_radius / self.radius) ** 2
        return 6 * (1 + nu) * (1 + m2) ** 2 / ((7 + 6 * nu) * (1 + m2) ** 2 + (20 + 12 * nu) * m2)

    def mass(self, length: float, material: Material) -> float:
        """Mass of a straight piece of this section [kg] (``density A L``)."""
        from pkdyn.inputs import instance

        _check_length(length)
        instance("material", material, Material, "a Material (pkdyn.precision.STEEL...)")
        return material.density * self.area * float(length)

    def inertia(self, length: float, material: Material) -> pin.Inertia:
        """Inertia of a straight piece along ``z``, centred on the origin (a tube or a rod).

        ``m = density A L``; ``I_xx = I_yy = m (3 (r^2 + r_i^2) + L^2) / 12``,
        ``I_zz = m (r^2 + r_i^2) / 2`` [kg, kg m^2].
        """
        m = self.mass(length, material)
        r2 = self.radius**2 + self.inner_radius**2
        I_t = m * (3.0 * r2 + length**2) / 12.0
        return pin.Inertia(m, np.zeros(3), np.diag([I_t, I_t, 0.5 * m * r2]))


def _check_length(length: float) -> None:
    from pkdyn.inputs import positive

    positive("length", length, "m", bound=MAX_LENGTH)


MAX_LENGTH = 1e3
"""Longest beam [m] (its compliance grows like the length cubed: beyond, a unit error)."""


def _check_parts(section: Any, material: Any) -> None:
    from pkdyn.inputs import instance

    instance("section", section, Section, "a Section (pkdyn.precision.Section)")
    instance("material", material, Material, "a Material (pkdyn.precision.STEEL...)")


@public
def centre_compliance(
    length: float, section: Section, material: Material, shear: bool = True
) -> np.ndarray:
    """Diagonal compliance (6,) of a cantilever beam at its elastic centre (mid-point).

    Args:
        length: Beam length ``L`` [m].
        section: Cross-section.
        material: Material.
        shear: Include Timoshenko's shear deflection (``False``: Euler-Bernoulli).

    Returns:
        ``[cx, cy, cz, crx, cry, crz]`` [m/N x3, rad/(N m) x3], beam axis ``z``.

    """
    _check_length(length)
    _check_parts(section, material)
    return _centre(float(length), section, material, shear)


def _centre(L: float, section: Section, material: Material, shear: bool) -> np.ndarray:
    """:func:`centre_compliance` of checked arguments."""
    E, G = material.E, material.G
    A, I, J = section.area, section.second_moment, section.polar_moment
    bend = L**3 / (12.0 * E * I)
    if shear:
        bend += L / (section.shear_coefficient(material.poisson) * G * A)
    return np.array([bend, bend, L / (E * A), L / (E * I), L / (E * I), L / (G * J)])


@public
def tip_compliance(
    length: float, section: Section, material: Material, shear: bool = True
) -> np.ndarray:
    """Compliance (6, 6) of a cantilever beam at its tip (the module's matrix ``C``).

    Args:
        length: Beam length ``L`` [m].
        section: Cross-section.
        material: Material.
        shear: Include Timoshenko's shear deflection.

    Returns:
        ``C`` mapping the tip wrench [N, N m] to the tip displacement [m, rad], tip axes.

    """
    c = centre_compliance(length, section, material, shear)
    # the tip body seen from the mid-point: transport the diagonal compliance by L / 2
    X = pin.SE3(np.eye(3), np.array([0.0, 0.0, length / 2.0])).toActionMatrixInverse()
    return np.asarray(X @ np.diag(c) @ X.T)
