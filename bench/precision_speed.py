"""Precision at the speed of its arithmetic (issue 37): Monte Carlo, compliant links, metrics.

- **Monte Carlo**, CPU time per sample of :func:`pkdyn.precision.monte_carlo` as users call it:
  the library families' parameters (every sample at once: the Delta's by Clavel's direct model,
  the Gough-Stewart's joint centres by Newton's method batched over the samples; the same draws
  as the general path) and the general path (each robot perturbed exactly in one working copy,
  its direct geometric model solved): targets 0.1 ms and 0.5 ms per sample;
- **stiffness with compliant links**, per pose, :func:`pkdyn.precision.stiffness` with steel
  links (the Gough-Stewart's legs slide: their beams follow the stroke at every pose): target
  5 ms per pose;
- **design metrics** in a study (the worked Delta's required cylinder, 425 poses), designs per
  CPU second of ``evaluate_design`` with ``contains`` and the metric: ``error_max`` (its
  first-order sensitivities in closed form, every pose at once), ``stiffness_min`` and
  ``f1_min`` (the closed forms of :mod:`pkdyn.precision.vectorised`): targets 30 and 300
  designs/s, with each metric's own share.

Run ``python bench/precision_speed.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import importlib
import time
import warnings

import numpy as np
from timing import Row, print_table

import pkdyn
from pkdyn.design import Study
from pkdyn.design.evaluate import evaluate_design
from pkdyn.precision import stiffness
from pkdyn.precision.parameters import parameter_model

monte_carlo = importlib.import_module("pkdyn.precision.monte_carlo").monte_carlo


def _cpu_per(fn, n: int, repeats: int = 3) -> float:
    """Median CPU seconds of ``fn()`` divided by ``n``."""
    fn()
    out = []
    for _ in range(repeats):
        t0 = time.process_time()
        fn()
        out.append((time.process_time() - t0) / n)
    return float(np.median(out))


def monte_carlo_rows() -> list[Row]:
    rows: list[Row] = []
    for name, kind, n, target in (
        ("delta", "family", 20000, 0.1),
        ("delta", "shortcuts", 200, 0.5),
        ("gough_stewart", "shortcuts", 200, 0.5),
        ("gough_stewart", "family", 20000, 0.1),
    ):
        robot = pkdyn.load(name)
        model = parameter_model(robot, kind)
        per = _cpu_per(
            lambda robot=robot, model=model, n=n: monte_carlo(
                robot, robot.q_home, model, 1e-5, samples=n, progress=False
            ),
            n,
        )
        rows.append(
            (
                f"Monte Carlo, {name}, {kind} parameters ({n} samples)",
                f"{per * 1e3:.3f} ms per sample",
                f"<= {target:g} ms: {'yes' if per * 1e3 <= target else '**no**'}",
            )
        )
    return rows


def stiffness_rows() -> list[Row]:
    rows: list[Row] = []
    for name in ("gough_stewart", "delta"):
        robot = pkdyn.load(name)
        per = _cpu_per(
            lambda robot=robot: [
                stiffness(robot, robot.q_home, actuator_stiffness=1e6, material="steel")
                for _ in range(10)
            ],
            10,
        )
        rows.append(
            (
                f"stiffness with steel links, {name}, per pose (`pkdyn.precision.stiffness`)",
                f"{per * 1e3:.2f} ms",
                f"<= 5 ms: {'yes' if per * 1e3 <= 5.0 else '**no**'}",
            )
        )
    return rows


def _study(metrics: list[str], n: int, **settings: object) -> Study:
    return Study(
        "delta",
        {"la": (0.15, 0.35), "lb": (0.30, 0.70), "ra": (0.08, 0.22)},
        fixed={"z_home": -0.35},
        metrics=metrics,
        requirement="cylinder:D=0.4,H=0.1,z=-0.35",
        n=n,
        seed=3,
        settings=settings,
    )


def metric_rows(n: int = 200) -> list[Row]:
    from pkdyn.threads import single_blas_thread

    rows: list[Row] = []
    # inside one BLAS-thread block, as a study runs its designs (run_study, evaluate_designs)
    with warnings.catch_warnings(), single_blas_thread():
        warnings.simplefilter("ignore")
        base = _study(["contains"], n)
        X = base.designs()
        t_base = _cpu_per(lambda: [evaluate_design(base, i, x) for i, x in enumerate(X)], n)
        for metric, settings, target in (
            ("error_max", {}, 30),
            ("stiffness_min", {"actuator_stiffness": 2e4}, 300),
            ("f1_min", {"actuator_stiffness": 2e4}, 300),
        ):
            st = _study(["contains", metric], n, **settings)
            per = _cpu_per(lambda st=st: [evaluate_design(st, i, x) for i, x in enumerate(X)], n)
            rows.append(
                (
                    f"design study with `{metric}` (Delta, 425 required poses)",
                    f"{1 / per:.0f} designs/s ({per * 1e3:.2f} ms per design; the metric "
                    f"{(per - t_base) * 1e3:.2f} ms)",
                    f">= {target} designs/s: {'yes' if 1 / per >= target else '**no**'}",
                )
            )
    return rows


def rows() -> list[Row]:
    return monte_carlo_rows() + stiffness_rows() + metric_rows()


if __name__ == "__main__":
    print_table(rows())
