"""The entries of the registry: a command, an API entry point, an exemption."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from contract.kinds import Arg, Scratch

__all__ = ["Api", "Cli", "Exempt"]


@dataclass
class Cli:
    """A command of ``pkdyn``.

    Attributes:
        words: The command words (``("tripod", "scenario")``).
        baseline: Valid arguments after the words (fast: small robots, few samples).
        options: Every option (its first long spelling) and positional (its ``dest``) -> its
            :class:`~contract.kinds.Arg` (the baseline tokens are in ``baseline``).
        robot: The family the sizes and names of the options refer to.
        inputs: Valid input files, by key -> their bytes (written in each example's scratch
            directory; ``{key}`` in ``baseline`` stands for the file's path).
        outputs: Output options and the name of the file each writes in the scratch directory.
        timeout: Time limit of one run [s].
        slow: Drive it only in the slow run (``-m slow``).

    """

    words: tuple[str, ...]
    baseline: list[str]
    options: dict[str, Arg]
    robot: str | None = None
    inputs: dict[str, Callable[[], bytes]] = field(default_factory=dict)
    timeout: float = 10.0
    slow: bool = False

    @property
    def name(self) -> str:
        return " ".join(self.words)


@dataclass
class Api:
    """A public function, class (its constructor) or method.

    Attributes:
        name: Its public name (``pkdyn.dynamics.simulate``, ``pkdyn.Robot.platform_placement``).
        args: Every argument the harness drives -> its :class:`~contract.kinds.Arg`.
        robot: The family the sizes and names of the arguments refer to (loaded without
            geometry unless ``geometry``).
        geometry: Load the robot with its geometry.
        inputs: Valid input files (as for :class:`Cli`).
        obj: For a method: builds the instance from the scratch directory.
        call: How to call it (default: the public object, or the method of ``obj``) with the
            arguments as keywords.
        timeout: Time limit of one call [s].
        nan_ok: NaN is a documented value of the result (an undefined figure).
        slow: Drive it only in the slow run.
        baseline: The entry has a valid baseline call (``False``: only the classes that need
            no valid arguments around them are driven, a wrong type of each argument).

    """

    name: str
    args: dict[str, Arg] = field(default_factory=dict)
    robot: str | None = "delta"
    geometry: bool = False
    inputs: dict[str, Callable[[], bytes]] = field(default_factory=dict)
    obj: Callable[[Scratch], Any] | None = None
    call: Callable[..., Any] | None = None
    timeout: float = 10.0
    nan_ok: bool = False
    slow: bool = False
    baseline: bool = True


@dataclass(frozen=True)
class Exempt:
    """A public name the harness does not drive, and why (a result record built by pkdyn, a
    constant, a class internal to the robot-agnostic solvers)."""

    name: str
    reason: str
    methods: bool = False
    """The exemption covers the class's methods too."""
