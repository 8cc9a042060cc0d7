"""Running a study: designs through an executor, streamed to disk, resumable.

:func:`run_study` evaluates the designs of a sweep (or the generations of NSGA-II) on the chosen
executor (:mod:`pkdyn.design.executors`), appends every finished design to the partial file
(:class:`pkdyn.design.table.PartialFile`), and at the end writes the table (CSV and Parquet)
and the study file beside it, each to a temporary name renamed when complete. Run again on the
same output, the same study skips the designs already done (from the partial file, or all of
them from a complete earlier run).
"""

from __future__ import annotations

import json
import os
import time
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.design.evaluate import Row, evaluate_designs, pack
from pkdyn.design.executors import Executor, SerialExecutor, make_executor
from pkdyn.design.optimize import nsga2_rows
from pkdyn.design.result import StudyResult
from pkdyn.design.study import MAX_STUDY_FILE, Study
from pkdyn.design.table import PartialFile, Table, output_paths
from pkdyn.exceptions import InvalidInputError, PkdynError, StudyError
from pkdyn.files import atomic_write, read_text
from pkdyn.model.arguments import public
from pkdyn.progress import progress as progress_bar
from pkdyn.threads import single_blas_thread

__all__ = ["run_study"]


def _chunks(items: list[tuple[int, list[float]]], workers: int) -> list[list[Any]]:
    """Chunks of designs: a few per worker, at most 32 designs each (1 when serial)."""
    if workers <= 1:
        return [[it] for it in items]
    size = max(1, min(32, len(items) // (8 * workers)))
    return [items[k : k + size] for k in range(0, len(items), size)]


def _evaluate(
    ex: Executor,
    payload: Any,
    items: list[tuple[int, list[float]]],
    done: dict[int, Row],
    partial: PartialFile | None,
) -> Iterator[Row]:
    """Rows of ``items``: those already done, then the others as the executor finishes them.

    A row already done counts only if it holds the design the sampler proposes at its index
    (NSGA-II proposes its designs as it goes: a partial file may differ from them).
    """
    todo = []
    for i, x in items:
        r = done.get(i)
        if r is not None and r.x == tuple(x):
            yield r
        else:
            todo.append((i, x))
    for rows in ex.map_chunks(evaluate_designs, payload, _chunks(todo, ex.workers)):
        if partial is not None:
            partial.append(rows)
        for r in rows:
            done[r.index] = r
        yield from rows


def _complete(paths: dict[str, Path], study: Study, header: list[str]) -> list[Row] | None:
    """Rows of an earlier complete run of the same study (same digest) here, else ``None``."""
    import yaml

    if not (paths["study"].is_file() and paths["csv"].is_file()):
        return None
    try:
        meta = yaml.safe_load(
            read_text(  # (this run's own study file, rewritten when it ends: not an input)
                paths["study"], MAX_STUDY_FILE, lambda m: StudyError("study file", m), record=False
            )
        )
        results = meta.get("results") if isinstance(meta, dict) else None
        if not isinstance(results, dict) or results.get("digest") != study.digest():
            return None
        with open(paths["csv"], newline="") as fh:
            rows = Table.read_rows(fh, header)
    except (OSError, yaml.YAMLError, PkdynError, RecursionError):
        return None
    return rows  # (checked row by row by _belonging)


def _belonging(study: Study, rows: list[Row], source: Path) -> dict[int, Row]:
    """The rows of an earlier run that belong to ``study``, by index; a warning counts the rest.

    A row belongs if its index is one of the study's designs and its design variables are
    those the sampler gives at that index (NSGA-II, which proposes its designs as it goes:
    inside the ranges, whole numbers where the parameter is an integer; each is compared with
    the proposal when it comes). Of repeated indices the last row is kept (a design evaluated
    again after a restart is appended after the first).
    """
    total = study.total
    X = None if study.sampler == "nsga2" else study.designs()
    ranges = study.space.ranges
    integral = study.space.integral
    kept: dict[int, Row] = {}
    dropped = {"index": 0, "values": 0, "repeated": 0}
    for r in rows:
        if not 0 <= r.index < total:
            dropped["index"] += 1
            continue
        if X is not None:
            ok = r.x == tuple(float(v) for v in X[r.index])
        else:
            ok = len(r.x) == len(ranges) and all(
                rg.low <= v <= rg.high and (not whole or v == round(v))
                for rg, v, whole in zip(ranges, r.x, integral, strict=True)
            )
        if not ok:
            dropped["values"] += 1
            continue
        if r.index in kept:
            dropped["repeated"] += 1
        kept[r.index] = r
    if any(dropped.values()):
        what = {
            "index": f"an index outside 0..{total - 1}",
            "values": "design values the sampler does not give at their index",
            "repeated": "an index given again (the last row kept)",
        }
        parts = [f"{n} with {what[k]}" for k, n in dropped.items() if n]
        n = sum(dropped.values())
        warnings.warn(
            f"{source}: {n} row{'s' if n > 1 else ''} that do not belong to this study dropped "
            f"({', '.join(parts)}); {len(kept)} kept, the others are evaluated",
            UserWarning,
            stacklevel=3,
        )
    return kept


@public
def run_study(
    study: Study,
    out: str | os.PathLike[str] | None = None,
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
    resume: bool = True,
    progress: bool | None = None,
    executor: Executor | None = None,
    scheduler_timeout: float = 10.0,
) -> StudyResult:
    """Evaluate every design of a study.

    Args:
        study: The study.
        out: Table file (``.csv`` or ``.parquet``; both are written, and ``<stem>.study.yaml``);
            ``None`` keeps the results in memory only.
        workers: Local worker processes (default: the usable cores, at most one per design;
            1: this process; more than the machine or the study justify are capped, with a
            warning).
        client: A Dask :class:`distributed.Client` to run on.
        scheduler: A Dask scheduler address to connect to (``tcp://host:8786``).
        resume: Skip the designs an earlier run of the same study at ``out`` finished (rows
            that do not belong to the study are dropped, with a warning).
        progress: Progress bar over designs (default: on a terminal).
        executor: An executor to use (overrides ``workers``, ``client``, ``scheduler``).
        scheduler_timeout: How long to wait for the scheduler and for workers [s] (at most
            :data:`pkdyn.design.executors.MAX_TIMEOUT`).

    Returns:
        The results.

    Raises:
        StudyError: Unreachable scheduler, a cluster or a worker process lost (the designs
            finished are kept: the same call resumes), a partial file of another study, a
            design that exhausts the memory, or a required workspace that no design reaches
            (the complete table is written first).
        OutputError: The output cannot be written.

    """
    if not isinstance(study, Study):
        raise InvalidInputError(
            "study", f"expected a pkdyn.design.Study, got {type(study).__name__}"
        )
    from pkdyn.executors import check_scheduler, check_timeout
    from pkdyn.files import output_target

    scheduler_timeout = check_timeout(scheduler_timeout, "scheduler_timeout")
    check_scheduler(scheduler)
    if out is not None:
        output_target(out, "out")
    t0 = time.perf_counter()
    variables = study.space.names
    units = study.units
    empty = Table(variables, study.metric_names, units, [])
    header = empty.header()
    paths = output_paths(out) if out is not None else {}
    done: dict[int, Row] = {}
    results: dict[int, Row] = {}
    partial = None
    parallel = study.n if study.sampler == "nsga2" else study.total
    ex = (
        executor
        if executor is not None
        else make_executor(workers, client, scheduler, scheduler_timeout, designs=parallel)
    )
    failed = True
    try:
        if paths:
            partial = PartialFile(paths["partial"], study.digest(), header)
            if resume:
                complete = _complete(paths, study, header)
                source = paths["csv"] if complete is not None else paths["partial"]
                rows = complete if complete is not None else partial.load()
                done = _belonging(study, rows, source)
            partial.open(sorted(done.values(), key=lambda r: r.index))
        payload: Any = study if isinstance(ex, SerialExecutor) else pack(study)
        if study.sampler == "nsga2":
            stream = nsga2_rows(study, lambda items: _evaluate(ex, payload, items, done, partial))
        else:
            X = study.designs()
            items = [(i, [float(v) for v in x]) for i, x in enumerate(X)]
            stream = _evaluate(ex, payload, items, done, partial)
        # one BLAS thread for the whole study (its parallelism is over designs): set once here
        # (the local pool's forked workers inherit it), not by each precision metric per design
        with single_blas_thread():
            for row in progress_bar(stream, "designs", "design", progress, total=study.total):
                results[row.index] = row
        failed = False
    finally:
        if partial is not None:
            partial.close()
        if executor is None:
            ex.close(abort=failed)
    table = Table(variables, study.metric_names, units, list(results.values()))
    result = StudyResult(study, table, time.perf_counter() - t0, ex.name, paths)
    if paths:
        meta = {"digest": study.digest(), "units": json.dumps(units)}
        table.write_csv(paths["csv"])
        table.write_parquet(paths["parquet"], {"pkdyn_study": study.to_yaml(), **meta})
        with atomic_write(paths["study"]) as fh:
            fh.write(result.study_file())
        assert partial is not None
        partial.close(remove=True)
    if study.requirement is not None:
        contains = table.column("contains")
        if not np.isfinite(contains).any():  # not one design could be checked: say why
            reasons = [r.reason for r in table.rows if r.reason]
            common = max(set(reasons), key=reasons.count) if reasons else "no value"
            raise StudyError(
                "requirement",
                f"no design of the {len(table)} could be checked against the required "
                f"workspace: {common}",
            )
        reached = float(np.nanmax(contains))
        if reached < 1.0:
            where = f"; the table is in {paths['csv']}" if paths else ""
            raise StudyError(
                "requirement",
                f"no design of the {len(table)} reaches the whole required workspace "
                f"({study.requirement.describe()}): at best {100 * reached:.1f} % of its "
                f"samples; widen the ranges or move the requirement{where}",
            )
    return result
