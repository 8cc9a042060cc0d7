"""Multi-objective optimisation of a study with NSGA-II (pymoo), seeded and reproducible.

pymoo's ask-and-tell loop: each generation's offspring (points of the unit cube of the design
variables) are evaluated through the study's executor, like a sweep, then told back with their
objectives (``sign x value``: maximised metrics negated) and constraint violations (0 when
satisfied). A design that failed gets a violation of :data:`FAILED` on every constraint and
objectives of :data:`FAILED`, so the search moves away from it. With the same seed and the same
evaluations (deterministic metrics), the same designs are proposed in the same order: a
restarted study finds its earlier designs in its partial file and re-proposes them unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from pkdyn.design.evaluate import Row
from pkdyn.design.study import Study
from pkdyn.exceptions import StudyError

__all__ = ["FAILED", "nsga2_rows", "objective_values"]

FAILED = 1e30
"""Objective and violation given to a design that could not be evaluated."""


def objective_values(study: Study, rows: list[Row]) -> tuple[np.ndarray, np.ndarray]:
    """Pymoo's ``F`` (N, n_obj) and ``G`` (N, n_constr) of evaluated rows."""
    names = study.metric_names
    F = np.full((len(rows), len(study.objective_list)), FAILED)
    G = np.full((len(rows), max(1, len(study.all_constraints))), 0.0)
    for k, r in enumerate(rows):
        val = dict(zip(names, r.values, strict=True))
        failed = not all(math.isfinite(v) for v in r.values)  # a metric could not be computed
        for j, o in enumerate(study.objective_list):
            v = o.sign() * val[o.metric]
            F[k, j] = v if math.isfinite(v) and not failed else FAILED
        for j, c in enumerate(study.all_constraints):
            g = c.violation(val[c.metric])
            G[k, j] = FAILED if failed or not math.isfinite(g) else g
    return F, G


def nsga2_rows(
    study: Study,
    evaluate: Callable[[list[tuple[int, list[float]]]], Iterator[Row]],
) -> Iterator[Row]:
    """Run NSGA-II, yielding every evaluated design as it completes.

    Args:
        study: The study (``sampler="nsga2"``, ``n`` = population, ``generations``).
        evaluate: Evaluates ``(index, x)`` pairs, yielding their rows in any order.

    Yields:
        Rows, generation after generation.

    """
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.core.evaluator import Evaluator
    from pymoo.core.problem import Problem
    from pymoo.problems.static import StaticProblem
    from pymoo.termination import get_termination

    d = study.space.dimension
    problem: Any = Problem(
        n_var=d,
        n_obj=len(study.objective_list),
        n_ieq_constr=max(1, len(study.all_constraints)),
        xl=np.zeros(d),
        xu=np.ones(d),
    )
    algorithm = NSGA2(pop_size=study.n)
    algorithm.setup(
        problem, termination=get_termination("n_gen", study.generations), seed=study.seed
    )
    counter = 0
    while algorithm.has_next():
        pop = algorithm.ask()
        X = study.space.values(np.clip(pop.get("X"), 0.0, 1.0))
        items = [(counter + k, [float(v) for v in x]) for k, x in enumerate(X)]
        counter += len(items)
        got: dict[int, Row] = {}
        for row in evaluate(items):
            got[row.index] = row
            yield row
        rows = [got[i] for i, _ in items]
        for r, (_, x) in zip(rows, items, strict=True):
            if not np.array_equal(np.array(r.x), np.array(x)):
                raise StudyError(
                    "results", f"design {r.index} differs from the partial results; restart anew"
                )
        F, G = objective_values(study, rows)
        Evaluator().eval(StaticProblem(problem, F=F, G=G), pop)
        algorithm.tell(infills=pop)
