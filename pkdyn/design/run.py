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
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.design.evaluate import Row, evaluate_designs, pack
from pkdyn.design.executors import Executor, SerialExecutor, make_executor
from pkdyn.design.optimize import nsga2_rows
from pkdyn.design.result import StudyResult
from pkdyn.design.study import Study
from pkdyn.design.table import PartialFile, Table, output_paths
from pkdyn.exceptions import StudyError
from pkdyn.files import atomic_write
from pkdyn.progress import progress as progress_bar

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
    """Rows of ``items``: those already done, then the others as the executor finishes them."""
    for i, _ in items:
        if i in done:
            yield done[i]
    todo = [it for it in items if it[0] not in done]
    for rows in ex.map_chunks(evaluate_designs, payload, _chunks(todo, ex.workers)):
        if partial is not None:
            partial.append(rows)
        for r in rows:
            done[r.index] = r
        yield from rows


def _complete(paths: dict[str, Path], study: Study, header: list[str]) -> list[Row] | None:
    """Rows of a complete earlier run of the same study at these paths, else ``None``."""
    import yaml

    if not (paths["study"].exists() and paths["csv"].exists()):
        return None
    try:
        meta = yaml.safe_load(paths["study"].read_text())
        if not isinstance(meta, dict) or meta.get("results", {}).get("digest") != study.digest():
            return None
        with open(paths["csv"], newline="") as fh:
            rows = Table.read_rows(fh, header)
    except (OSError, yaml.YAMLError, StudyError):
        return None
    return rows if len(rows) == meta["results"].get("designs") else None


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
        workers: Local worker processes (default: the machine's cores; 1: this process).
        client: A Dask :class:`distributed.Client` to run on.
        scheduler: A Dask scheduler address to connect to (``tcp://host:8786``).
        resume: Skip the designs an earlier run of the same study at ``out`` finished.
        progress: Progress bar over designs (default: on a terminal).
        executor: An executor to use (overrides ``workers``, ``client``, ``scheduler``).
        scheduler_timeout: How long to try to reach ``scheduler`` [s].

    Returns:
        The results.

    Raises:
        StudyError: Unreachable scheduler, a partial file of another study, or a required
            workspace that no design reaches (the complete table is written first).
        OutputError: The output cannot be written.

    """
    t0 = time.perf_counter()
    variables = study.space.names
    units = study.units
    empty = Table(variables, study.metric_names, units, [])
    header = empty.header()
    paths = output_paths(out) if out is not None else {}
    done: dict[int, Row] = {}
    partial = None
    if paths and not paths["csv"].parent.is_dir():
        raise StudyError(str(out), f"directory '{paths['csv'].parent}' does not exist")
    ex = (
        executor
        if executor is not None
        else make_executor(workers, client, scheduler, scheduler_timeout)
    )
    try:
        if paths:
            partial = PartialFile(paths["partial"], study.digest(), header)
            if resume:
                complete = _complete(paths, study, header)
                rows = complete if complete is not None else partial.load()
                done = {r.index: r for r in rows}
            partial.open(sorted(done.values(), key=lambda r: r.index))
        payload: Any = study if isinstance(ex, SerialExecutor) else pack(study)
        if study.sampler == "nsga2":
            stream = nsga2_rows(study, lambda items: _evaluate(ex, payload, items, done, partial))
        else:
            X = study.designs()
            items = [(i, [float(v) for v in x]) for i, x in enumerate(X)]
            stream = _evaluate(ex, payload, items, done, partial)
        for _ in progress_bar(stream, "designs", "design", progress, total=study.total):
            pass
    finally:
        if partial is not None:
            partial.close()
        if executor is None:
            ex.close()
    table = Table(variables, study.metric_names, units, list(done.values()))
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
        reached = float(np.nanmax(contains)) if np.isfinite(contains).any() else 0.0
        if reached < 1.0:
            where = f"; the table is in {paths['csv']}" if paths else ""
            raise StudyError(
                "requirement",
                f"no design of the {len(table)} reaches the whole required workspace "
                f"({study.requirement.describe()}): at best {100 * reached:.1f} % of its "
                f"samples; widen the ranges or move the requirement{where}",
            )
    return result
