"""What a loaded robot is: ``pkdyn info`` (sizes, mobility, actuators, closures, passive parts)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkdyn.model.description import CouplingSpec, LinearCouplingSpec
from pkdyn.model.robot import Robot
from pkdyn.results import Result, jsonable
from pkdyn.units import quantity

__all__ = ["RobotInfo", "robot_info"]


@dataclass
class RobotInfo(Result):
    """The summary of a robot (:func:`robot_info`).

    Attributes:
        name: Robot name.
        nq: Configuration size.
        nv: Velocity size.
        dof: Degrees of freedom of the platform (``Robot.mobility_split``).
        internal: Internal mobilities (that leave the platform still).
        loops: Independent kinematic loops.
        actuation: Per actuator: ``name``, ``joint``, ``type`` (prismatic or revolute),
            ``effort`` [N m or N] and ``velocity`` [rad/s or m/s] limits (``None``: none),
            ``reduction``, ``units``.
        closures: Per closure: ``name`` and ``type`` (point, hinge, weld).
        couplings: Per joint coupling: ``name``, ``joint``, ``source``, ``coefficients``
            (constant term first), ``joint_ref``, ``source_ref``.
        passive: The passive elements (:func:`pkdyn.model.passive.passive_summary`).

    """

    name: str
    nq: int
    nv: int
    dof: int
    internal: int
    loops: int
    actuation: list[dict[str, Any]]
    closures: list[dict[str, str]]
    couplings: list[dict[str, Any]] = field(default_factory=list)
    passive: dict[str, Any] = field(default_factory=dict)
    prismatic: frozenset[str] = frozenset()
    """Names of the prismatic joints (their passive elements in N/m, m, N s/m, N)."""

    def to_json(self) -> dict[str, Any]:
        """The summary as JSON values (limits ``None`` where there is none)."""
        return jsonable(
            {
                "name": self.name,
                "nq": self.nq,
                "nv": self.nv,
                "dof": self.dof,
                "internal": self.internal,
                "actuated": [a["joint"] for a in self.actuation],
                "actuators": [a["name"] for a in self.actuation],
                "actuation": self.actuation,
                "loops": self.loops,
                "closures": self.closures,
                "couplings": self.couplings,
                "passive": self.passive,
            }
        )

    def table(self) -> str:
        """Sizes and mobility, the actuators with their limits, closures, couplings, passive."""
        lines = [
            f"{self.name}: nq={self.nq} nv={self.nv} dof={self.dof} internal={self.internal} "
            f"loops={self.loops}",
            "actuated: " + ", ".join(_actuator(a) for a in self.actuation),
            "closures: "
            + (", ".join(f"{c['name']} ({c['type']})" for c in self.closures) or "none"),
        ]
        if self.couplings:
            lines.append("couplings: " + ", ".join(_coupling(c) for c in self.couplings))
        lines.append("passive: " + (_passive(self.passive, self.prismatic) or "none"))
        return "\n".join(lines)


def _actuator(a: dict[str, Any]) -> str:
    u = a["units"]
    eff = "-" if a["effort"] is None else quantity(a["effort"], u["effort"])
    vel = "-" if a["velocity"] is None else quantity(a["velocity"], u["velocity"])
    return f"{a['joint']} ({a['name']}, {a['type']}, {eff}, {vel})"


def _coupling(c: dict[str, Any]) -> str:
    """``name (joint from source, coefficients ...)`` or ``name (a1 joint1 + a2 joint2 = b)``."""
    if "terms" in c:  # a linear coupling over any number of joints
        parts = []
        for t in c["terms"]:
            a = float(t["coefficient"])
            scale = "" if abs(a) == 1.0 else f"{abs(a):.6g} "
            parts.append(f"{'-' if a < 0 else '+'} {scale}{t['joint']}")
        lhs = " ".join(parts).removeprefix("+ ")
        return f"{c['name']} ({lhs} = {c['offset']:.6g})"
    coef = " ".join(f"{v:.6g}" for v in c["coefficients"])
    if c["source"] is None:
        return f"{c['name']} ({c['joint']} locked at {c['joint_ref'] + c['coefficients'][0]:.6g})"
    return f"{c['name']} ({c['joint']} from {c['source']}, coefficients {coef})"


def _values(x: list[float], unit: str) -> str:
    return ", ".join(quantity(v, unit) for v in x)


def _passive(passive: dict[str, Any], prismatic: frozenset[str] = frozenset()) -> str:
    """One line per passive element, with the units of its joint's kind (per degree of freedom)."""
    rows = []
    for e in passive.get("joints", []):
        p = e["joint"] in prismatic
        parts = []
        if "stiffness" in e:
            parts.append(
                f"stiffness {_values(e['stiffness'], 'N/m' if p else 'N m/rad')}, "
                f"rest {_values(e['rest'], 'm' if p else 'rad')}"
            )
        for k, unit in (
            ("damping", "N s/m" if p else "N m s/rad"),
            ("friction", "N" if p else "N m"),
            ("armature", "kg" if p else "kg m^2"),
        ):
            if k in e:
                parts.append(f"{k} {_values(e[k], unit)}")
        rows.append(f"\n  joint {e['joint']}: " + "; ".join(parts))
    for s in passive.get("springs", []):
        rows.append(
            f"\n  spring {s['name']} ({s['link1']} - {s['link2']}): "
            f"{quantity(s['stiffness'], 'N/m')}, free length {quantity(s['rest_length'], 'm')}, "
            f"tension at home {quantity(s['tension'], 'N')}"
        )
    return "".join(rows)


def _limit(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None


def _coupling_json(c: CouplingSpec | LinearCouplingSpec) -> dict[str, Any]:
    """A coupling's fields: ``terms`` and ``offset`` of a linear one, the polynomial's else."""
    if isinstance(c, LinearCouplingSpec):
        return {
            "name": c.name,
            "terms": [{"joint": j, "coefficient": a} for j, a in c.terms],
            "offset": c.offset,
        }
    return {
        "name": c.name,
        "joint": c.joint,
        "source": c.source,
        "coefficients": list(c.coefficients),
        "joint_ref": c.joint_ref,
        "source_ref": c.source_ref,
    }


def robot_info(robot: Robot) -> RobotInfo:
    """The summary of a robot: sizes, mobility split, actuators, closures, couplings, passive.

    Args:
        robot: The robot.

    Returns:
        The summary.

    """
    from pkdyn.model.passive import passive_summary

    dof, internal = robot.mobility_split()
    actuation = []
    for a, prismatic in zip(robot.actuators, robot.actuator_prismatic, strict=True):
        units = ("m", "m/s", "N") if prismatic else ("rad", "rad/s", "N m")
        actuation.append(
            {
                "name": a.name,
                "joint": a.joint,
                "type": "prismatic" if prismatic else "revolute",
                "effort": _limit(a.effort),
                "velocity": _limit(a.velocity),
                "reduction": a.reduction,
                "units": {"position": units[0], "velocity": units[1], "effort": units[2]},
            }
        )
    return RobotInfo(
        name=robot.name,
        nq=robot.nq,
        nv=robot.nv,
        dof=dof,
        internal=internal,
        loops=robot.loops,
        actuation=actuation,
        closures=[{"name": c.name, "type": c.kind} for c in robot.closures],
        couplings=[_coupling_json(c) for c in robot.couplings],
        passive=passive_summary(robot),
        prismatic=frozenset(
            str(robot.model.names[j])
            for j in range(1, robot.model.njoints)
            if robot.model.joints[j].shortname().startswith(("JointModelP", "JointModelPrismatic"))
            and not robot.model.joints[j].shortname().startswith("JointModelPlanar")
        ),
    )
