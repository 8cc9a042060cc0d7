"""User functions called during a simulation: their failures and results checked.

A torque law ``tau(t, q, v)`` is the user's code running inside the integrator. Whatever it
raises (``SystemExit`` included: ``sys.exit`` in a callback must not end the program from
within the solver) becomes a :class:`~pkdyn.exceptions.SimulationError` naming the function and
the time, with the user's exception as ``__cause__``; ``KeyboardInterrupt`` (and the CLI's
SIGTERM) stay interrupts. What it returns must be ``n`` finite real numbers: a string, a dict,
``None``, complex or ragged values are refused the same way, before they reach the dynamics.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from pkdyn.exceptions import SimulationError

__all__ = ["user_efforts"]

EffortFn = Callable[[float, np.ndarray, np.ndarray], np.ndarray]


def _shown(value: Any) -> str:
    text = repr(value)
    return (text if len(text) <= 60 else text[:57] + "...") + f" ({type(value).__name__})"


def _efforts(name: str, value: Any, n: int, t: float) -> np.ndarray:
    """The ``n`` efforts a callback returned, or a :class:`SimulationError` saying what it was."""
    expected = f"expected {n} finite real numbers"
    if isinstance(value, str | bytes | dict) or value is None:
        raise SimulationError(f"the {name} function returned {_shown(value)}; {expected}", t)
    try:
        arr = np.asarray(value)
    except ValueError:  # ragged nested sequences
        raise SimulationError(
            f"the {name} function returned {_shown(value)}; {expected}", t
        ) from None
    if arr.dtype.kind not in "iuf":
        what = "complex numbers" if arr.dtype.kind == "c" else f"{arr.dtype} values"
        raise SimulationError(
            f"the {name} function returned {what}: {_shown(value)}; {expected}", t
        )
    arr = arr.astype(float, copy=False).reshape(-1)
    if arr.size != n:
        raise SimulationError(
            f"the {name} function returned {arr.size} values for {n} actuators", t
        )
    if not np.all(np.isfinite(arr)):
        raise SimulationError(f"the {name} function returned {arr.tolist()}; {expected}", t)
    return arr


def user_efforts(name: str, fn: EffortFn, n: int) -> EffortFn:
    """``fn`` wrapped: its exceptions and bad results become :class:`SimulationError`.

    Args:
        name: The argument that passed it, for messages (``torque``, ``motor_torque``).
        fn: The user's ``fn(t [s], q (nq,), v (nv,)) -> (n,)``.
        n: Number of efforts expected.

    Returns:
        A function with the same signature returning a float array (n,).

    """

    def call(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        try:
            out = fn(t, q, v)
        except (Exception, SystemExit) as err:  # (KeyboardInterrupt and SIGTERM pass)
            raise SimulationError(
                f"the {name} function raised {type(err).__name__}: {err}", t
            ) from err
        return _efforts(name, out, n, t)

    return call
