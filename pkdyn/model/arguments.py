"""The arguments every public entry point shares, checked where they enter.

:func:`public` decorates a public function (or method) of pkdyn: before its body runs, the
arguments that follow the API's conventions (``docs/guide/conventions.md``) are checked by
name and annotation, so that no bad value reaches numpy, Pinocchio or a solver:

- ``robot`` annotated ``Robot`` (or ``self`` of a :class:`~pkdyn.model.robot.Robot` method): a
  :class:`~pkdyn.model.robot.Robot` (annotated with other types too, ``Robot | ElasticModel``:
  the sizes below are checked when it is a Robot, the rest is the body's);
- ``q``, ``q0``, ``q_init``, ``q_ref``: a configuration of the robot (nq,), finite numbers;
- ``v``, ``v0``: a velocity (nv,) (actuator coordinates ``qa`` are the functions' own to
  check: their reach depends on the robot's scale);
- ``tol`` and the arguments named ``*_tol``: a finite number > 0;
- every argument annotated ``bool`` (or ``bool | None``): ``True`` or ``False`` (or
  ``None``) — a string ``"no"`` would otherwise count as true.

A bad value raises :class:`~pkdyn.exceptions.InvalidInputError` naming the argument. The
checked arrays are copies: the body never changes what the caller passed. Arguments left at
``None`` (the documented default) are not checked. Everything else an entry point takes (its
counts, ranges, names) it checks itself with :mod:`pkdyn.inputs`.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np

from pkdyn.inputs import flag, instance, positive, vector
from pkdyn.model.robot import Robot

__all__ = ["check_robot", "configuration", "public"]

F = TypeVar("F", bound=Callable[..., Any])

_CONFIGURATIONS = ("q", "q0", "q_init", "q_ref")
_VELOCITIES = ("v", "v0")


def check_robot(value: Any, name: str = "robot") -> Robot:
    """``value`` if it is a :class:`Robot`.

    Raises:
        InvalidInputError: Anything else (a family name, a Pinocchio model...).

    """
    return instance(name, value, Robot, "a Robot (pkdyn.load)")  # type: ignore[no-any-return]


def configuration(robot: Robot, q: Any, name: str = "q") -> np.ndarray:
    """A configuration of ``robot``: nq finite numbers (a copy).

    Raises:
        InvalidInputError: Not nq finite numbers.

    """
    return vector(name, q, robot.nq, "rad or m")


def _is_bool(annotation: Any) -> tuple[bool, bool]:
    """``(is a bool argument, accepts None)`` from an annotation (a string under PEP 563)."""
    text = annotation if isinstance(annotation, str) else getattr(annotation, "__name__", "")
    parts = {p.strip() for p in str(text).split("|")}
    if "bool" not in parts or not parts <= {"bool", "None"}:
        return False, False
    return True, "None" in parts


def public(fn: F) -> F:
    """Check the conventional arguments of a public function before it runs (module doc)."""
    sig = inspect.signature(fn)
    params = sig.parameters
    bools = {
        name: _is_bool(p.annotation)[1] for name, p in params.items() if _is_bool(p.annotation)[0]
    }
    tols = [n for n in params if n == "tol" or n.endswith("_tol")]
    method = next(iter(params), None) == "self"
    # ``robot: Robot`` must be one; ``robot: Robot | ElasticModel`` is checked by the body when
    # it is not a Robot (the sizes below are then the body's to check too)
    strict = "robot" in params and str(params["robot"].annotation).strip() == "Robot"

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        bound = sig.bind(*args, **kwargs)
        a = bound.arguments
        if "robot" in a:
            robot = check_robot(a["robot"], "robot") if strict else a["robot"]
        elif method:  # a method of a Robot, or of an object made for one (its .robot)
            owner = a.get("self")
            robot = owner if isinstance(owner, Robot) else getattr(owner, "robot", None)
        else:
            robot = None
        if robot is not None and isinstance(robot, Robot):
            for name in _CONFIGURATIONS:
                if a.get(name) is not None:
                    a[name] = configuration(robot, a[name], name)
            for name in _VELOCITIES:
                if a.get(name) is not None:
                    a[name] = vector(name, a[name], robot.nv, "rad/s or m/s")
        for name in tols:
            if a.get(name) is not None:
                a[name] = positive(name, a[name])
        for name, none_ok in bools.items():
            if name in a and not (none_ok and a[name] is None):
                a[name] = flag(name, a[name])
        return fn(*bound.args, **bound.kwargs)

    return wrapper  # type: ignore[return-value]
