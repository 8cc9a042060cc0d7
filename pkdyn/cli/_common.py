"""Shared pieces of the command line: parameters, loading, output, configuration arguments."""

from __future__ import annotations

import argparse
import difflib
import math
import os
import re
from collections.abc import Sequence
from typing import Any, NoReturn

import numpy as np

from pkdyn.cli._paths import check_figure
from pkdyn.cli._spelling import spelled_option
from pkdyn.exceptions import InvalidInputError, close_match

__all__ = [
    "NEGATIVE_NUMBER",
    "Parser",
    "add_param_option",
    "check_figure",
    "configuration",
    "emit",
    "fmt",
    "gains_of",
    "reads_differently",
    "integer",
    "load",
    "check_numbers",
    "number",
    "params",
    "posed_command",
    "qa_argument",
    "robot_command",
    "units",
]


class _Formatter(argparse.HelpFormatter):
    """argparse's formatter, with the terminal width read without importing shutil (4 ms)."""

    def __init__(self, prog: str, **kwargs: Any) -> None:
        if kwargs.get("width") is None:
            try:
                width = int(os.environ["COLUMNS"])
            except (KeyError, ValueError):
                try:
                    width = os.get_terminal_size().columns
                except OSError:
                    width = 80
            kwargs["width"] = max(width - 2, 40)
        super().__init__(prog, **kwargs)


NEGATIVE_NUMBER = re.compile(
    r"^-(?:(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|inf|infinity|nan)$", re.IGNORECASE
)
"""A negative number in any notation (``-3``, ``-.5``, ``-3.6e-1``, ``-5E+1``; ``-inf`` and
``-nan`` too, so that the number's type refuses them with a message): a value, not an option.
argparse's own matcher knows only ``-3`` and ``-3.5``."""


class Parser(argparse.ArgumentParser):
    """Argument parser whose errors are one line and exit code 2.

    Negative numbers in any notation are values (:data:`NEGATIVE_NUMBER`); a mistyped option
    is refused before anything else with the closest option of the command
    (``unrecognized option '--pos'; did you mean '--pose'?``).
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"pkdyn: error: {message}{_did_you_mean(message)} (see {self.prog} --help)\n")

    def parse_known_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        if args is not None and not any(
            isinstance(a, argparse._SubParsersAction) for a in self._actions
        ):
            self._check_options(list(args))
        return super().parse_known_args(args, namespace)

    def _check_options(self, args: list[str]) -> None:
        """Refuse an option this (leaf) command does not have, with the closest one."""
        known = list(self._option_string_actions)
        for tok in args:
            if tok == "--":
                return
            if not tok.startswith("-") or tok == "-" or " " in tok:
                continue
            if self._negative_number_matcher.match(tok):
                continue
            opt = tok.split("=", 1)[0] if tok.startswith("--") else tok
            if opt in known:
                continue
            if tok.startswith("--") and any(k.startswith(opt) for k in known):
                continue  # an abbreviation: argparse resolves it (or says it is ambiguous)
            if not tok.startswith("--") and len(tok) > 2 and tok[:2] in known:
                continue  # -ofile: -o with its value attached
            close = difflib.get_close_matches(opt, known, n=2, cutoff=0.6)
            hint = "; did you mean " + " or ".join(f"'{c}'" for c in close) + "?" if close else ""
            self.error(f"unrecognized option '{opt}'{hint}")


def _did_you_mean(message: str) -> str:
    """``; did you mean 'fk'?`` for an argparse "invalid choice" close to a valid one."""
    m = re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message)
    if m is None:
        return ""
    return close_match(m[1], re.findall(r"'([^']*)'", m[2]))


def number(text: str) -> float:
    """The argparse type of a numeric option: a number in any notation (``-3.6e-1``, ``-.5``).

    NaN is refused by :func:`check_numbers` after parsing (exit 1, naming the option); an
    infinity is left to the command, which refuses it where it is not meaningful (a rigid
    ``--actuator-stiffness inf`` is; most are not).

    Raises:
        argparse.ArgumentTypeError: Not a number (exit 2, one line).

    """
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a number") from None


def check_numbers(parser: Any, args: argparse.Namespace) -> None:
    """Refuse NaN in every numeric option of the command, before any work.

    Raises:
        InvalidInputError: A value is NaN (``nan``, ``-nan``), naming the option and which value.

    """
    from pkdyn.cli._paths import chosen_parser

    for action in getattr(chosen_parser(parser, args), "_actions", ()):
        if action.type is not number:
            continue
        value = getattr(args, action.dest, None)
        values = value if isinstance(value, list) else [value]
        flat = [v for item in values for v in (item if isinstance(item, list) else [item])]
        for k, v in enumerate(flat):
            if isinstance(v, float) and math.isnan(v):
                name = (action.option_strings or [action.dest])[-1]
                which = f"value #{k + 1} is nan" if len(flat) > 1 else "is nan"
                raise InvalidInputError(name, f"{which} (not a number); give a finite number")


def integer(text: str) -> int:
    """The argparse type of a count: a whole number (``-2``, ``1000``, ``1e3``).

    Raises:
        argparse.ArgumentTypeError: Not a whole number.

    """
    try:
        return int(text)
    except ValueError:
        pass
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a whole number") from None
    if not (math.isfinite(x) and x.is_integer() and abs(x) < 1e15):
        raise argparse.ArgumentTypeError(f"'{text}' is not a whole number")
    return int(x)


def params(items: Sequence[str] | None) -> dict[str, Any]:
    """Builder parameters from ``--param`` items (``NAME=VALUE``; repeated or several at once).

    Raises:
        InvalidInputError: An item is not ``NAME=VALUE`` or a name is given twice.

    """
    out: dict[str, Any] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise InvalidInputError(
                "--param", f"'{item}': expected NAME=VALUE (give ROBOT before --param)"
            )
        if key in out:
            raise InvalidInputError("--param", f"'{key}' is given twice")
        out[key] = value.strip()
    return out


def add_param_option(sp: argparse.ArgumentParser) -> None:
    """``--param NAME=VALUE [NAME=VALUE ...]``, repeatable."""
    sp.add_argument(
        "--param",
        nargs="+",
        action="extend",
        metavar="NAME=VALUE",
        help="builder parameters (SI units), e.g. --param la=0.3 lb=0.8; see pkdyn list",
    )


def load(args: argparse.Namespace, geometry: bool = False) -> Any:
    import pkdyn

    extra: dict[str, Any] = {}
    if getattr(args, "home", None) is not None:
        extra["home"] = args.home
    if getattr(args, "tol", None) is not None:
        extra["tol"] = args.tol
    if getattr(args, "xacro_arg", None):
        from pkdyn.model.formats.xacro_files import parse_xacro_args

        extra["xacro_args"] = parse_xacro_args(args.xacro_arg)
    if getattr(args, "ignore_element", None):
        extra["ignore_elements"] = tuple(args.ignore_element)
    if getattr(args, "repair_inertias", False):
        extra["repair_inertias"] = True
    robot = pkdyn.load(args.robot, geometry=geometry, **extra, **params(args.param))
    _resolve_readings(args, robot)
    return robot


def _non_finite(value: Any, where: str = "") -> str | None:
    """Path of the first NaN or infinite number in a JSON-ready value, else ``None``."""
    if isinstance(value, float):
        return None if math.isfinite(value) else (where or "value")
    if isinstance(value, dict):
        for k, v in value.items():
            found = _non_finite(v, f"{where}.{k}" if where else str(k))
            if found:
                return found
    if isinstance(value, list | tuple):
        for i, v in enumerate(value):
            found = _non_finite(v, f"{where}[{i}]")
            if found:
                return found
    return None


def emit(args: argparse.Namespace, payload: Any, text: str | None = None) -> None:
    """Print the result: one JSON object with ``--json`` (never NaN or Infinity), else text.

    Args:
        args: The parsed command line (``--json``).
        payload: A :class:`pkdyn.results.Result` (its ``to_json()`` and ``table()`` are
            printed), or a JSON-ready dict with its ``text``.
        text: The text (for a dict payload).

    Raises:
        InvalidInputError: A result is not finite (an input overflowed the computation).

    """
    from pkdyn.results import Result

    if isinstance(payload, Result):
        text = payload.table() if text is None else text
        payload = payload.to_json()
    bad = _non_finite(payload)
    if bad is not None:
        raise InvalidInputError(
            bad, "the result is not a finite number (an input is too large or degenerate)"
        )
    if args.json:
        import json

        print(json.dumps(payload, allow_nan=False))
    else:
        print(text or "")


def units(robot: Any) -> list[tuple[str, str, str]]:
    """Per actuator: position, speed and effort units (``rad, rad/s, N m`` or ``m, m/s, N``)."""
    return [
        ("m", "m/s", "N") if prismatic else ("rad", "rad/s", "N m")
        for prismatic in robot.actuator_prismatic
    ]


def fmt(v: np.ndarray) -> str:
    return " ".join(f"{x:.6f}" for x in v)


def configuration(args: argparse.Namespace, geometry: bool = False) -> tuple[Any, np.ndarray]:
    """The robot and the assembled configuration named by ``--pose`` or ``--qa``."""
    import pkdyn

    robot = load(args, geometry=geometry)
    if args.qa is not None:
        return robot, pkdyn.forward_geometry(robot, args.qa, check_limits=False).q
    return robot, pkdyn.inverse_geometry(robot, args.pose, check_limits=False).q


def qa_argument(parser: Any, required: bool = False) -> None:
    """Add ``--qa QA...`` (joint coordinates) and ``--readings R...`` (encoder readings).

    ``--qa``: the actuated joint coordinates, in actuator order (``--q``, its former spelling,
    kept for one release). ``--readings``:
    the actuators' encoder readings, the description's ``<pkdyn:encoder gain>`` applied (joint
    coordinate = gain x reading). One of them is required when ``required``.
    """
    where = parser.add_mutually_exclusive_group(required=True) if required else parser
    spelled_option(
        where,
        "--qa",
        deprecated=("--q",),
        nargs="+",
        type=number,
        metavar="QA",
        help="actuated joint coordinates in actuator order (rad or m)",
    )
    where.add_argument(
        "--readings",
        nargs="+",
        type=number,
        metavar="R",
        help="actuator (encoder) readings in actuator order: the description's "
        "<pkdyn:encoder gain> applied (joint coordinate = gain x reading)",
    )


def gains_of(robot: Any) -> np.ndarray:
    """The actuators' encoder gains (n_a,) (:meth:`pkdyn.Robot.joint_coordinates`'s rule)."""
    return np.asarray(robot.encoder_gains)


def reads_differently(robot: Any) -> bool:
    """Whether the robot's readings differ from its joint coordinates (gains or offsets)."""
    return bool(np.any(robot.encoder_gains != 1.0) or np.any(robot.encoder_offsets != 0.0))


def _resolve_readings(args: argparse.Namespace, robot: Any) -> None:
    """Turn ``--readings`` into ``args.qa`` (joint coordinates).

    ``--qa`` on a robot with encoder gains, where readings and coordinates differ, prints a note.
    """
    readings = getattr(args, "readings", None)
    gains = gains_of(robot)
    if readings is not None:
        from pkdyn.inputs import vector

        r = vector("--readings", readings, len(gains), "rad or m")
        args.qa = [float(v) for v in robot.joint_coordinates(r)]  # the one readings rule
    elif getattr(args, "qa", None) is not None and reads_differently(robot):
        import sys

        listed = ", ".join(
            f"{a.name} {g:.9g}" for a, g in zip(robot.actuators, gains, strict=True) if g != 1.0
        )
        print(
            f"pkdyn: note: {robot.name} has encoder gains ({listed}): --qa are joint "
            "coordinates; give encoder readings with --readings",
            file=sys.stderr,
        )


def robot_command(
    sub: Any, name: str, help_: str, aliases: tuple[str, ...] = ()
) -> argparse.ArgumentParser:
    """A sub-command taking ``ROBOT`` and ``--param NAME=VALUE`` (also called ``aliases``)."""
    sp: argparse.ArgumentParser = sub.add_parser(name, help=help_, aliases=list(aliases))
    from pkdyn.cli._paths import input_option

    input_option(
        sp, "robot", or_name=True, help="library family name, or a URDF, MJCF or SDFormat file"
    )
    add_param_option(sp)
    sp.add_argument(
        "--home",
        nargs="+",
        type=number,
        metavar="Q",
        help="home configuration to assemble: actuator coordinates, or a full configuration",
    )
    sp.add_argument(
        "--tol",
        type=number,
        metavar="TOL",
        help="assembly tolerance (m or rad): closure errors of a CAD-rounded description that "
        "are absorbed with a warning (default 1e-4)",
    )
    sp.add_argument(
        "--xacro-arg",
        action="append",
        metavar="NAME:=VALUE",
        help="argument of a .xacro file (repeatable), e.g. --xacro-arg prefix:=left_",
    )
    sp.add_argument(
        "--ignore-element",
        action="append",
        metavar="NAME",
        help="leave the file's elements of this name out (repeatable), e.g. --ignore-element "
        "loop: an element pkdyn does not read whose name says loop, closure, constraint or "
        "coupling is otherwise an error",
    )
    sp.add_argument(
        "--repair-inertias",
        action="store_true",
        help="replace the file's physically invalid inertia tensors by the nearest valid ones "
        "(same principal axes; the links are named)",
    )
    return sp


def posed_command(sub: Any, name: str, help_: str) -> argparse.ArgumentParser:
    """A robot sub-command at one configuration given by ``--pose`` or ``--qa``, with ``--json``."""
    sp = robot_command(sub, name, help_)
    where = sp.add_mutually_exclusive_group(required=True)
    where.add_argument("--pose", nargs="+", type=number, help="X Y Z [ROLL PITCH YAW] (m, rad)")
    qa_argument(where)
    sp.add_argument("--json", action="store_true")
    return sp


def worker_options(
    sp: argparse.ArgumentParser, what: str, per: str = "chunk of work", more: str = ""
) -> None:
    """``--workers``, ``--scheduler``, ``--timeout``: where a command's work runs.

    Args:
        sp: The sub-command's parser.
        what: What the workers evaluate (the help).
        per: The unit of work a worker takes (the help: at most one worker per ``per``).
        more: What happens to more workers (the help), if anything.

    """
    sp.add_argument(
        "--workers",
        type=integer,
        help=f"local worker processes for {what} (default: the usable cores, at most one per "
        f"{per}{more})",
    )
    sp.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler, e.g. tcp://host:8786")
    sp.add_argument(
        "--timeout",
        type=number,
        default=10.0,
        help="seconds to wait for the scheduler to answer, or for a worker (10; at most 3600)",
    )


def check_worker_options(args: argparse.Namespace) -> None:
    """``--workers``, ``--scheduler`` and ``--timeout`` checked before any work."""
    from pkdyn.executors import check_scheduler, check_timeout

    check_timeout(args.timeout, "--timeout")
    check_scheduler(args.scheduler, "--scheduler")
    if args.workers is not None and args.workers < 1:
        raise InvalidInputError("--workers", f"must be >= 1, got {args.workers}")
