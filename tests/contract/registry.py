"""The registry of pkdyn's entry points: every command of ``pkdyn`` and every public function,
class and method, with the kind of each argument and a valid baseline call.

``tests/contract/test_contract_registry.py`` compares it with what exists (the parser, every
``__all__``, the public methods of the public classes) and fails naming any entry point not
registered here, or registered but gone. The drive (``test_contract_api.py``,
``test_contract_cli.py``) calls each entry point with its baseline, one argument replaced by a
bad value of each class its kind has (:mod:`contract.kinds`).

How to register a new entry point: ``tests/contract/README.md``.
"""

from __future__ import annotations

from typing import Any

from contract import fixtures as fx
from contract.entries import Api, Cli, Exempt
from contract.kinds import (
    Arg,
    Choice,
    Count,
    Flag,
    Kind,
    Mapping,
    Names,
    Opaque,
    PathIn,
    PathOut,
    Pose,
    Real,
    Vector,
)
from contract.pending import PENDING_CLI

__all__ = ["API", "CLI", "EXEMPT", "PENDING", "Api", "Cli", "Exempt", "pending"]


PENDING: dict[str, str] = {
    **PENDING_CLI,
}


def pending(tid: str) -> str | None:
    """The reason a case is expected to fail on this branch (``PENDING``: an exact test id,
    or a prefix ending with ``|``), else ``None``."""
    if tid in PENDING:
        return PENDING[tid]
    return next((r for k, r in PENDING.items() if k.endswith("|") and tid.startswith(k)), None)


"""Cases known to fail on this branch because their fix is on another: test id prefix ->
reason (``xfail(strict=True)``: the lead removes the mark when the branches meet)."""


# --------------------------------------------------------------------------------------------
# the command line

CLAVEL = ("--clavel",)
SETTLE = ("--fastest", "--band", "1e-4", "--actuator-stiffness", "2e4", "--dwell", "0.1")
STIFFNESS_MAP = ("--map", "xy", "--grid", "3")
VIBRATION_METRIC = ("--metric", "settling_time", "--actuator-stiffness", "2e4", "--dt", "0.004")
ORIENTATION = ("ROBOT=gough_stewart", "--kind", "orientation", "--n1", "6", "--n2", "12")
MAP = ("--map", "xy", "--grid", "3")
MONTE_CARLO = ("--samples", "4")
CATALOG = ("--catalog", "{catalog.yaml}")
SIZING = ("--metric", "peak_effort", "--dt", "0.004")
REQUIRE = ("--require", "box:dx=0.05,dy=0.05,dz=0.05,z=-0.35", "--samples", "2")
PRECISION = ("--metric", "stiffness_min", *REQUIRE)
NSGA2 = ("--optimize", "nsga2", "--minimize", "moving_mass", "--generations", "1")
GENERAL_MAP = ("ROBOT=five_bar", "--map", "xy", "--grid", "3")
"""A precision map on the general (pose-by-pose) path: the one the workers share."""


def _robot_options(family: str, param: str) -> dict[str, Arg]:
    """``ROBOT``, ``--param``, ``--home``, ``--tol``, ``--xacro-arg`` of a robot command."""
    return {
        "robot": Arg(
            RobotSource(key="robot.urdf"), names=("robot", "no_such", "robot.urdf", ".urdf")
        ),
        "--param": Arg(Mapping({param: 0.2}), names=("param", param, "no_such_key")),
        "--home": Arg(Vector("n_a"), names=("home",)),
        "--tol": Arg(Real(sign="positive"), names=("tol",)),
        "--xacro-arg": Arg(Assign(), names=("xacro",)),
        "--ignore-element": Arg(Names(), names=("ignore", "element", "no_such_name")),
        "--repair-inertias": Arg(Flag()),
    }


def _posed(which: str = "pose qa readings json") -> dict[str, Arg]:
    """``--pose``, ``--qa``, ``--readings``, ``--json`` of a command at one configuration."""
    opts = {
        "--pose": Arg(Pose("task"), names=("pose", "reach", "components")),
        "--qa": Arg(Vector("n_a"), names=("qa", "actuat", "reach", "assembl")),
        "--readings": Arg(Vector("n_a"), names=("readings", "actuat", "reach", "assembl")),
        "--json": Arg(Flag()),
    }
    return {k: v for k, v in opts.items() if k[2:] in which.split()}


class RobotSource(Kind):
    """``ROBOT``: a library family name or a description file."""

    def __init__(self, key: str = "robot.urdf") -> None:
        self.key = key

    def cli(self) -> dict[str, Any]:
        from hypothesis import strategies as st

        from contract.kinds import Case

        files = PathIn(key=self.key, fmt="urdf").cli()
        files.pop("empty", None)  # (covered below with the unknown names)
        return files | {
            "unknown": st.sampled_from(["delt", "no_such_robot", "", "-"]).map(
                lambda v: Case("unknown", repr(v), lambda s, v=v: [v])
            )
        }


class Assign(Kind):
    """``NAME:=VALUE`` (a xacro argument)."""

    def cli(self) -> dict[str, Any]:
        from contract.kinds import _tokens

        return {"wrong_type": _tokens("wrong_type", [["noassign"], [":=1"]])}


class RangeSpec(Kind):
    """``NAME=LOW:HIGH`` (a design variable's range)."""

    def cli(self) -> dict[str, Any]:
        from contract.kinds import _tokens

        return {
            "wrong_type": _tokens("wrong_type", [["la"], ["la=0.2"], ["la=a:b"], ["=0.2:0.3"]]),
            "non_finite": _tokens("non_finite", [["la=nan:0.3"], ["la=0.2:inf"]]),
            "huge": _tokens("huge", [["la=0.2:1e308"]]),
            "empty": _tokens("empty", [["la=0.3:0.2"], ["la=0.2:0.2"]], refuse=False),
            "unknown": _tokens("unknown", [["no_such_key=0.1:0.2"]]),
        }


def _worker_options(context: tuple[str, ...]) -> dict[str, Arg]:
    """``--workers``, ``--scheduler``, ``--timeout`` (``context``: where the work is shared)."""
    return {
        "--workers": Arg(Count(), names=("workers",), context=context),
        "--scheduler": Arg(Choice(), names=("scheduler",), context=context),
        "--timeout": Arg(Real(sign="positive"), names=("timeout",), context=context),
    }


def _map_options() -> dict[str, Arg]:
    """The map options of ``stiffness`` and ``modes`` (``--map PLANE`` and its grid)."""
    return {
        "--map": Arg(Choice(("xy", "xz", "yz")), names=("map",)),
        "--center": Arg(Vector(3), names=("center",), context=STIFFNESS_MAP),
        "--extent": Arg(Real(sign="positive"), names=("extent",), context=STIFFNESS_MAP),
        "--grid": Arg(Count(minimum=2), names=("grid",), context=STIFFNESS_MAP),
        "--plot": Arg(PathOut(".png", onto=("robot.urdf",)), names=("plot",),
                      context=STIFFNESS_MAP),
        "--csv": Arg(PathOut(".csv", onto=("robot.urdf",)), names=("csv",), context=STIFFNESS_MAP),
        "--field": Arg(Choice(("stiffness_min", "deflection")), names=("field",),
                       context=STIFFNESS_MAP),
        "--shear": Arg(Choice(("on", "off")), names=("shear",)),
    }  # fmt: skip


def _robot_cmd(
    words: tuple[str, ...],
    family: str,
    param: str,
    extra: list[str],
    options: dict[str, Arg],
    posed: bool | str = False,
    **kw: Any,
) -> Cli:
    which = posed if isinstance(posed, str) else "pose qa readings json"
    opts = _robot_options(family, param) | (_posed(which) if posed else {}) | options
    inputs = {"robot.urdf": lambda f=family: fx.urdf_text(f)} | kw.pop("inputs", {})
    return Cli(words, [family, *extra], opts, robot=family, inputs=inputs, **kw)


CLI: list[Cli] = [
    Cli(("list",), [], {"--params": Arg(Flag()), "--json": Arg(Flag())}),
    Cli(("demo",), [], {}, slow=True, timeout=120),
    _robot_cmd(("info",), "five_bar", "l1", [], {"--json": Arg(Flag())}),
    _robot_cmd(
        ("urdf",),
        "five_bar",
        "l1",
        ["-o", "{out.urdf}"],
        {"--out": Arg(PathOut(".urdf", onto=("robot.urdf",)), names=("-o", "output"))},
    ),
    _robot_cmd(
        ("forward-geometry",),
        "five_bar",
        "l1",
        ["--qa", "1.2", "1.9"],
        {},
        posed="qa readings json",
    ),
    _robot_cmd(
        ("inverse-geometry",), "delta", "la", ["--pose", "0", "0", "-0.4"], {}, posed="pose json"
    ),
    _robot_cmd(("mobility",), "five_bar", "l1", [], {"--json": Arg(Flag())}),
    _robot_cmd(("jacobian",), "delta", "la", ["--pose", "0", "0", "-0.4"], {}, posed=True),
    _robot_cmd(("singularity",), "delta", "la", ["--pose", "0", "0", "-0.4"], {}, posed=True),
    _robot_cmd(
        ("statics",),
        "delta",
        "la",
        ["--pose", "0", "0", "-0.4", "--wrench", "0", "0", "-5", "0", "0", "0"],
        {"--wrench": Arg(Vector(6), names=("wrench",)), "--gravity": Arg(Flag())},
        posed=True,
    ),
    _robot_cmd(
        ("simulate",),
        "five_bar",
        "l1",
        ["--duration", "0.02", "--dt", "0.01"],
        {
            "--duration": Arg(Real(sign="positive"), names=("duration",)),
            "--dt": Arg(Real(sign="positive"), names=("dt",)),
            "--integrator": Arg(Choice(("dopri5", "rk4", "euler")), names=("integrator",)),
            "--step": Arg(Real(sign="positive"), names=("step",)),
            "--v0": Arg(Vector("n_a"), names=("v0", "velocit")),
            "--torque": Arg(Vector("n_a"), names=("torque", "effort")),
            "--csv": Arg(PathOut(".csv", onto=("robot.urdf",)), names=("csv",)),
            "--plot": Arg(PathOut(".png", onto=("robot.urdf",)), names=("plot", "figure")),
            "--html": Arg(PathOut(".html", onto=("robot.urdf",)), names=("html",)),
            "--json": Arg(Flag()),
        },
    ),
    _robot_cmd(
        ("size",),
        "delta",
        "la",
        ["--dt", "0.004"],
        {
            "--trajectory": Arg(
                PathIn(key="trajectory.csv"), names=("trajectory", "trajectory.csv", "t,x")
            ),
            "--payload": Arg(Real(sign="non_negative"), names=("payload",)),
            "--cycle-time": Arg(Real(sign="positive"), names=("cycle", "cycle_time")),
            "--cycles": Arg(Count(), names=("cycles",)),
            "--profile": Arg(Choice(("quintic", "jerk")), names=("profile",)),
            "--dt": Arg(Real(sign="positive"), names=("dt",)),
            "--csv": Arg(PathOut(".csv", onto=("robot.urdf", "trajectory.csv")), names=("csv",)),
            "--plot": Arg(PathOut(".png", onto=("robot.urdf",)), names=("plot", "figure")),
            "--no-passive": Arg(Flag()),
            "--fastest": Arg(Flag()),
            "--catalog": Arg(PathIn(key="catalog.yaml", fmt="yaml"), names=("catalog",)),
            "--gearboxes": Arg(
                PathIn(key="catalog.yaml", fmt="yaml"), names=("gearbox",), context=CATALOG
            ),
            "--criterion": Arg(
                Choice(("rated_torque", "mass", "price")), names=("criterion",), context=CATALOG
            ),
            "--top": Arg(Count(minimum=0), names=("top", "show"), context=CATALOG),
            "--band": Arg(Real(sign="positive"), names=("band", "settle")),
            "--dwell": Arg(Real(sign="positive"), names=("dwell",), context=SETTLE),
            "--actuator-stiffness": Arg(
                Vector((1, 3), inf_ok=True),
                names=("actuator-stiffness", "actuator_stiffness"),
                context=SETTLE,
            ),
            "--damping-ratio": Arg(
                Real(sign="non_negative"),
                names=("damping-ratio", "damping_ratio"),
                context=SETTLE,
            ),
            "--material": Arg(
                Choice(("steel", "aluminium", "carbon")), names=("material",), context=SETTLE
            ),
            "--shaper": Arg(Choice(("zv", "zvd", "none")), names=("shaper",), context=SETTLE),
            "--operating-points": Arg(
                PathOut(".png", onto=("robot.urdf", "catalog.yaml")),
                names=("operating", "catalog"),
                context=CATALOG,
            ),
            "--json": Arg(Flag()),
        },
        inputs={"trajectory.csv": fx.trajectory_csv, "catalog.yaml": fx.catalog_yaml},
        # (--cycles 2e0 is accepted: two cycles to size; --damping-ratio 0 with --band: the
        # motion stretched until an undamped vibration stays in the band, ~15 s of CPU)
        timeout=60,
    ),
    _robot_cmd(
        ("collisions",),
        "delta",
        "la",
        ["--pose", "0", "0", "-0.4"],
        {
            "--margin": Arg(Real(sign="non_negative"), names=("margin",)),
            "--pair": Arg(Names(), names=("pair", "no_such_name")),
            "--top": Arg(Count(minimum=0), names=("top",)),
        },
        posed=True,
    ),
    _robot_cmd(
        ("workspace",),
        "delta",
        "la",
        ["--samples", "5", "--limits", "stroke"],
        {
            "--clavel": Arg(Flag()),
            "--gamma-max": Arg(Real(sign="positive"), names=("gamma",), context=CLAVEL),
            "--ab-min": Arg(Real(), names=("ab_min", "ab-min"), context=CLAVEL),
            "--rays": Arg(Count(), names=("rays",), context=CLAVEL),
            "--kind": Arg(Choice(("translation", "orientation", "dextrous")), names=("kind",)),
            "--rpy": Arg(Vector(3), names=("rpy",)),
            "--bounds": Arg(Vector(6), names=("bounds",)),
            "--step": Arg(Real(sign="positive"), names=("step",)),
            "--samples": Arg(Count(minimum=2), names=("samples",)),
            "--limits": Arg(Names(), names=("limits",)),
            "--margin": Arg(
                Real(sign="non_negative"), names=("margin",), context=("--limits", "interference")
            ),
            "--method": Arg(Choice(("auto", "closed", "numeric")), names=("method",)),
            "--center": Arg(Vector(3), names=("center",), context=ORIENTATION),
            "--vector": Arg(Vector(3), names=("vector", "N"), context=ORIENTATION),
            "--x1": Arg(Vector(3), names=("x1", "X1"), context=ORIENTATION),
            "--x2": Arg(Vector(3), names=("x2", "X2"), context=ORIENTATION),
            "--n1": Arg(Count(), names=("n1",), context=ORIENTATION),
            "--n2": Arg(Count(), names=("n2",), context=ORIENTATION),
            "--mel": Arg(Flag()),
            "--joint-limits": Arg(Flag()),
            "--plot": Arg(PathOut(".png", onto=("robot.urdf",)), names=("plot", "figure")),
            "--json": Arg(Flag()),
        },
    ),
    _robot_cmd(
        ("stiffness",),
        "delta",
        "la",
        ["--pose", "0", "0", "-0.4", "--actuator-stiffness", "2e4"],
        {
            "--actuator-stiffness": Arg(
                Vector((1, 3), inf_ok=True), names=("actuator-stiffness", "actuator_stiffness")
            ),
            "--material": Arg(Choice(("steel", "aluminium", "carbon")), names=("material",)),
            "--rigid-links": Arg(Flag()),
            "--point": Arg(Vector(3), names=("point",)),
            "--wrench": Arg(Vector((3, 6)), names=("wrench",)),
            "--loaded": Arg(Flag()),
            **_map_options(),
            **_worker_options(GENERAL_MAP),
        },
        posed=True,
    ),
    _robot_cmd(
        ("modes",),
        "delta",
        "la",
        ["--pose", "0", "0", "-0.4", "--actuator-stiffness", "2e4", "--top", "3"],
        {
            "--actuator-stiffness": Arg(
                Vector((1, 3), inf_ok=True), names=("actuator-stiffness", "actuator_stiffness")
            ),
            "--material": Arg(Choice(("steel", "aluminium", "carbon")), names=("material",)),
            "--rigid-links": Arg(Flag()),
            "--point": Arg(Vector(3), names=("point",)),
            "--top": Arg(Count(), names=("top", "count")),
            "--gravity": Arg(Flag()),
            "--html": Arg(PathOut(".html", onto=("robot.urdf",)), names=("html",)),
            "--mode": Arg(Count(), names=("mode",), context=("--html", "{out.html}")),
            **_map_options(),
            **_worker_options(GENERAL_MAP),
        },
        posed=True,
    ),
    Cli(
        ("design",),
        [
            "delta",
            "--range",
            "la=0.2:0.3",
            "--metric",
            "moving_mass",
            "--n",
            "4",
            "--workers",
            "1",
        ],  # fmt: skip
        {
            "family": Arg(Choice(), names=("family", "delt", "no_such")),
            "--study": Arg(PathIn(key="study.yaml", fmt="yaml"), names=("study",)),
            "--plugin": Arg(PathIn(key="plugin.py", fmt="py"), names=("plugin",)),
            "--save-study": Arg(
                PathOut(".yaml", onto=("study.yaml", "plugin.py")),
                names=("save-study", "save_study"),
            ),
            "--range": Arg(RangeSpec(), names=("range", "la")),
            "--param": Arg(Mapping({"lb": 0.4}), names=("param", "fix", "lb", "no_such_key")),
            "--parametrisation": Arg(Choice(), names=("parametrisation",)),
            "--metric": Arg(Names(), names=("metric",)),
            "--constraint": Arg(Names(), names=("constraint",)),
            "--minimize": Arg(Names(), names=("minimize", "objective", "metric")),
            "--maximize": Arg(Names(), names=("maximize", "objective", "metric")),
            "--require": Arg(Choice(), names=("require",)),
            "--samples": Arg(Count(minimum=2), names=("samples", "require"), context=REQUIRE),
            "--trajectory": Arg(
                Choice(("adept", "sine", "p2p")), names=("trajectory",), context=SIZING
            ),
            "--payload": Arg(Real(sign="non_negative"), names=("payload",), context=SIZING),
            "--cycle-time": Arg(Real(sign="positive"), names=("cycle",), context=SIZING),
            "--depth": Arg(Real(sign="non_negative"), names=("depth",), context=SIZING),
            "--dt": Arg(Real(sign="positive"), names=("dt",), context=SIZING),
            "--length": Arg(Real(sign="positive"), names=("length",), context=REQUIRE),
            "--actuator-stiffness": Arg(
                Vector((1, 3), inf_ok=True),
                names=("actuator-stiffness", "actuator_stiffness"),
                context=PRECISION,
            ),
            "--material": Arg(
                Choice(("steel", "aluminium", "carbon")), names=("material",), context=PRECISION
            ),
            "--n": Arg(Count(), names=("n",)),
            "--grid": Arg(Count(minimum=2), names=("grid",)),
            "--sampler": Arg(Choice(("lhs", "sobol", "random")), names=("sampler",)),
            "--optimize": Arg(Choice(("nsga2",)), names=("optimize",)),
            "--generations": Arg(Count(), names=("generations", "optimize"), context=NSGA2),
            "--population": Arg(Count(minimum=2), names=("population", "optimize"), context=NSGA2),
            "--seed": Arg(Count(minimum=0), names=("seed",)),
            "--workers": Arg(Count(), names=("workers",)),
            "--scheduler": Arg(Choice(), names=("scheduler",)),
            "--timeout": Arg(Real(sign="positive"), names=("timeout",)),
            "--out": Arg(PathOut(".csv", onto=("study.yaml", "plugin.py")), names=("out",)),
            "--no-resume": Arg(Flag()),
            "--plot": Arg(PathOut(".png", onto=("study.yaml",)), names=("plot", "figure")),
            "--urdf": Arg(PathOut(".urdf", onto=("study.yaml",)), names=("urdf",)),
            "--verify": Arg(Count(minimum=2), names=("verify", "require"), context=REQUIRE),
            "--clavel-chart": Arg(Flag()),
            "--json": Arg(Flag()),
            "--band": Arg(Real(sign="positive"), names=("band",), context=VIBRATION_METRIC),
            "--dwell": Arg(Real(sign="positive"), names=("dwell",), context=VIBRATION_METRIC),
            "--damping-ratio": Arg(
                Real(sign="non_negative"),  # (0: undamped, as in the API)
                names=("damping-ratio", "damping_ratio"),
                context=VIBRATION_METRIC,
            ),
        },
        robot="delta",
        inputs={"study.yaml": fx.study_yaml, "plugin.py": fx.plugin_py},
        timeout=30,
    ),
    _robot_cmd(
        ("view",),
        "five_bar",
        "l1",
        ["--qa", "1.2", "1.9", "--html", "{out.html}"],
        {
            "--trajectory": Arg(Names(), names=("trajectory",)),
            "--html": Arg(PathOut(".html", onto=("robot.urdf",)), names=("html",)),
            "--host": Arg(Opaque("the live viewer's address (tests/test_viewer.py)")),
            "--collision": Arg(Flag()),
            "--singular": Arg(Flag()),
            "--closest": Arg(Flag()),
            "--points": Arg(PathIn(key="points.txt", fmt="txt"), names=("points",)),
        },
        posed="pose qa readings",
        inputs={"points.txt": lambda: b"0 0 0.3\n0.1 0 0.3\n"},
    ),
    _robot_cmd(
        ("mjcf",),
        "five_bar",
        "l1",
        ["-o", "{out.xml}"],
        {
            "--out": Arg(PathOut(".xml", onto=("robot.urdf",)), names=("-o", "output")),
            "--step": Arg(Real(sign="positive"), names=("step", "timestep")),
            "--no-contacts": Arg(Flag()),
        },
    ),
    _robot_cmd(
        ("vibration",),
        "delta",
        "la",
        ["--actuator-stiffness", "2e4", "--dt", "0.004", "--dwell", "0.1"],
        {
            "--trajectory": Arg(
                PathIn(key="trajectory.csv"), names=("trajectory", "trajectory.csv", "t,x")
            ),
            "--cycle-time": Arg(Real(sign="positive"), names=("cycle", "cycle_time")),
            "--payload": Arg(Real(sign="non_negative"), names=("payload",)),
            "--actuator-stiffness": Arg(
                Vector((1, 3), inf_ok=True), names=("actuator-stiffness", "actuator_stiffness")
            ),
            "--damping-ratio": Arg(
                Real(sign="non_negative"), names=("damping-ratio", "damping_ratio")
            ),
            "--actuator-damping": Arg(
                Vector((1, 3)), names=("actuator-damping", "actuator_damping")
            ),
            "--feedforward": Arg(Choice(("none", "gravity", "rigid")), names=("feedforward",)),
            "--material": Arg(Choice(("steel", "aluminium", "carbon")), names=("material",)),
            "--rigid-links": Arg(Flag()),
            "--band": Arg(Real(sign="positive"), names=("band",)),
            "--dwell": Arg(Real(sign="positive"), names=("dwell",)),
            "--method": Arg(Choice(("modal", "multibody")), names=("method",)),
            "--shaper": Arg(Choice(("zv", "zvd")), names=("shaper",)),
            "--shaper-modes": Arg(
                Count(), names=("shaper-modes", "shaper_modes"), context=("--shaper", "zv")
            ),
            "--modes": Arg(Count(), names=("modes",)),
            "--poses": Arg(Count(minimum=2), names=("poses",)),
            "--point": Arg(Vector(3), names=("point",)),
            "--profile": Arg(Choice(("quintic", "jerk")), names=("profile",)),
            "--dt": Arg(Real(sign="positive"), names=("dt",)),
            "--csv": Arg(PathOut(".csv", onto=("robot.urdf", "trajectory.csv")), names=("csv",)),
            "--plot": Arg(PathOut(".png", onto=("robot.urdf",)), names=("plot", "figure")),
            "--html": Arg(PathOut(".html", onto=("robot.urdf",)), names=("html",)),
            "--scale": Arg(Real(sign="positive"), names=("scale",), context=("--html", "{v.html}")),
            "--slow": Arg(Real(sign="positive"), names=("slow",), context=("--html", "{v.html}")),
            "--json": Arg(Flag()),
        },
        inputs={"trajectory.csv": fx.trajectory_csv},
        timeout=60,
        slow=True,
    ),
    _robot_cmd(
        ("identify",),
        "five_bar",
        "l1",
        ["--measurements", "{data.csv}", "-o", "{out.urdf}"],
        {
            "--measurements": Arg(
                PathIn(key="data.csv"), names=("measurements", "data", "data.csv")
            ),
            "--out": Arg(
                PathOut(".urdf", onto=("robot.urdf", "data.csv", "other.csv")),
                names=("-o", "output"),
            ),
            "--parameters": Arg(Names(), names=("parameters", "group")),
            "--cutoff": Arg(
                Real(sign="positive"),
                names=("cutoff",),
                context=("--measurements", "{positions.csv}"),
            ),
            "--predict": Arg(PathIn(key="other.csv"), names=("predict", "other.csv")),
            "--csv": Arg(
                PathOut(".csv", onto=("robot.urdf", "data.csv", "other.csv")),
                names=("csv",),
                context=("--predict", "{other.csv}"),
            ),
            "--plot": Arg(PathOut(".png", onto=("robot.urdf", "data.csv")), names=("plot",)),
            "--json": Arg(Flag()),
        },
        inputs={
            "data.csv": fx.identification_csv,
            "other.csv": lambda: fx.identification_csv(9, 1.0),
            "positions.csv": fx.positions_csv,
        },
        timeout=30,
    ),
    Cli(
        ("tripod", "scenario"),
        ["--no-machining", "--cycles", "1", "--dt", "0.25"],
        {
            "--param": Arg(Mapping({"r_p": 0.3}), names=("param", "r_p", "no_such_key")),
            "--branches": Arg(Choice(("3", "4")), names=("branches",)),
            "--allocation": Arg(Choice(("norm", "max")), names=("allocation",)),
            "--cycles": Arg(Count(), names=("cycles",)),
            "--step": Arg(Vector(2), names=("step",)),
            "--lift": Arg(Real(sign="non_negative"), names=("lift",)),
            "--tilt": Arg(Real(), names=("tilt",)),
            "--swing-time": Arg(Real(sign="positive"), names=("swing",)),
            "--reconfiguration-time": Arg(Real(sign="positive"), names=("reconfiguration",)),
            "--dt": Arg(Real(sign="positive"), names=("dt",)),
            "--no-machining": Arg(Flag()),
            "--surface-radius": Arg(
                Real(sign="positive", inf_ok=True), names=("surface", "radius")
            ),
            "--stride": Arg(Count(), names=("stride",)),
            "--json": Arg(Flag()),
            "--plot": Arg(PathOut(".png"), names=("plot", "figure")),
            "--html": Arg(PathOut(".html"), names=("html",)),
        },
        robot="tripod",
        timeout=30,
    ),
    _robot_cmd(
        ("accuracy",),
        "delta",
        "la",
        ["--pose", "0", "0", "-0.4"],
        {
            "--map": Arg(Choice(("xy", "xz", "yz")), names=("map",)),
            "--resolution": Arg(Vector((1, 3)), names=("resolution",)),
            "--backlash": Arg(Vector((1, 3)), names=("backlash",)),
            "--tolerance": Arg(Vector((1, 2, 3)), names=("tolerance",)),
            "--model": Arg(Choice(("auto", "placements", "shortcuts", "family")), names=("model",)),
            "--distribution": Arg(
                Choice(("uniform", "normal")), names=("distribution",), context=MONTE_CARLO
            ),
            "--samples": Arg(Count(minimum=0), names=("samples",)),
            "--seed": Arg(Count(minimum=0), names=("seed",), context=MONTE_CARLO),
            "--top": Arg(Count(minimum=0), names=("top",)),
            "--center": Arg(Vector(3), names=("center",), context=MAP),
            "--extent": Arg(Real(sign="positive"), names=("extent",), context=MAP),
            "--grid": Arg(Count(minimum=2), names=("grid",), context=MAP),
            "--field": Arg(Choice(), names=("field",), context=MAP),
            "--plot": Arg(PathOut(".png", onto=("robot.urdf",)), names=("plot", "figure")),
            "--csv": Arg(PathOut(".csv", onto=("robot.urdf",)), names=("csv",), context=MAP),
            **_worker_options(MONTE_CARLO),
        },
        posed=True,
    ),
    _robot_cmd(
        ("calibrate",),
        "delta",
        "la",
        ["--measurements", "{measurements.csv}", "-o", "{out.urdf}"],
        {
            "--measurements": Arg(
                PathIn(key="measurements.csv"), names=("measurements", "measurements.csv")
            ),
            "--out": Arg(
                PathOut(".urdf", onto=("robot.urdf", "measurements.csv")), names=("-o", "output")
            ),
            "--model": Arg(Choice(("auto", "placements", "shortcuts", "family")), names=("model",)),
            "--gains": Arg(Flag()),
            "--noise": Arg(Vector((1, 2)), names=("noise",)),
            "--holdout": Arg(Real(sign="non_negative"), names=("holdout",)),
            "--robust": Arg(Choice(("huber", "cauchy", "none")), names=("robust",)),
            "--implicit": Arg(Choice(("point", "plane")), names=("implicit", "group")),
            "--seed": Arg(Count(minimum=0), names=("seed",)),
            "--json": Arg(Flag()),
            "--validation": Arg(
                PathIn(key="measurements.csv"), names=("validation", "measurements.csv")
            ),
            "--tolerance": Arg(Vector((1, 2, 3)), names=("tolerance",)),
            "--residual-limit": Arg(Real(sign="positive"), names=("residual",)),
            "--correction-limit": Arg(Real(sign="positive"), names=("correction",)),
            "--accept": Arg(Flag()),
            "--plot": Arg(
                PathOut(".png", onto=("robot.urdf", "measurements.csv")), names=("plot",)
            ),
        },
        inputs={"measurements.csv": fx.calibration_csv},
        timeout=30,
    ),
]


# --------------------------------------------------------------------------------------------
# the API

from contract.registry_api import API, EXEMPT  # noqa: E402
