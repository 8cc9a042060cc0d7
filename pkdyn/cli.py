"""The ``pkdyn`` command line.

``ROBOT`` is a library family name or a URDF path; ``--param k=v`` overrides builder parameters;
``--json`` prints one JSON object. A user error prints one line on stderr and exits with 1.
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from collections.abc import Sequence
from typing import Any, NoReturn

import numpy as np

from pkdyn.exceptions import PkdynError

__all__ = ["main"]


class _Parser(argparse.ArgumentParser):
    """Argument parser whose errors are one line and exit code 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"pkdyn: error: {message} (see pkdyn {self.prog.split()[-1]} --help)\n")


def _params(items: Sequence[str] | None) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise PkdynError(f"--param '{item}': expected NAME=VALUE")
        out[key.strip()] = value.strip()
    return out


def _load(args: argparse.Namespace, geometry: bool = False) -> Any:
    import pkdyn

    return pkdyn.load(args.robot, geometry=geometry, **_params(args.param))


def _emit(args: argparse.Namespace, payload: dict[str, Any], text: str) -> None:
    if args.json:
        print(json.dumps(payload))
    else:
        print(text)


def _fmt(v: np.ndarray) -> str:
    return " ".join(f"{x:.6f}" for x in v)


def _cmd_info(args: argparse.Namespace) -> None:
    robot = _load(args)
    closures = [{"name": c.name, "type": c.kind} for c in robot.closures]
    payload = {
        "name": robot.name,
        "nq": robot.nq,
        "nv": robot.nv,
        "dof": robot.dof(),
        "actuated": robot.actuator_names,
        "loops": robot.loops,
        "closures": closures,
    }
    lines = [
        f"{robot.name}: nq={robot.nq} nv={robot.nv} dof={payload['dof']} loops={robot.loops}",
        "actuated: " + ", ".join(robot.actuator_names),
        "closures: " + ", ".join(f"{c['name']} ({c['type']})" for c in closures),
    ]
    _emit(args, payload, "\n".join(lines))


def _cmd_urdf(args: argparse.Namespace) -> None:
    from pkdyn import library

    params = _params(args.param)
    if args.robot in library.FAMILIES:
        fam = library.FAMILIES[args.robot]
        text = fam.build_urdf(fam.make_params(params))
    else:
        import pkdyn

        pkdyn.load(args.robot, geometry=False, **params)  # validates the file
        with open(args.robot) as fh:
            text = fh.read()
    if args.output:
        try:
            with open(args.output, "w") as fh:
                fh.write(text)
        except OSError as err:
            raise PkdynError(f"cannot write '{args.output}': {err.strerror}") from None
    else:
        sys.stdout.write(text)


def _cmd_fk(args: argparse.Namespace) -> None:
    import pkdyn

    robot = _load(args)
    res = pkdyn.forward_geometry(robot, args.q)
    if res.placement is None:
        raise PkdynError(f"{robot.name} declares no platform frame; nothing to report")
    payload = {
        "position": res.position.tolist(),
        "rpy": res.rpy.tolist(),
        "q_full": res.q.tolist(),
        "residual": res.residual,
    }
    text = f"position [m]: {_fmt(res.position)}\nrpy [rad]:    {_fmt(res.rpy)}"
    _emit(args, payload, text)


def _cmd_ik(args: argparse.Namespace) -> None:
    import pkdyn

    robot = _load(args)
    res = pkdyn.inverse_geometry(robot, args.pose)
    names = robot.actuator_names
    payload = {"q": res.qa.tolist(), "actuators": names, "residual": res.residual}
    text = "\n".join(f"{n}: {v:.9f}" for n, v in zip(names, res.qa, strict=True))
    _emit(args, payload, text)


def _cmd_mobility(args: argparse.Namespace) -> None:
    from pkdyn.mobility import format_mobility, mobility

    result = mobility(_load(args))
    _emit(args, result.as_json(), format_mobility(result))


def _configuration(args: argparse.Namespace) -> tuple[Any, np.ndarray]:
    """The robot and the assembled configuration named by ``--pose`` or ``--q``."""
    import pkdyn

    robot = _load(args)
    if args.q is not None:
        return robot, pkdyn.forward_geometry(robot, args.q, check_limits=False).q
    return robot, pkdyn.inverse_geometry(robot, args.pose, check_limits=False).q


def _cmd_jacobian(args: argparse.Namespace) -> None:
    from pkdyn.kinematics import jacobian_json

    robot, q = _configuration(args)
    out = jacobian_json(robot, q)
    text = "\n".join(f"{k} =\n{np.array2string(np.array(out[k]), precision=5)}" for k in "ABJ")
    _emit(args, out, text)


def _cmd_singularity(args: argparse.Namespace) -> None:
    from pkdyn.singularity import singularity_json

    robot, q = _configuration(args)
    out = singularity_json(robot, q)
    text = (
        f"{out['kind']}: cond(A) = {out['cond_A']:.4g}, cond(B) = {out['cond_B']:.4g}, "
        f"distance = {out['distance']:.4g}"
    )
    _emit(args, out, text)


def _cmd_statics(args: argparse.Namespace) -> None:
    from pkdyn.statics import statics_json

    robot, q = _configuration(args)
    out = statics_json(robot, q, args.wrench, gravity=args.gravity)
    text = "\n".join(f"{n}: {t:.6g}" for n, t in zip(out["actuators"], out["tau"], strict=True))
    _emit(args, out, text)


def _cmd_demo(args: argparse.Namespace) -> None:
    from pkdyn.demo import run_demo

    run_demo()


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="pkdyn", description="Kinematics and dynamics of parallel robots.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    def robot_cmd(name: str, help_: str) -> argparse.ArgumentParser:
        sp = sub.add_parser(name, help=help_)
        sp.add_argument("robot", help="library family name or URDF path")
        sp.add_argument("--param", action="append", metavar="NAME=VALUE", help="builder parameter")
        return sp

    sp = robot_cmd("info", "model summary")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_info)
    sp = robot_cmd("urdf", "write the description")
    sp.add_argument("-o", "--output", help="output file (default: stdout)")
    sp.set_defaults(func=_cmd_urdf)
    sp = robot_cmd("fk", "direct geometric model")
    sp.add_argument("--q", nargs="+", type=float, required=True, help="actuated coordinates")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_fk)
    sp = robot_cmd("ik", "inverse geometric model")
    sp.add_argument(
        "--pose", nargs="+", type=float, required=True, help="X Y Z [ROLL PITCH YAW] (m, rad)"
    )
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_ik)
    sp = robot_cmd("mobility", "mobility: Gruebler and rank-based (Pasqui), internal mobilities")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_mobility)

    def posed(name: str, help_: str) -> argparse.ArgumentParser:
        sp = robot_cmd(name, help_)
        where = sp.add_mutually_exclusive_group(required=True)
        where.add_argument("--pose", nargs="+", type=float, help="X Y Z [ROLL PITCH YAW] (m, rad)")
        where.add_argument("--q", nargs="+", type=float, help="actuated coordinates")
        sp.add_argument("--json", action="store_true")
        return sp

    posed("jacobian", "parallel-robot form A xd = B qd, J = A^-1 B").set_defaults(
        func=_cmd_jacobian
    )
    posed("singularity", "regular / serial / parallel / both, conditioning").set_defaults(
        func=_cmd_singularity
    )
    sp = posed("statics", "actuator efforts holding the platform against a wrench")
    sp.add_argument(
        "--wrench",
        nargs=6,
        type=float,
        default=[0.0] * 6,
        metavar=("FX", "FY", "FZ", "MX", "MY", "MZ"),
    )
    sp.add_argument("--gravity", action="store_true", help="include the robot's weight")
    sp.set_defaults(func=_cmd_statics)
    sp = sub.add_parser("demo", help="run the demonstration on built-in defaults")
    sp.set_defaults(func=_cmd_demo)
    return p


def _one_line_warning(message: Warning | str, category: type[Warning], *_: Any, **__: Any) -> None:
    print(f"pkdyn: warning: {message}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line.

    Args:
        argv: Arguments (default: ``sys.argv[1:]``).

    Returns:
        Exit code: 0 on success, 1 on a user error (one line on stderr).

    """
    args = _parser().parse_args(argv)
    warnings.showwarning = _one_line_warning
    try:
        args.func(args)
    except PkdynError as err:
        print(f"pkdyn: error: {err}", file=sys.stderr)
        return 1
    except BrokenPipeError:
        return 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
