"""The results of a study: the table, the chosen design, the Pareto front, the study file."""

from __future__ import annotations

import dataclasses
import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.design.pareto import non_dominated
from pkdyn.design.study import Study
from pkdyn.design.table import Table
from pkdyn.exceptions import InvalidInputError, StudyError
from pkdyn.files import atomic_write
from pkdyn.results import Result, deprecated_alias, jsonable
from pkdyn.units import quantity

__all__ = ["StudyResult", "check_verify"]


def check_verify(study: Study, samples: int, candidates: int = 50) -> Study:
    """The study with its requirement sampled ``samples`` per axis, for :meth:`StudyResult.verify`.

    Refused before any work when the denser requirement, checked on up to ``candidates``
    designs, exceeds the budgets (:data:`pkdyn.design.requirement.MAX_REQUIRED_POSES` poses,
    :data:`pkdyn.design.study.MAX_STUDY_WORK` pose checks).

    Raises:
        InvalidInputError: No required workspace, bad numbers, or too many poses.

    """
    from pkdyn.design import fields
    from pkdyn.design.requirement import MAX_REQUIRED_POSES
    from pkdyn.design.study import MAX_STUDY_WORK

    samples = fields.integer("--verify (samples per axis)", samples, 2)
    candidates = fields.integer("candidates", candidates, 1)
    req = study.requirement
    if req is None:
        raise InvalidInputError("--verify", "the study has no required workspace to check")
    count = req.count_at(samples)
    if count > MAX_REQUIRED_POSES:
        raise InvalidInputError(
            "--verify",
            f"{req.kind} at {samples} samples per axis is {count:,} poses, more than "
            f"{MAX_REQUIRED_POSES:,}; use fewer samples per axis",
        )
    dense = dataclasses.replace(req, samples=samples)
    work = candidates * dense.count
    if work > MAX_STUDY_WORK:
        raise InvalidInputError(
            "--verify",
            f"{candidates} candidates x {dense.count:,} poses = {work:.3g} pose checks, more "
            f"than {MAX_STUDY_WORK:.0e}; use fewer samples per axis",
        )
    return dataclasses.replace(study, requirement=dense)


def _param_text(v: Any) -> str:
    if isinstance(v, tuple | list):
        return "(" + ",".join(_param_text(x) for x in v) + ("," if len(v) == 1 else "") + ")"
    return repr(float(v)) if isinstance(v, float) else str(v)


@dataclass
class StudyResult(Result):
    """What a study found.

    ``result.table()`` is the report the command line prints (the result protocol); the table
    of designs is ``result.designs`` (``result.table.rows`` and the other attributes of the
    table still work, with a deprecation warning, for one release).

    Attributes:
        study: The study.
        designs: Every design, sorted by index.
        seconds: Wall time of the run [s].
        executor: Where the designs were evaluated.
        paths: Files written (``csv``, ``parquet``, ``study``), empty when none.
        verified: Samples per axis of the denser check the chosen design passed (0: none,
            see :meth:`verify`).

    """

    study: Study
    designs: Table
    seconds: float
    executor: str
    paths: dict[str, Path] = field(default_factory=dict)
    verified: int = 0
    _chosen: int | None = field(default=None, repr=False)

    # ------------------------------------------------------------------ selections

    def objective_matrix(self) -> np.ndarray:
        """Objectives of every row as minimised values (N, n_obj) (maximised ones negated)."""
        cols = [o.sign() * self.designs.column(o.metric) for o in self.study.objective_list]
        return np.column_stack(cols) if cols else np.zeros((len(self.designs), 0))

    def pareto(self) -> np.ndarray:
        """Positions (in the table) of the feasible designs on the Pareto front.

        Non-dominated on the objectives, sorted by the first objective.
        """
        feas = np.flatnonzero(self.designs.feasible)
        if feas.size == 0 or not self.study.objective_list:
            return np.zeros(0, dtype=int)
        F = self.objective_matrix()[feas]
        front = feas[non_dominated(F)]
        return front[np.lexsort(self.objective_matrix()[front].T[::-1])]

    def best(self) -> int | None:
        """Position (in the table) of the chosen design.

        The feasible design best on the first objective (the next objectives break ties); the
        first feasible design when there is no objective; ``None`` when none is feasible.
        """
        if self.verified:
            return self._chosen
        feas = np.flatnonzero(self.designs.feasible)
        if feas.size == 0:
            return None
        if not self.study.objective_list:
            return int(feas[0])
        F = self.objective_matrix()[feas]
        return int(feas[np.lexsort(F.T[::-1])[0]])

    def verified_best(self, samples: int = 15, candidates: int = 50) -> int | None:
        """Position of the best feasible design that also passes a denser required workspace.

        A required workspace is checked on samples (:mod:`pkdyn.design.requirement`); a design
        at the edge of the feasible set (a minimum usually is) can lose a sliver between them.
        The feasible designs are re-evaluated in the order of :meth:`best`, with the
        requirement sampled ``samples`` per axis, until one passes every constraint.

        Args:
            samples: Samples per axis of the denser check.
            candidates: How many designs to try at most.

        Returns:
            The position, or ``None`` if none of the candidates passes.

        Raises:
            InvalidInputError: A denser requirement beyond the budgets (:func:`check_verify`).
            StudyError: The memory runs out (never read as "no design passes").

        """
        from pkdyn.design import fields
        from pkdyn.design.evaluate import evaluate_design

        samples = fields.integer("--verify (samples per axis)", samples, 2)
        candidates = fields.integer("candidates", candidates, 1)
        if self.study.requirement is None:
            return self.best()
        dense = check_verify(self.study, samples, candidates)
        feas = np.flatnonzero(self.designs.feasible)
        if self.study.objective_list:
            feas = feas[np.lexsort(self.objective_matrix()[feas].T[::-1])]
        for i in feas[:candidates]:
            r = self.designs.rows[int(i)]
            if evaluate_design(dense, r.index, r.x).feasible:
                return int(i)
        return None

    def verify(self, samples: int = 15, candidates: int = 50) -> int | None:
        """Choose the best design that passes a denser required workspace.

        See :meth:`verified_best`; :meth:`best`, the URDF and the reports then use it.

        Returns:
            Its position, or ``None`` if no candidate passes.

        """
        chosen = self.verified_best(samples, candidates)
        self._chosen, self.verified = chosen, int(samples)  # (checked by verified_best)
        return chosen

    def _row(self, i: int | None) -> int:
        if i is not None:
            from pkdyn.design import fields

            i = fields.integer("design (row position)", i, 0, len(self.designs) - 1)
        i = self.best() if i is None else i
        if i is None:
            raise StudyError(
                "study",
                f"no feasible design among {len(self.designs)}; widen the ranges or relax "
                "the constraints (see the reason column)",
            )
        return i

    def record(self, i: int | None = None) -> dict[str, Any]:
        """A row (default: the chosen design) as ``{column: value}``."""
        return self.designs.record(self._row(i))

    def overrides(self, i: int | None = None) -> dict[str, Any]:
        """Builder parameter overrides of a design (default: the chosen one)."""
        return self.study.space.overrides(self.designs.rows[self._row(i)].x)

    def params(self, i: int | None = None) -> Any:
        """Builder parameters of a design (default: the chosen one)."""
        return self.study.space.params(self.designs.rows[self._row(i)].x)

    def robot(self, i: int | None = None, geometry: bool = True) -> Any:
        """The built design (default: the chosen one)."""
        import pkdyn

        return pkdyn.load(self.study.family, geometry=geometry, **self.overrides(i))

    def urdf(self, i: int | None = None) -> str:
        """URDF text of a design (default: the chosen one), as ``pkdyn urdf`` writes it.

        With its ``<pkdyn:family>`` element: the file loads as the family with these parameters.
        """
        from pkdyn.model.families import export_urdf

        fam = self.study.space.family_obj
        return export_urdf(fam.name, self.params(i))

    def write_urdf(self, path: str | os.PathLike[str], i: int | None = None) -> None:
        """Write the URDF of a design (default: the chosen one), atomically."""
        text = self.urdf(i)
        with atomic_write(path) as fh:
            fh.write(text)

    def param_args(self, i: int | None = None) -> str:
        """The design as ``--param`` arguments of the ordinary commands."""
        return " ".join(
            f"--param {k}={_param_text(v)}" for k, v in sorted(self.overrides(i).items())
        )

    def command(self, what: str = "urdf", i: int | None = None) -> str:
        """The ordinary ``pkdyn`` command for a design: ``urdf``, ``size`` or ``workspace``."""
        from pkdyn.design import fields

        what = fields.text("what", what, ("urdf", "size", "workspace"))
        s = self.study
        base = f"pkdyn {what} {s.family} {self.param_args(i)}"
        if what == "size":
            opts = s.trajectory_options
            base += f" --trajectory {s.trajectory} --payload {s.payload:g}"
            if "cycle_time" in opts:
                base += f" --cycle-time {float(opts['cycle_time']):g}"
        return base

    # ------------------------------------------------------------------ reports

    def counts(self) -> dict[str, int]:
        """Designs evaluated, feasible, failed (could not be evaluated), constraint-broken."""
        rows = self.designs.rows
        failed = sum(1 for r in rows if not all(np.isfinite(r.values)))
        feasible = sum(1 for r in rows if r.feasible)
        return {
            "designs": len(rows),
            "feasible": feasible,
            "failed": failed,
            "constrained": len(rows) - feasible - failed,
        }

    as_json = deprecated_alias("as_json", "to_json")

    def to_json(self) -> dict[str, Any]:
        """Summary: counts, timing, the chosen design, the Pareto front, the files."""
        best = self.best()
        front = self.pareto()
        return jsonable(
            {
                "study": self.study.name or self.study.family,
                "digest": self.study.digest(),
                **self.counts(),
                "seconds": self.seconds,
                "designs_per_second": len(self.designs) / self.seconds
                if self.seconds > 0
                else None,
                "executor": self.executor,
                "best": None if best is None else _json_record(self.designs.record(best)),
                "best_params": None if best is None else _plain(self.overrides(best)),
                "pareto": [_json_record(self.designs.record(int(i))) for i in front],
                "files": {k: str(v) for k, v in self.paths.items()},
            }
        )

    def study_file(self) -> str:
        """The study file written beside the table: the study, then a ``results`` summary."""
        import yaml

        data = self.study.as_dict()
        best = self.best()
        data["results"] = {
            "digest": self.study.digest(),
            **self.counts(),
            "best_index": None if best is None else int(self.designs.rows[best].index),
            "best_params": None if best is None else _plain(self.overrides(best)),
        }
        return "# pkdyn design study: rerun with `pkdyn design --study THIS_FILE`\n" + str(
            yaml.safe_dump(data, sort_keys=False, default_flow_style=None)
        )

    summary = deprecated_alias("summary", "report")

    @property
    def table(self) -> Any:
        """Called, the report (:meth:`report`); its attributes: deprecated, see :attr:`designs`."""
        return _ReportOrTable(self)

    def report(self, top: int = 5) -> str:
        """A readable report: counts, reasons, the chosen design, the front."""
        from pkdyn.design import fields

        top = fields.integer("top", top, 1)
        c = self.counts()
        s = self.study
        lines = [
            f"{s.name or s.family}: {c['designs']} designs in {quantity(self.seconds, 's')} "
            f"({c['designs'] / max(self.seconds, 1e-9):.1f} designs/s, {self.executor}); "
            f"{c['feasible']} feasible, {c['constrained']} break a constraint, "
            f"{c['failed']} could not be evaluated"
        ]
        reasons: dict[str, int] = {}
        for r in self.designs.rows:
            if r.reason:
                key = r.reason.split(":")[0] if not all(np.isfinite(r.values)) else "constraint"
                if key == "constraint":
                    key = "; ".join(sorted({p.split(" = ")[0] for p in r.reason.split("; ")}))
                    key = f"breaks {key}"
                reasons[key] = reasons.get(key, 0) + 1
        for k, n in sorted(reasons.items(), key=lambda kv: -kv[1])[:top]:
            lines.append(f"  {n:6d}  {k}")
        best = self.best()
        if best is None:
            lines.append(
                "no feasible design"
                + (f" passes {self.verified} samples per axis" if self.verified else "")
            )
            return "\n".join(lines)
        rec = self.designs.record(best)
        obj = ", ".join(str(o) for o in s.objective_list) or "first feasible"
        if self.verified:
            obj += f"; passes the required workspace at {self.verified} samples per axis"
        lines.append(f"chosen ({obj}): design {rec['index']}")
        for name in s.space.names:
            lines.append(f"  {name:>22s} = {rec[name]:.6g}")
        units = self.designs.units
        for name in s.metric_names:
            lines.append(f"  {name:>22s} = {rec[name]:.6g} {units.get(name, '')}")
        front = self.pareto()
        if s.objective_list and len(front):
            lines.append(f"Pareto front: {len(front)} designs")
        lines.append(f"check: {self.command('size' if s.uses_duty else 'workspace', best)}")
        return "\n".join(lines)


class _ReportOrTable:
    """``result.table``: called, the report (the result protocol).

    Otherwise, for one release, the table of designs (now ``result.designs``), with a
    deprecation warning.
    """

    def __init__(self, result: StudyResult) -> None:
        self._result = result

    def __call__(self, top: int = 5) -> str:
        return self._result.report(top)

    def _designs(self) -> Table:
        warnings.warn(
            "StudyResult.table is the report now (table()); the table of designs is "
            "StudyResult.designs",
            DeprecationWarning,
            stacklevel=3,
        )
        return self._result.designs

    def __getattr__(self, name: str) -> Any:
        return getattr(self._designs(), name)

    def __len__(self) -> int:
        return len(self._designs())

    def __iter__(self) -> Any:
        return iter(self._designs().rows)


def _plain(v: Any) -> Any:
    if isinstance(v, dict):
        return {k: _plain(x) for k, x in v.items()}
    if isinstance(v, tuple | list):
        return [_plain(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    return v


def _json_record(rec: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in rec.items():
        if isinstance(v, float) and not np.isfinite(v):
            out[k] = None
        else:
            out[k] = _plain(v)
    return out
