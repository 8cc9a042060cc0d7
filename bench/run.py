"""pkdyn benchmark suite (``make bench``): writes ``bench/results.md``.

Runs every benchmark module of this directory that exists (each exposes ``rows()`` returning
``(benchmark, figure, target-or-comment)`` rows): ``public`` (the public functions as users
call them against the raw-Pinocchio floor: inverse dynamics, simulation, assembly, numeric
workspace), ``geometry`` (closed forms, assembly / FK and IK against raw Pinocchio),
``dynamics`` (forward step and inverse dynamics against raw Pinocchio), ``constraints`` (a
planar loop closed by hinges against the same loop by points), ``vs_mujoco`` (forward step
and inverse dynamics against MuJoCo, agreement), ``workspace`` (workspace throughput, when
present), ``actuation_map`` (closed-loop legs, loading public models), ``cli_latency`` (command
start-up against the bare imports), ``identification`` (a Delta identified from 1e5 samples),
``design`` (design studies: per design against its arithmetic, 1 and 2 workers and a 2-worker
Dask cluster, the user's 10,000-design study and a 100,000-design scaling study: long;
``PKDYN_BENCH_DESIGNS`` and ``PKDYN_BENCH_SCALING_DESIGNS`` make them smaller), ``scaling``
(the URDF+ ladder and legged robots: set-up, per-sample inverse dynamics, forward step),
``precision_speed`` (Monte Carlo, compliant links, precision design metrics), ``calibration``
(geometric calibration of a Gough-Stewart from 100 poses, a Delta from 40, pose
sensitivities), ``vibration`` (the modal method's cycles per second, the multibody simulation,
the settling search). Figures are medians of repeated runs; ratios are medians of ratios
measured on alternating batches (CPU time of the process), so that they hold under a varying
load. ``python bench/run.py MODULE ...`` runs the modules named and replaces their sections of
``bench/results.md``, keeping the others.
"""

from __future__ import annotations

import importlib
import os
import platform
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

from pkdyn.files import atomic_write

HERE = Path(__file__).resolve().parent
OUT = HERE / "results.md"
MODULES = (
    ("public", "Public functions as users call them, beside the core and the floor (issue 14)"),
    ("geometry", "Geometric models: closed forms, assembly / FK, IK (pkdyn vs raw Pinocchio)"),
    ("dynamics", "Dynamics: forward step and inverse dynamics (pkdyn vs raw Pinocchio)"),
    (
        "constraints",
        "The constraint layer: hinge-closed against point-closed planar loops (issue 37)",
    ),
    ("vs_mujoco", "pkdyn vs MuJoCo (exported models): speed and agreement"),
    ("passive", "Passive elements: springs, dampers, friction in the dynamics"),
    ("workspace", "Workspace throughput"),
    ("actuation_map", "Closed-loop legs (actuation maps) and loading public models"),
    ("precision", "Precision: stiffness and frequency maps, closed forms and general path"),
    (
        "precision_speed",
        "Precision at the speed of its arithmetic: Monte Carlo, compliant links, design metrics "
        "(issue 37)",
    ),
    ("vibration", "Vibration along a motion: the modal method against the multibody simulation"),
    (
        "design",
        "Design studies: per design against its arithmetic, 1 and 2 workers, Dask, the "
        "10,000-design Delta study (issue 37)",
    ),
    (
        "scaling",
        "Cost that grows like the robot: the URDF+ ladder and legged robots (issue 36 item 5)",
    ),
    ("sizing", "Sizing: fastest cycle (toppra) and motor selection"),
    (
        "identification",
        "Dynamic identification: a Delta and a Gough-Stewart from 1e5 samples (issue 27)",
    ),
    ("calibration", "Geometric calibration and pose sensitivities (issues 26, 27)"),
    ("cli_latency", "Command-line start-up: pkdyn commands against importing Pinocchio and numpy"),
)

NOTES = """\
## Notes

- *raw Pinocchio* is the plainest implementation of the same computation with Pinocchio's C++
  and numpy (`bench/raw_pinocchio.py`): the same `pin.constraintDynamics` call, model,
  Baumgarte gains and proximal settings for the forward dynamics; Gauss-Newton with
  `getConstraintsJacobian` and minimum-norm least-squares steps for assembly and IK; `rnea`,
  the constraint Jacobian and one least-squares solve for the inverse dynamics.
- Forward step, per dynamics evaluation. The `euler` step makes one evaluation: its overhead is
  the torque callback, the generalized force and the state update (~3 us of Python, of which
  ~2 us for the update `v + dt a`, `integrate(q, dt v)` that any Euler step needs: against a
  raw Euler step pkdyn costs ~1.15x), hence ~1.2-1.3x the bare call on the Delta and hexapod
  (14 us raw call) and ~1.4-1.5x on the 2- and 3-dof planar robots (7-8 us raw call).
- The adaptive `dopri5` step is a Runge-Kutta-Munthe-Kaas scheme: each of its stages also
  needs `pin.integrate`, `pin.dDifference` (a dense nv x nv chart Jacobian) and two stage
  combinations, about as much Python-side work again as the raw call on these small models,
  plus the error control and a closure check per output step (a residual, ~10-15 us); its
  ratio is therefore ~2-2.5x per evaluation (~1.4x on the tripod, whose raw call is 80 us) and
  cannot reach 1.3x without moving the integrator to C++.
- pkdyn vs MuJoCo, forward step: different physics (MuJoCo: soft closures solved by its
  Newton solver inside `mj_step`, all in C; pkdyn: hard closures, proximal solver, Python
  step), given for orientation.
- Inverse dynamics: MuJoCo's `mj_inverse` is fast, but it gives generalized forces of the tree;
  the actuator efforts of a closed-loop robot need the projection through the closure Jacobian
  (`pkdyn.model.formats.mjcf.actuator_efforts`, a least-squares solve), which dominates its cost.
- Agreement: MuJoCo's closures are soft; at its stiffest impedance (0.9999) the accelerations
  differ by O(1e-4 .. 1e-2) relative; the soft solution is smooth in eps = (1 - d) / d, and
  three MuJoCo runs extrapolated to eps = 0 agree with pkdyn to the figures given. The same
  comparisons run in `tests/test_mjcf.py`.
"""


def _versions() -> str:
    import numpy as np
    import pinocchio as pin

    parts = [f"Python {platform.python_version()}", f"Pinocchio {pin.__version__}"]
    parts.append(f"numpy {np.__version__}")
    for mod in ("mujoco", "proxsuite", "coal"):
        try:
            parts.append(f"{mod} {importlib.import_module(mod).__version__}")
        except ImportError:
            parts.append(f"{mod} missing")
    return ", ".join(parts)


def _cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "cpu"


def _sections(text: str) -> dict[str, str]:
    """The ``## title`` sections of a results file, by title (each with its lines)."""
    out: dict[str, str] = {}
    parts = text.split("\n## ")
    for part in parts[1:]:
        title, _, body = part.partition("\n")
        out[title.strip()] = "## " + title + "\n" + body.rstrip("\n")
    return out


def main() -> None:
    """Run every module (or those named on the command line: their sections are replaced)."""
    sys.path.insert(0, str(HERE))
    only = set(sys.argv[1:])
    unknown = only - {name for name, _ in MODULES}
    if unknown:
        raise SystemExit(f"unknown benchmark module(s): {', '.join(sorted(unknown))}")
    start = time.perf_counter()
    load0 = os.getloadavg()[0]
    sections = []
    for name, title in MODULES:
        if not (HERE / f"{name}.py").is_file() or (only and name not in only):
            continue
        t0 = time.perf_counter()
        try:
            rows = importlib.import_module(name).rows()
        except Exception as err:  # noqa: BLE001 - a broken module must not hide the others
            rows = [(f"`bench/{name}.py` failed", f"{type(err).__name__}: {err}", "-")]
        sections.append((title, rows, time.perf_counter() - t0))
        print(f"{name}: {time.perf_counter() - t0:.0f} s", file=sys.stderr)
    if only and OUT.is_file():  # replace these modules' sections in the existing results
        old = OUT.read_text()
        head, sep, _ = old.partition("\n## ")
        kept = _sections(old)
        for title, rows, seconds in sections:
            body = [f"## {title}", "", f"({seconds:.0f} s; load average {os.getloadavg()[0]:.1f})"]
            body += ["", "| benchmark | figure | target |", "|---|---|---|"]
            body += ["| " + " | ".join(r) + " |" for r in rows]
            kept[title] = "\n".join(body)
        order = [t for _, t in MODULES]
        titles = sorted(kept, key=lambda t: order.index(t) if t in order else len(order))
        notes = kept.pop("Notes", None)
        stamp = (
            f"Sections re-run on {datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC (load average "
            f"{load0:.1f} at the start): {', '.join(t for t, _, _ in sections)}."
        )
        head = "\n".join(
            line for line in head.rstrip("\n").split("\n") if not line.startswith("Sections re-run")
        )
        text = head + "\n" + stamp + "\n\n" + "\n\n".join(kept[t] for t in titles if t != "Notes")
        text += "\n\n" + (notes if notes else NOTES.rstrip("\n")) + "\n"
        with atomic_write(OUT) as fh:
            fh.write(text)
        print(text)
        return
    lines = [
        "# pkdyn benchmark results",
        "",
        f"{datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC. Machine: {_cpu()}, "
        f"{os.cpu_count()} cores ({platform.machine()}, shared: load average "
        f"{load0:.1f} at the start, {os.getloadavg()[0]:.1f} at the end). {_versions()}.",
        f"Medians of repeated runs (`make bench`, {time.perf_counter() - start:.0f} s).",
    ]
    for title, rows, seconds in sections:
        lines += ["", f"## {title}", "", f"({seconds:.0f} s)", ""]
        lines += ["| benchmark | figure | target |", "|---|---|---|"]
        lines += ["| " + " | ".join(r) + " |" for r in rows]
    lines += ["", NOTES]
    with atomic_write(OUT) as fh:  # an interrupted run keeps the previous results
        fh.write("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
