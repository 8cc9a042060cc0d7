"""Materials of the links modelled as beams: Young's and shear moduli, density.

Presets (:data:`MATERIALS`) are typical handbook values; a description names one
(``<pkdyn:material name="carbon"/>``) or gives its own constants (``E``, ``G``, ``density``),
and every function that takes a material accepts a preset name or a :class:`Material`.

``E`` and ``G`` are used as given: ``E`` in traction and bending, ``G`` in torsion and shear.
A material is **isotropic** when they are tied by a Poisson ratio ``nu = E / (2 G) - 1`` in
``[0, 0.5]`` (steel 0.30, aluminium 0.35); a fibre tube is not (carbon: ``E / (2 G) - 1 = 11``),
and no Poisson ratio is derived for it: the beams' shear coefficient then comes from the section
alone (:meth:`pkdyn.precision.beam.Section.shear_coefficient`).

The density sets a link's mass only where the description asks for it
(``mass="from-material"``); otherwise a material changes the stiffness only, and the links weigh
what the URDF's ``<inertial>`` says.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.description import MaterialSpec

__all__ = ["ALUMINIUM", "CARBON", "MATERIALS", "STEEL", "Material", "as_material"]


@dataclass(frozen=True)
class Material:
    """An isotropic (or, for a fibre tube, an equivalent isotropic) material.

    Attributes:
        name: Name, for messages and reports.
        E: Young's modulus [Pa] (axial stiffness and bending).
        G: Shear modulus [Pa] (torsion and Timoshenko shear).
        density: Density [kg/m^3] (a tube's mass: :meth:`pkdyn.precision.beam.Section.mass`).

    Raises:
        InvalidInputError: A constant that is not a finite number > 0.

    """

    name: str
    E: float
    G: float
    density: float

    def __post_init__(self) -> None:
        if not isinstance(self.name, str):
            raise InvalidInputError("name", f"a material's name is a string, got {self.name!r:.40}")
        for what in ("E", "G", "density"):
            value = getattr(self, what)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0.0):
                raise InvalidInputError(
                    f"material '{self.name}' {what}", f"must be a finite number > 0, got {value}"
                )

    @property
    def isotropic(self) -> bool:
        """``E / (2 G) - 1`` is a Poisson ratio (in ``[0, 0.5]``): an isotropic material."""
        return 0.0 <= self.E / (2.0 * self.G) - 1.0 <= 0.5

    @property
    def poisson(self) -> float | None:
        """Poisson's ratio ``E / (2 G) - 1`` of an isotropic material [-] (``None``: not one)."""
        return self.E / (2.0 * self.G) - 1.0 if self.isotropic else None


STEEL = Material("steel", E=210e9, G=81e9, density=7850.0)
"""Structural steel."""
ALUMINIUM = Material("aluminium", E=70e9, G=26e9, density=2700.0)
"""Aluminium alloy (6061 / 7075 class)."""
CARBON = Material("carbon", E=120e9, G=5e9, density=1600.0)
"""Pultruded / wound carbon-fibre tube, axial modulus and in-plane shear modulus of the laminate
(fibres mostly along the tube: stiff in bending and traction, soft in torsion)."""

MATERIALS: dict[str, Material] = {m.name: m for m in (STEEL, ALUMINIUM, CARBON)}
"""Presets by name (``aluminum`` is accepted for ``aluminium``)."""


def as_material(value: str | Material | MaterialSpec) -> Material:
    """A material from a preset name, a description's ``<pkdyn:material>``, or itself.

    Args:
        value: ``steel``, ``aluminium`` (or ``aluminum``), ``carbon``; a
            :class:`pkdyn.model.description.MaterialSpec` (a preset whose constants it may
            override, or a custom material with all three constants); or a :class:`Material`.

    Returns:
        The material.

    Raises:
        InvalidInputError: An unknown name, or a custom material with a constant missing.

    """
    if isinstance(value, Material):
        return value
    if isinstance(value, MaterialSpec):
        base = MATERIALS.get(_preset(value.name))
        given = {"E": value.E, "G": value.G, "density": value.density}
        if base is None:
            missing = [k for k, v in given.items() if v is None]
            if missing:
                raise InvalidInputError(
                    f"material '{value.name}'",
                    f"not a preset ({', '.join(MATERIALS)}) and {', '.join(missing)} not given",
                )
            return Material(value.name, **{k: float(v) for k, v in given.items()})  # type: ignore[arg-type]
        return Material(
            base.name,
            **{k: float(v if v is not None else getattr(base, k)) for k, v in given.items()},
        )
    found = MATERIALS.get(_preset(str(value)))
    if found is None:
        raise InvalidInputError(
            "material", f"unknown material '{value}'; presets: {', '.join(MATERIALS)}"
        )
    return found


def _preset(name: str) -> str:
    key = name.strip().lower()
    return "aluminium" if key == "aluminum" else key
