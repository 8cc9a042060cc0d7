"""pkdyn's exceptions: one base class, one subclass per kind of user error.

Every exception carries the offending element or value in its attributes and says, in its
message, what was found and how to fix it. The CLI prints ``str(err)`` on one line.
"""

from __future__ import annotations

import re
from typing import Any

__all__ = [
    "PkdynError",
    "DescriptionError",
    "UnknownRobotError",
    "ParameterError",
    "InvalidInputError",
    "AssemblyError",
    "LoopClosureError",
    "UnreachablePoseError",
    "JointLimitError",
    "SingularConfigurationError",
    "TrajectoryError",
    "InfeasibleEffortError",
    "LimitsExceededError",
    "SimulationError",
    "OutputError",
    "StudyError",
    "CatalogError",
    "NoFeasibleDriveError",
    "CalibrationError",
]


class PkdynError(Exception):
    """Base class of every error a pkdyn user can cause.

    Its message is one line (a library's multi-line message pasted into it is joined), and it
    crosses process boundaries (pickled with its attributes: a worker's error reaches the
    parent as raised).
    """

    def __str__(self) -> str:
        return re.sub(r"\s*[\r\n]+\s*", " ", super().__str__()).strip()

    def __reduce__(self) -> tuple[object, ...]:
        return _rebuild, (type(self), self.args, self.__dict__)


def _rebuild(cls: type[PkdynError], args: tuple[object, ...], state: dict[str, object]) -> Any:
    """Unpickle a :class:`PkdynError` without calling its ``__init__`` (whose signature varies)."""
    err = cls.__new__(cls)
    Exception.__init__(err, *args)
    err.__dict__.update(state)
    return err


def close_match(name: str, known: list[str]) -> str:
    """``; did you mean 'x'?`` with the closest of ``known`` to ``name``, or ``""``."""
    import difflib

    close = difflib.get_close_matches(name, known, n=2, cutoff=0.6)
    return "; did you mean " + " or ".join(f"'{c}'" for c in close) + "?" if close else ""


class DescriptionError(PkdynError):
    """A robot description (URDF, extension element or YAML sidecar) is malformed.

    Attributes:
        source: File or robot the description came from.
        culprit: The element, attribute or name at fault.

    """

    def __init__(self, source: str, culprit: str, message: str) -> None:
        self.source = source
        self.culprit = culprit
        super().__init__(f"{source}: {culprit}: {message}")


class UnknownRobotError(PkdynError):
    """Neither a library robot nor an existing file was named."""

    def __init__(self, name: str, known: list[str]) -> None:
        self.name = name
        self.known = known
        super().__init__(
            f"unknown robot '{name}': not a file and not one of the library robots "
            f"({', '.join(known)}){close_match(name, known)}"
        )


class ParameterError(PkdynError):
    """A builder parameter is unknown or has an invalid value."""

    def __init__(self, family: str, name: str, message: str) -> None:
        self.family = family
        self.name = name
        super().__init__(f"{family}: parameter '{name}': {message}")


class InvalidInputError(PkdynError):
    """A numeric input is malformed: wrong size, NaN or infinite."""

    def __init__(self, name: str, message: str) -> None:
        self.name = name
        super().__init__(f"{name}: {message}")


class AssemblyError(PkdynError):
    """The closures could not be satisfied (the geometry cannot be assembled).

    Attributes:
        closure: Name of the closure with the largest residual.
        residual: Its residual norm [m or rad].

    """

    def __init__(self, closure: str, residual: float, message: str) -> None:
        self.closure = closure
        self.residual = residual
        super().__init__(message)


class LoopClosureError(DescriptionError, AssemblyError):
    """A description whose loops cannot be closed in any configuration found when loading.

    Both a :class:`DescriptionError` (the description is at fault) and an
    :class:`AssemblyError` (with the closure and its residual).

    Attributes:
        source: File or robot the description came from.
        culprit: ``closure '<name>'`` (``coupling '<name>'`` when a joint coupling
            contradicts the closures).
        closure: Name of the closure (or coupling) with the largest residual.
        residual: Its residual at the best configuration found [m or rad].

    """

    def __init__(
        self, source: str, closure: str, residual: float, message: str, kind: str = "closure"
    ) -> None:
        self.source = source
        self.culprit = f"{kind} '{closure}'"
        self.closure = closure
        self.residual = residual
        PkdynError.__init__(self, message)


class UnreachablePoseError(AssemblyError):
    """A requested platform pose is outside what the mechanism can reach."""


class JointLimitError(PkdynError):
    """A solution exists but a joint (actuator stroke, angle) is outside its limits.

    Attributes:
        joint: Joint name.
        value: Joint value [rad or m].
        lower: Lower limit [rad or m].
        upper: Upper limit [rad or m].

    """

    def __init__(self, joint: str, value: float, lower: float, upper: float) -> None:
        self.joint = joint
        self.value = value
        self.lower = lower
        self.upper = upper
        super().__init__(
            f"joint '{joint}' would be at {value:.6g}, outside its limits "
            f"[{lower:.6g}, {upper:.6g}]; choose a pose inside the workspace"
        )


class SingularConfigurationError(PkdynError):
    """The configuration is exactly singular for the requested operation."""

    def __init__(self, kind: str, message: str) -> None:
        self.kind = kind
        super().__init__(message)


class TrajectoryError(PkdynError):
    """A trajectory cannot be mapped to the joints: out of reach, singular or not finite.

    Attributes:
        sample: Index of the first offending sample (``None`` for the trajectory as a whole).
        time: Its time [s] (``None`` if unknown).

    """

    def __init__(self, message: str, sample: int | None = None, time: float | None = None) -> None:
        self.sample = sample
        self.time = time
        where = (
            ""
            if sample is None
            else f"sample {sample}" + ("" if time is None else f" (t = {time:.6g} s)") + ": "
        )
        super().__init__(where + message)


class InfeasibleEffortError(PkdynError):
    """No actuator efforts within the limits realise the motion.

    Attributes:
        sample: Trajectory sample index (``None`` for a single state).
        actuator: Name of the actuator at fault (``None`` if the motion itself is inconsistent).

    """

    def __init__(self, message: str, sample: int | None = None, actuator: str | None = None):
        self.sample = sample
        self.actuator = actuator
        super().__init__(message)


class LimitsExceededError(PkdynError):
    """A motion was sized and exceeds actuator limits: the report stands, the answer is no.

    Raised by the command line after printing the sizing (``pkdyn size``): the margins are
    reported, and the exit status says the motion is not feasible.

    Attributes:
        exceeded: One phrase per limit exceeded (``motor1 speed by 9.04 %``).

    """

    def __init__(self, what: str, exceeded: list[str], hint: str) -> None:
        self.exceeded = exceeded
        super().__init__(f"{what}: limits exceeded: {'; '.join(exceeded)}; {hint}")


class SimulationError(PkdynError):
    """A simulation cannot continue (state not finite, closures lost, step size collapsed).

    Attributes:
        time: Simulated time at the failure [s].

    """

    def __init__(self, message: str, time: float) -> None:
        self.time = time
        super().__init__(f"t = {time:.6g} s: {message}")


class OutputError(PkdynError):
    """An output file cannot be written (missing directory, permissions, bad name or format).

    Attributes:
        path: The file pkdyn was asked to write.

    """

    def __init__(self, path: str, message: str) -> None:
        self.path = path
        super().__init__(f"cannot write '{path}': {message}")


class StudyError(PkdynError):
    """A design study cannot run or conclude (see :mod:`pkdyn.design`).

    Attributes:
        culprit: What is at fault (a study file, a scheduler address, a requirement...).

    """

    def __init__(self, culprit: str, message: str) -> None:
        self.culprit = culprit
        super().__init__(f"{culprit}: {message}")


class CatalogError(PkdynError):
    """A motor or gearbox catalog is malformed: missing field, bad value, implausible unit.

    Attributes:
        source: Catalog file.
        entry: The entry at fault (``motor 'M1'``, ``gearbox #3``), or ``None`` for the file.
        field: The field at fault, or ``None``.

    """

    def __init__(self, source: str, entry: str | None, field: str | None, message: str) -> None:
        self.source = source
        self.entry = entry
        self.field = field
        where = source + "".join(f": {x}" for x in (entry, field and f"field '{field}'") if x)
        super().__init__(f"{where}: {message}")


class NoFeasibleDriveError(PkdynError):
    """No motor (x gearbox) of the catalogs can drive an actuator along the trajectory.

    Attributes:
        actuator: The actuator.
        closest: Descriptions of the closest candidates and what each lacks.

    """

    def __init__(self, actuator: str, closest: list[str]) -> None:
        self.actuator = actuator
        self.closest = closest
        super().__init__(
            f"no feasible motor x gearbox pair for actuator '{actuator}'; closest: "
            + "; ".join(closest)
        )


class CalibrationError(PkdynError):
    """A calibration that should not be trusted (:mod:`pkdyn.calibration.trust`).

    It did not converge, left residuals beyond a multiple of the noise, or made corrections
    beyond a multiple of the tolerances; the message names the reasons and the likely cause
    (units, axis order, orientation convention, another robot).

    Attributes:
        reasons: Why, one phrase each.
        cause: The likely cause, or ``""``.
        result: The calibration itself (:class:`pkdyn.calibration.CalibrationResult`), to
            inspect or to keep anyway.

    """

    def __init__(self, robot: str, reasons: list[str], cause: str, result: Any = None) -> None:
        self.reasons = list(reasons)
        self.cause = cause
        self.result = result
        super().__init__(
            f"calibration of {robot} not trusted: {'; '.join(reasons)}"
            + (f"; likely cause: {cause}" if cause else "")
            + "; nothing is written unless it is accepted (--accept, accept=True)"
        )
