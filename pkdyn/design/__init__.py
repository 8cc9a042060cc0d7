"""Design studies: many robots of a family, measured, filtered and ranked.

A study (:class:`Study`) is a family of the library (any registered family), ranges of some of
its builder parameters, fixed values for others, metrics (:mod:`pkdyn.design.metrics`: small
functions of a built robot, with units; add your own), constraints and objectives, a required
workspace and a duty cycle. A runner chooses the designs: a full grid, a Latin hypercube or a
Sobol' sequence (:mod:`pkdyn.design.samplers`), or NSGA-II (:mod:`pkdyn.design.optimize`).
:func:`run_study` evaluates them in local worker processes (default) or on a Dask cluster
(:mod:`pkdyn.design.executors`), streams them to disk and resumes an interrupted run
(:mod:`pkdyn.design.table`); a design that cannot be built or evaluated is recorded as
infeasible with its reason. :class:`StudyResult` gives the table (CSV, Parquet), the chosen
design (its URDF, the ordinary commands that check it) and the Pareto front
(:func:`pkdyn.plotting.design.plot_pareto`).

Layering: may import everything below the viewer, plots and CLI.
"""

from pkdyn.design.context import Conditions, DesignContext
from pkdyn.design.goals import Constraint, Objective
from pkdyn.design.metrics import GROUPS, METRICS, Metric, metric, resolve_metrics
from pkdyn.design.parametrisations import PARAMETRISATIONS, Parametrisation
from pkdyn.design.plugins import load_plugin
from pkdyn.design.requirement import Requirement
from pkdyn.design.result import StudyResult
from pkdyn.design.run import run_study
from pkdyn.design.space import DesignSpace, Range
from pkdyn.design.study import Study

__all__ = [
    "GROUPS",
    "METRICS",
    "PARAMETRISATIONS",
    "Conditions",
    "Constraint",
    "DesignContext",
    "DesignSpace",
    "Metric",
    "Objective",
    "Parametrisation",
    "Range",
    "Requirement",
    "Study",
    "StudyResult",
    "load_plugin",
    "metric",
    "resolve_metrics",
    "run_study",
]
