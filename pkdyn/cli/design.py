"""``pkdyn design``: design studies from the command line (or from a YAML study file).

Examples (one line each)::

    pkdyn design delta --range la=0.15:0.35 lb=0.3:0.6 --param z_home=-0.35
      --require cylinder:D=0.4,H=0.1,z=-0.35 --trajectory adept --payload 1 --cycle-time 0.5
      --constraint "inv_cond_min>=0.2" --minimize peak_effort --maximize inv_cond_min
      --n 512 --out study.csv --plot pareto.png --urdf chosen.urdf
    pkdyn design --study study.study.yaml --out again.csv      # the same study again
    pkdyn design delta --clavel-chart --grid 5                  # Clavel's Tableau 21
"""

from __future__ import annotations

import argparse
import json
from typing import Any

from pkdyn.cli._common import integer, number, params, worker_options
from pkdyn.cli._paths import input_option, output_option
from pkdyn.cli._spelling import spelled_option
from pkdyn.exceptions import InvalidInputError

__all__ = ["register"]


def _flat(items: list[list[str]] | None) -> list[str]:
    return [x for group in items or [] for x in group]


def _definition(args: argparse.Namespace) -> dict[str, Any]:
    """Study keys given on the command line (those not given are left out)."""
    from pkdyn.design.space import Range

    d: dict[str, Any] = {}
    if args.family:
        d["family"] = args.family
    if args.range:
        ranges: dict[str, list[float]] = {}
        for r in (Range.parse(t) for t in _flat(args.range)):
            if r.name in ranges:
                raise InvalidInputError("--range", f"'{r.name}' is given twice")
            ranges[r.name] = [r.low, r.high]
        d["ranges"] = ranges
    fixed = params(_flat(args.param))
    if fixed:
        d["fixed"] = fixed
    if args.metric:
        d["metrics"] = _flat(args.metric)
    if args.constraint:
        d["constraints"] = _flat(args.constraint)
    objectives = [f"min:{m}" for m in _flat(args.minimize)]
    objectives += [f"max:{m}" for m in _flat(args.maximize)]
    if objectives:
        d["objectives"] = objectives
    if args.require is not None:  # ("" is refused, not ignored)
        from pkdyn.design.requirement import Requirement

        samples = 5 if args.samples is None else args.samples
        d["requirement"] = Requirement.parse(args.require, samples).as_dict()
    elif args.samples is not None:
        raise InvalidInputError("--samples", "applies to a required workspace (--require)")
    if args.trajectory:
        d["trajectory"] = args.trajectory
    opts = {
        k: v
        for k, v in (("cycle_time", args.cycle_time), ("depth", args.depth), ("dt", args.dt))
        if v is not None
    }
    if opts:
        d["trajectory_options"] = opts
    if args.payload is not None:
        d["payload"] = args.payload
    if args.optimize:
        d["sampler"] = args.optimize
        if args.population is not None:
            d["n"] = args.population
        if args.generations is not None:
            d["generations"] = args.generations
    elif args.grid is not None:
        d["sampler"], d["n"] = "grid", args.grid
    elif args.n is not None or args.sampler:
        d["sampler"] = args.sampler or "lhs"
        if args.n is not None:
            d["n"] = args.n
    if args.seed is not None:
        d["seed"] = args.seed
    if args.parametrisation is not None:  # ("" is refused by the study, not ignored)
        d["parametrisation"] = args.parametrisation
    settings = {
        k: v
        for k, v in (
            ("length", args.length),
            ("actuator_stiffness", args.actuator_stiffness),
            ("material", args.material),
            ("damping_ratio", args.damping_ratio),
            ("band", args.band),
            ("dwell", args.dwell),
        )
        if v is not None
    }
    if settings:
        d["settings"] = settings
    return d


def _study(args: argparse.Namespace) -> Any:
    from pkdyn.design.study import Study

    for name in _flat(args.plugin):
        from pkdyn.design.plugins import load_plugin

        load_plugin(name)
    d = _definition(args)
    if args.study:
        base = Study.load(args.study).as_dict()
        for key in ("ranges", "fixed", "trajectory_options", "settings"):
            if key in d and key in base:
                d[key] = {**base[key], **d[key]}
        base.update(d)
        return Study.from_dict(base, args.study)
    if "family" not in d:
        raise InvalidInputError("pkdyn design", "give a FAMILY (or --study FILE)")
    if "ranges" not in d:
        raise InvalidInputError("--range", "a study needs at least one --range NAME=LOW:HIGH")
    if "metrics" not in d and "objectives" not in d and "constraints" not in d:
        d["metrics"] = _default_metrics(d)
    return Study.from_dict(d, "command line")


def _default_metrics(d: dict[str, Any]) -> list[str]:
    metrics = ["required"] if d.get("requirement") else []
    metrics += ["sizing", "moving_mass"]
    if d["family"] == "delta":
        metrics.insert(0, "clavel")
    return metrics


def _clavel_chart(args: argparse.Namespace) -> None:
    from pkdyn.design.clavel import clavel_chart_study, clavel_chart_text
    from pkdyn.design.space import Range

    if args.family not in (None, "delta"):
        raise InvalidInputError("--clavel-chart", "applies to the delta family")
    spans = {"r": (0.4, 1.0), "b": (1.5, 3.0)}
    given: set[str] = set()
    for r in (Range.parse(t) for t in _flat(args.range)):
        if r.name not in spans:
            raise InvalidInputError("--range", f"the chart sweeps r and b, not '{r.name}'")
        if r.name in given:
            raise InvalidInputError("--range", f"'{r.name}' is given twice")
        given.add(r.name)
        spans[r.name] = (r.low, r.high)
    study = clavel_chart_study(
        spans["r"], spans["b"], grid=args.grid or 4, **params(_flat(args.param))
    )
    result = _run(study, args)
    if args.json:
        print(
            json.dumps(
                {"rows": [_plain(result.designs.record(i)) for i in range(len(result.designs))]}
            )
        )
    else:
        print(clavel_chart_text(result))


def _run(study: Any, args: argparse.Namespace) -> Any:
    """Run a study with the command line's executor, resume and progress options."""
    from pkdyn.design.run import run_study

    return run_study(
        study,
        args.out,
        workers=args.workers,
        scheduler=args.scheduler,
        resume=not args.no_resume,
        progress=None if not args.json else False,
        scheduler_timeout=args.timeout,
    )


def _plain(rec: dict[str, Any]) -> dict[str, Any]:
    import math

    return {
        k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in rec.items()
    }


def _check_options(args: argparse.Namespace) -> None:
    """The options that are not part of the study, checked before any work.

    (The paths are checked by the command line before: :mod:`pkdyn.cli._paths`.)
    """
    from pkdyn.design.executors import check_timeout

    check_timeout(args.timeout, "--timeout")
    if args.workers is not None and args.workers < 1:
        raise InvalidInputError("--workers", f"must be >= 1, got {args.workers}")
    if args.verify is not None:
        if args.verify < 2:
            raise InvalidInputError("--verify", f"samples per axis must be >= 2, got {args.verify}")
        if not args.require and not args.study:
            raise InvalidInputError("--verify", "checks a required workspace: give --require")


def _cmd_design(args: argparse.Namespace) -> None:
    _check_options(args)
    if args.clavel_chart:
        _clavel_chart(args)
        return
    study = _study(args)
    if args.verify is not None:
        from pkdyn.design.result import check_verify

        check_verify(study, args.verify)
    if args.save_study:
        from pkdyn.files import atomic_write

        with atomic_write(args.save_study) as fh:
            fh.write(study.to_yaml())
    result = _run(study, args)
    if args.verify:
        result.verify(args.verify)
    if args.plot:
        result.plot(args.plot)
    if args.urdf:
        result.write_urdf(args.urdf)
    from pkdyn.cli._common import emit

    emit(args, result)


def _study_files(out: str) -> list[str]:
    """Every file a study writes for ``--out`` (the tables, the study file, the partial file)."""
    from pkdyn.design.table import output_paths

    return [str(p) for p in output_paths(out).values()]


def register(sub: Any) -> None:
    """Add ``design`` to the ``pkdyn`` parser."""
    sp = sub.add_parser(
        "design",
        help="design study: sweep or optimise a family's parameters (local processes or Dask)",
        description="Design study over a family's parameters; see pkdyn.design.",
    )
    sp.add_argument("family", nargs="?", help="library family (any registered family)")
    input_option(sp, "--study", metavar="FILE.yaml", help="study file (options given override it)")
    input_option(
        sp,
        "--plugin",
        or_name=True,
        action="append",
        nargs="+",
        metavar="MODULE",
        help="load a plug-in first (a module name or a .py file) whose metrics or "
        "parametrisations the study names; a study file never imports code by itself",
    )
    output_option(sp, "--save-study", metavar="FILE.yaml", help="write the study file and run it")
    sp.add_argument("--range", action="append", nargs="+", metavar="NAME=LOW:HIGH")
    spelled_option(
        sp,
        "--param",
        deprecated=("--fix",),
        action="append",
        nargs="+",
        metavar="NAME=VALUE",
        help="builder parameter held fixed (SI units), e.g. --param z_home=-0.35",
    )
    sp.add_argument(
        "--parametrisation",
        help="clavel (r, b) or mel (scale factors), or module:attr of a --plugin",
    )
    sp.add_argument(
        "--metric",
        action="append",
        nargs="+",
        metavar="NAME",
        help="metric or group (clavel, required, sizing, workspace, precision, vibration, "
        "clavel_chart)",
    )
    sp.add_argument("--constraint", action="append", nargs="+", metavar="NAME>=VALUE")
    sp.add_argument("--minimize", action="append", nargs="+", metavar="METRIC")
    sp.add_argument("--maximize", action="append", nargs="+", metavar="METRIC")
    sp.add_argument(
        "--require",
        metavar="KIND:K=V,...",
        help="required workspace: cylinder:D=,H=,x=,y=,z= | box:dx=,dy=,dz=,... | "
        "orientation:roll=,pitch=,yaw=,x=,y=,z=",
    )
    sp.add_argument("--samples", type=integer, help="samples per axis of the required workspace")
    sp.add_argument("--trajectory", choices=("adept", "sine", "p2p"), help="duty cycle")
    sp.add_argument("--payload", type=number, help="payload on the duty cycle [kg]")
    sp.add_argument("--cycle-time", type=number, help="duty cycle time [s]")
    sp.add_argument("--depth", type=number, help="adept: pick line below home [m]")
    sp.add_argument("--dt", type=number, help="duty cycle sample period [s]")
    sp.add_argument("--length", type=number, help="characteristic length for 1/cond [m]")
    sp.add_argument(
        "--actuator-stiffness",
        type=number,
        nargs="+",
        metavar="K",
        help="actuator stiffness for stiffness_min, f1_min and the vibration metrics "
        "[N m/rad or N/m]",
    )
    sp.add_argument(
        "--material", help="link material for stiffness_min, f1_min, vibration (steel...)"
    )
    sp.add_argument(
        "--damping-ratio",
        type=number,
        help="damping ratio of the first mode for the vibration metrics (0.02)",
    )
    sp.add_argument("--band", type=number, help="settling band of settling_time [m] (1e-4)")
    sp.add_argument(
        "--dwell", type=number, help="time after the duty cycle to settle within [s] (0.5)"
    )
    how = sp.add_mutually_exclusive_group()
    how.add_argument("--n", type=integer, help="number of designs (lhs, sobol, random)")
    how.add_argument("--grid", type=integer, help="full grid, values per variable")
    sp.add_argument("--sampler", choices=("lhs", "sobol", "random"))
    sp.add_argument("--optimize", choices=("nsga2",), help="multi-objective optimisation")
    sp.add_argument("--generations", type=integer, help="nsga2 generations")
    sp.add_argument("--population", type=integer, help="nsga2 population")
    sp.add_argument("--seed", type=integer)
    worker_options(sp, "the designs", "design", "; more are capped, with a warning")
    output_option(
        sp,
        "-o",
        "--out",
        companions=_study_files,
        metavar="FILE.csv",
        help="results table (.csv and .parquet; also FILE.study.yaml, the study file)",
    )
    sp.add_argument("--no-resume", action="store_true", help="ignore earlier partial results")
    output_option(sp, "--plot", figure=True, metavar="FILE.png", help="Pareto front plot")
    output_option(sp, "--urdf", metavar="FILE.urdf", help="URDF of the chosen design")
    sp.add_argument(
        "--verify",
        type=integer,
        metavar="SAMPLES",
        help="choose the best design that passes the required workspace at SAMPLES per axis",
    )
    sp.add_argument(
        "--clavel-chart",
        action="store_true",
        help="Clavel's Tableau 21: sweep r and b (--range r=.. b=.., --grid)",
    )
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_design)
