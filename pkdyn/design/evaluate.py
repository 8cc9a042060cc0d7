"""Evaluating designs: build, measure, judge; never raise for a bad design.

:func:`evaluate_design` builds one design of a study, computes every metric and checks the
constraints. The design is built the way ``pkdyn.load(family, **params)`` builds it, but once
per process and structure: each next design's numbers are written into the same Pinocchio
model, geometry and constraint models (:class:`pkdyn.model.candidate.CandidateBuilder`, one per
study and process), which gives the same robot, bit for bit, without its URDF text. A design
that cannot be built, assembled or evaluated (a parameter combination the builder refuses, a
cycle out of reach, a singularity...) or that breaks a constraint comes back infeasible with
its reason: it never stops the study.
:func:`evaluate_designs` does a batch in a worker process (local or Dask); the study travels
as a cloudpickle payload (user metrics may be lambdas) and is unpickled once per worker.
"""

from __future__ import annotations

import warnings
import weakref
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from pkdyn.design.context import DesignContext
from pkdyn.design.study import Study
from pkdyn.exceptions import PkdynError, StudyError
from pkdyn.model.candidate import CandidateBuilder
from pkdyn.model.robot import Robot
from pkdyn.threads import single_blas_thread

__all__ = ["Row", "build", "candidates", "evaluate_design", "evaluate_designs", "pack"]

_REASON_LENGTH = 300
"""Longest reason kept in the table [characters]."""


@dataclass(frozen=True)
class Row:
    """One evaluated design.

    Attributes:
        index: Design number in the study.
        x: Design variables (d,).
        feasible: Built, evaluated and within every constraint.
        reason: Why not (empty when feasible).
        values: Metric values in the study's metric order (NaN where not computed).

    """

    index: int
    x: tuple[float, ...]
    feasible: bool
    reason: str
    values: tuple[float, ...]


def _reason(err: BaseException, where: str = "") -> str:
    text = f"{where}{type(err).__name__}: {err}".replace("\n", " ").replace("\r", " ")
    return text if len(text) <= _REASON_LENGTH else text[: _REASON_LENGTH - 3] + "..."


_BUILDERS: dict[int, CandidateBuilder] = {}
"""The candidate builder of each study in this process, by ``id(study)`` (dropped with it)."""


def candidates(study: Study) -> CandidateBuilder:
    """The study's candidate builder in this process (made on first use)."""
    key = id(study)
    builder = _BUILDERS.get(key)
    if builder is None:
        builder = CandidateBuilder(study.space.family, collision=study.geometry)
        _BUILDERS[key] = builder
        weakref.finalize(study, _BUILDERS.pop, key, None)
    return builder


def build(study: Study, x: Any) -> Robot:
    """The robot of design ``x``, as ``pkdyn.load(family, **overrides)`` builds it.

    With collision geometry when a metric needs it, without the visual geometry (no metric
    looks at it). Written into the study's candidate in this process (:func:`candidates`): the
    robot is valid until the next design is built.
    """
    fam = study.space.family_obj
    params = fam.make_params(study.space.overrides(x))
    return candidates(study).robot(params)


def evaluate_design(study: Study, index: int, x: Any) -> Row:
    """Build and evaluate one design.

    Args:
        study: The study.
        index: Design number.
        x: Design variables (d,) in range order.

    Returns:
        The row (infeasible with a reason when the design fails or breaks a constraint).

    Raises:
        StudyError: The memory ran out (a property of the machine and the study's sampling,
            not of the design: never recorded as an infeasible design).

    """
    xs = tuple(float(v) for v in x)
    metrics = study.metric_list
    values = [float("nan")] * len(metrics)
    exhausted = ""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        where = "build: "
        try:
            robot = build(study, xs)
            ctx = DesignContext(robot, study.conditions)
            for k, m in enumerate(metrics):
                where = f"{m.name}: "
                values[k] = m(robot, ctx)
        except PkdynError as err:
            return Row(index, xs, False, _reason(err, where), tuple(values))
        except MemoryError:
            exhausted = where  # not a property of the design: stop the study, below
        except Exception as err:  # a user metric's bug, a numerical failure: record it
            return Row(index, xs, False, _reason(err, where + "error: "), tuple(values))
        except SystemExit as err:  # sys.exit in a metric or a parametrisation: stop the study
            raise StudyError(
                f"design {index}",
                f"{where}called sys.exit({err.code!r}): a metric or parametrisation must return "
                "a value or raise an exception, not end the program",
            ) from None
    if exhausted:
        raise StudyError(
            f"design {index}",
            f"the memory ran out ({exhausted.rstrip(': ')}); lower the required samples, the "
            "duty cycle's samples or the workers",
        )
    by_name = dict(zip(study.metric_names, values, strict=True))
    broken = [
        f"{c.metric} = {by_name[c.metric]:.6g} breaks {c}"
        for c in study.all_constraints
        if c.violation(by_name[c.metric]) > 0.0
    ]
    return Row(index, xs, not broken, "; ".join(broken), tuple(values))


def pack(study: Study) -> bytes:
    """The study as a payload for workers (cloudpickle: user metrics may be closures)."""
    import cloudpickle

    return bytes(cloudpickle.dumps(study))


@lru_cache(maxsize=4)
def _unpack(payload: bytes) -> Study:
    import cloudpickle

    study = cloudpickle.loads(payload)
    assert isinstance(study, Study)
    return study


def evaluate_designs(payload: bytes | Study, items: list[tuple[int, list[float]]]) -> list[Row]:
    """Evaluate a batch of designs (the function workers run).

    Args:
        payload: :func:`pack` of the study (the study itself in this process).
        items: ``(index, x)`` pairs.

    Returns:
        The rows, in the order of ``items``.

    """
    study = payload if isinstance(payload, Study) else _unpack(payload)
    with single_blas_thread():  # (once per batch: free inside a study's block, pkdyn.threads)
        return [evaluate_design(study, i, np.asarray(x, dtype=float)) for i, x in items]
