"""The ``view`` command: a meshcat scene of a robot, served live or written as one HTML file."""

from __future__ import annotations

import argparse
import signal
import time
from typing import Any

import numpy as np

from pkdyn.cli._common import load, number, qa_argument, robot_command
from pkdyn.cli._paths import input_option, output_option
from pkdyn.exceptions import InvalidInputError

__all__ = ["register"]


def _read_points(path: str) -> np.ndarray:
    """An (N, 3) point array [m] from ``.npy`` or a text file (comma or blank separated)."""
    import io

    from pkdyn.files import read_bytes

    data = read_bytes(
        path, 256_000_000, lambda msg: InvalidInputError("--points", f"'{path}' {msg}")
    )
    try:
        if path.endswith(".npy"):
            P = np.load(io.BytesIO(data), allow_pickle=False)
        else:
            text = data.decode("utf-8").replace(",", " ")
            P = np.loadtxt(text.splitlines(), ndmin=2)
    except (OSError, ValueError) as err:
        raise InvalidInputError("--points", f"cannot read '{path}': {err}") from None
    P = np.asarray(P, dtype=float)
    if P.ndim != 2 or P.shape[1] != 3:
        raise InvalidInputError(
            "--points", f"'{path}': expected N rows of x y z [m], got {P.shape}"
        )
    return P


class _Stop(Exception):  # noqa: N818 (a stop request, not an error)
    """The live viewer was asked to stop by a signal (its number)."""

    def __init__(self, signum: int) -> None:
        self.signum = signum
        super().__init__(signum)


def _wait_for_stop(announce: str) -> int:
    """Print ``announce``, then block until Ctrl-C, SIGTERM or SIGHUP.

    The live scene's server is closed afterwards.

    The handlers are installed explicitly, before the announcement (a signal sent as soon as it
    is read must find them): a process started in the background inherits an ignored SIGINT,
    and meshcat's server runs in its own session, so it would outlive us.

    Returns:
        The signal that stopped it.

    """

    def stop(signum: int, frame: Any) -> None:
        raise _Stop(signum)

    signals = [signal.SIGINT, signal.SIGTERM, signal.SIGHUP]
    previous = {s: signal.signal(s, stop) for s in signals}
    try:
        print(announce, flush=True)
        while True:
            time.sleep(3600)
    except _Stop as err:
        print("pkdyn: viewer stopped", flush=True)
        return err.signum
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


def _exit_for(signum: int) -> None:
    """Leave as the signal asks: 130 (Ctrl-C), 143 (SIGTERM), 129 (SIGHUP): ``EXIT_CODES``."""
    from pkdyn.cli import _Terminated

    if signum == signal.SIGINT:
        raise KeyboardInterrupt
    if signum == signal.SIGTERM:
        raise _Terminated
    raise SystemExit(128 + signum)


def _configuration(robot: Any, args: argparse.Namespace) -> np.ndarray | None:
    import pkdyn

    if args.qa is not None:
        return pkdyn.forward_geometry(robot, args.qa, check_limits=False).q
    if args.pose is not None:
        return pkdyn.inverse_geometry(robot, args.pose, check_limits=False).q
    return None


def _cmd_view(args: argparse.Namespace) -> None:
    from pkdyn.viewer import Scene, chain

    robot = load(args, geometry=True)
    segments = []
    if args.trajectory:
        from pkdyn.dynamics.trajectory import named_trajectory

        for name in args.trajectory:
            traj = named_trajectory(robot, name, check_limits=False)
            segments.append((traj.t, traj.q))
    q = _configuration(robot, args)
    if q is None and segments:
        q = segments[0][1][0]
    scene = Scene(robot, q, collision=args.collision, serve=args.html is None, host=args.host)
    try:
        for k, path in enumerate(args.points or []):
            scene.add_points(
                f"points{k + 1}" if len(args.points) > 1 else "points", _read_points(path)
            )
        what = [f"{robot.name}"]
        if segments:
            t, Q = chain(segments)
            keep = scene.animate(t, Q, singular=args.singular, closest=args.closest)
            what.append(f"{' + '.join(args.trajectory)} ({t[-1]:.3g} s, {keep.size} keyframes)")
        else:
            if args.singular:
                what.append(f"configuration {scene.highlight_singular()}")
            if args.closest:
                a, b, d = scene.highlight_closest()
                what.append(f"closest {a} / {b} at {d * 1e3:.1f} mm")
        if args.html is not None:
            out = scene.save_html(args.html)
            size = out.stat().st_size / 1e6
            print(f"wrote {out} ({size:.1f} MB): {', '.join(what)}")
            return
        signum = _wait_for_stop(f"pkdyn: viewer at {scene.url} ({', '.join(what)}); Ctrl-C to stop")
    finally:
        scene.close()
    _exit_for(signum)


def register(sub: Any) -> None:
    """Add ``view`` to the ``pkdyn`` parser."""
    sp = robot_command(sub, "view", "meshcat scene of a robot (live, or a self-contained HTML)")
    where = sp.add_mutually_exclusive_group()
    where.add_argument("--pose", nargs="+", type=number, help="X Y Z [ROLL PITCH YAW] (m, rad)")
    qa_argument(where)
    sp.add_argument(
        "--trajectory",
        nargs="+",
        action="extend",
        metavar="NAME",
        help="animate built-in trajectories one after the other (adept, sine, p2p)",
    )
    output_option(sp, "--html", metavar="FILE", help="write a self-contained HTML file, no server")
    sp.add_argument(
        "--host",
        default="127.0.0.1",
        help="address the live viewer listens on (default 127.0.0.1: this machine only; "
        "0.0.0.0 serves every interface, with a warning)",
    )
    sp.add_argument("--collision", action="store_true", help="draw the collision geometry")
    sp.add_argument(
        "--singular", action="store_true", help="colour singular (red), near-singular (pink)"
    )
    sp.add_argument(
        "--closest", action="store_true", help="colour the two bodies closest to collision"
    )
    input_option(
        sp,
        "--points",
        action="append",
        metavar="FILE",
        help="overlay a point cloud (N x 3 [m], .npy or text)",
    )
    sp.set_defaults(func=_cmd_view)
