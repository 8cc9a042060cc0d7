"""The public API in the registry: every function, class and method with the kind of each
argument and a valid baseline call (see :mod:`contract.registry`)."""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

import pkdyn
import pkdyn.calibration
import pkdyn.design
import pkdyn.precision
import pkdyn.tripod
import pkdyn.viewer
from contract import fixtures as fx
from contract.entries import Api, Exempt
from contract.kinds import (
    Arg,
    Callback,
    Choice,
    Count,
    Flag,
    Lazy,
    Mapping,
    Matrix,
    Names,
    Obj,
    PathIn,
    PathOut,
    Pose,
    Real,
    RobotArg,
    Scratch,
    Text,
    Vector,
)

__all__ = ["API", "EXEMPT"]


# --------------------------------------------------------------------------------------------
# shared arguments


def ROBOT(*names: str) -> Arg:
    """The entry's robot."""
    return Arg(RobotArg(), Lazy(lambda s: s.robot), names=names or ("robot", "Robot"))


def Q(name: str = "q", pose: tuple[float, ...] | None = None, optional: bool = False) -> Arg:
    """A configuration (nq,) of the entry's robot: home, or at a platform pose."""
    return Arg(
        Vector("nq", optional=optional),
        Lazy(lambda s: fx.q_at(s.robot.name, pose) if pose else s.robot.q_home.copy()),
        names=(name, "configuration"),
    )


def QA(name: str = "qa") -> Arg:
    """Actuator coordinates (n_a,) of the entry's robot at home."""
    return Arg(
        Vector("n_a"),
        Lazy(lambda s: s.robot.q_home[s.robot.actuated_q].copy()),
        names=(name, "actuat"),
    )


def V(name: str = "v") -> Arg:
    """A velocity (nv,), zero."""
    return Arg(Vector("nv"), Lazy(lambda s: np.zeros(s.robot.nv)), names=(name, "velocit"))


def PROGRESS() -> Arg:
    """A progress-bar switch (``None``: automatic)."""
    return Arg(Flag(optional=True), False, names=("progress",))


DELTA_POSE = (0.0, 0.0, -0.4)


@functools.cache
def _ankle_map() -> Any:
    return pkdyn.actuation_map(fx.robot("parallel_ankle"), ["ankle_pitch", "ankle_roll"])


@functools.cache
def _ankle_samples() -> Any:
    return _ankle_map().from_joints([[0.1, 0.0], [0.0, 0.1]])


@functools.cache
def _elastic() -> Any:
    from pkdyn.precision import elastic_model

    return elastic_model(fx.robot("delta"), 2e4)


@functools.cache
def _elastic_geo() -> Any:
    from pkdyn.precision import elastic_model

    return elastic_model(fx.robot("five_bar", True), 2e4)


@functools.cache
def _modes_geo() -> Any:
    from pkdyn.precision import modes

    return modes(_elastic_geo(), fx.robot("five_bar", True).q_home)


@functools.cache
def _modes() -> Any:
    from pkdyn.precision import modes

    return modes(_elastic(), fx.q_at("delta", DELTA_POSE))


@functools.cache
def _study() -> Any:
    from pkdyn.design import Study

    return Study("delta", {"la": (0.2, 0.3)}, metrics=["moving_mass"], n=4)


@functools.cache
def _study_result() -> Any:
    from pkdyn.design import run_study

    return run_study(_study(), workers=1, progress=False)


def _id_measurements(key: str = "data") -> Any:
    from pkdyn.identification import read_measurements

    @functools.cache
    def read() -> Any:
        import tempfile
        from pathlib import Path

        with tempfile.TemporaryDirectory() as d:
            p = Path(d) / "data.csv"
            p.write_bytes(fx.identification_csv())
            return read_measurements(p, fx.robot("five_bar").actuator_names)

    return read()


@functools.cache
def _identified() -> Any:
    from pkdyn.identification import identify

    return identify(fx.robot("five_bar"), _id_measurements(), progress=False)


@functools.cache
def _cal_measurements() -> Any:
    import tempfile
    from pathlib import Path

    from pkdyn.calibration import read_csv

    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "m.csv"
        p.write_bytes(fx.calibration_csv())
        return read_csv(p, fx.robot("delta"))


@functools.cache
def _translation_ws() -> Any:
    from pkdyn.workspace import translation_workspace

    return translation_workspace(fx.robot("delta"), samples=5, limits=("stroke",), progress=False)


@functools.cache
def _orientation_ws() -> Any:
    from pkdyn.workspace import orientation_workspace

    return orientation_workspace(
        fx.robot("gough_stewart"), n1=6, n2=12, limits=("stroke",), progress=False
    )


@functools.cache
def _precision_map() -> Any:
    from pkdyn.precision import precision_map

    return precision_map(fx.robot("five_bar"), samples=3, actuator_stiffness=2e4, progress=False)


@functools.cache
def _accuracy_map() -> Any:
    from pkdyn.precision.accuracy import accuracy_map, slice_grid

    r = fx.robot("five_bar")
    P, shape = slice_grid(r.platform_placement(r.q_home).translation, "xy", 0.02, 3)
    return accuracy_map(r, P, resolution=1e-4, shape=shape, progress=False)


@functools.cache
def _conditioning_map() -> Any:
    from pkdyn.analysis.maps import delta_map

    u = np.linspace(-0.1, 0.1, 4)
    return delta_map(fx.robot("delta").params, u, u, -0.4)


@functools.cache
def _vibration(geometry: bool = False) -> Any:
    import warnings

    from pkdyn.precision import vibration

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return vibration(
            fx.robot("delta", geometry), "adept", actuator_stiffness=2e4, dt=0.004, dwell=0.1
        )


@functools.cache
def _delta_model() -> Any:
    from pkdyn.precision.parameters import parameter_model

    return parameter_model(fx.robot("delta"), "auto")


@functools.cache
def _geometric() -> Any:
    from pkdyn.precision import geometric_errors

    return geometric_errors(fx.robot("delta"), fx.q_at("delta", DELTA_POSE), _delta_model(), 1e-5)


@functools.cache
def _calibrated() -> Any:
    from pkdyn.calibration import calibrate

    return calibrate(fx.robot("delta"), _cal_measurements(), noise=1e-5)


def _scene(s: Scratch) -> Any:
    from pkdyn.viewer import Scene

    return Scene(s.robot)


def _trajectory(s: Scratch) -> Any:
    from pkdyn.dynamics.trajectory import named_trajectory

    return named_trajectory(s.robot, "adept", dt=0.004)


@functools.cache
def _adept() -> Any:
    import warnings

    from pkdyn.dynamics.trajectory import named_trajectory

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return named_trajectory(fx.robot("delta"), "adept", dt=0.004)


def _W(s: Scratch) -> np.ndarray:
    return np.random.default_rng(0).standard_normal((12, 4))


def _ex(reason: str, *names: str, methods: bool = False) -> list[Exempt]:
    return [Exempt(n, reason, methods) for n in names]


OWN_NAMES = {"unknown": "a parametrisation declares its own variables (empty names refused)"}
TITLE = {"wrong_type": "shown as str(title)"}
STORED = {
    c: "stored, called per design: evaluate_design reports its failures"
    for c in ("raises", "exits", "returns_garbage")
}
UNRESOLVED = "the metric is resolved by the study (Study: an unknown name is refused there)"
NO_ROBOT = "measurements know no robot: calibrate checks the widths and names against it"
RECORD = "a result record built by pkdyn (its fields are outputs, not user input)"
VIEW = "a view of a result built by pkdyn: no argument"
INTERNAL = (
    "robot-agnostic solver internals (pin models, data, index arrays): pkdyn's entry points "
    "validate what they pass; driven through them"
)

EXEMPT: list[Exempt] = [
    *_ex(RECORD, "pkdyn.GeometryResult", "pkdyn.analysis.CollisionReport",
         "pkdyn.analysis.KinematicModels", "pkdyn.analysis.MobilityResult",
         "pkdyn.analysis.SingularityReport", "pkdyn.analysis.StaticsResult",
         "pkdyn.analysis.MapSamples", "pkdyn.calibration.CalibrationResult",
         "pkdyn.calibration.ErrorStats", "pkdyn.calibration.Identifiability",
         "pkdyn.design.StudyResult", "pkdyn.dynamics.EffortTrajectory",
         "pkdyn.identification.IdentificationResult", "pkdyn.precision.ElasticModel",
         "pkdyn.precision.LinkCompliance", "pkdyn.precision.Modes", "pkdyn.precision.PoseFigures",
         "pkdyn.precision.PrecisionMap", "pkdyn.precision.Principal", "pkdyn.precision.Stiffness",
         "pkdyn.workspace.ClavelFigures", "pkdyn.workspace.OrientationWorkspace",
         "pkdyn.workspace.TranslationWorkspace", "pkdyn.cli.Command", "pkdyn.library.Family",
         "pkdyn.tripod.Lock", "pkdyn.design.DesignContext"),
    *_ex("built by pkdyn.load / load_string (driven through them)", "pkdyn.Robot"),
    *_ex(VIEW, "pkdyn.Robot.components", "pkdyn.Robot.constraint_data",
         "pkdyn.analysis.CollisionReport.as_json", "pkdyn.analysis.MobilityResult.as_json",
         "pkdyn.analysis.SingularityReport.to_json", "pkdyn.analysis.StaticsResult.to_json",
         "pkdyn.calibration.CalibrationResult.perturbed",
         "pkdyn.calibration.CalibrationResult.as_dict", "pkdyn.calibration.ErrorStats.as_dict",
         "pkdyn.calibration.Identifiability.as_dict", "pkdyn.calibration.Measurements.check_groups",
         "pkdyn.design.Conditions.as_dict", "pkdyn.design.DesignContext.requirement",
         "pkdyn.design.DesignContext.required", "pkdyn.design.DesignContext.duty",
         "pkdyn.design.DesignContext.translation", "pkdyn.design.DesignContext.clavel",
         "pkdyn.design.DesignContext.clavel_numeric", "pkdyn.design.DesignContext.gci",
         "pkdyn.design.DesignSpace.as_dict", "pkdyn.design.Objective.sign",
         "pkdyn.design.Requirement.as_dict", "pkdyn.design.Requirement.describe",
         "pkdyn.design.Study.designs", "pkdyn.design.Study.as_dict", "pkdyn.design.Study.to_yaml",
         "pkdyn.design.Study.digest", "pkdyn.design.StudyResult.objective_matrix",
         "pkdyn.design.StudyResult.pareto", "pkdyn.design.StudyResult.best",
         "pkdyn.design.StudyResult.counts", "pkdyn.design.StudyResult.as_json",
         "pkdyn.design.StudyResult.study_file",
         "pkdyn.identification.IdentificationResult.robot_identified",
         "pkdyn.identification.IdentificationResult.urdf",
         "pkdyn.identification.IdentificationResult.payload",
         "pkdyn.identification.IdentificationResult.drives",
         "pkdyn.identification.IdentificationResult.as_json",
         "pkdyn.precision.ElasticModel.spring_stiffness", "pkdyn.precision.Stiffness.to_json",
         "pkdyn.tripod.Mode.lock_targets", "pkdyn.tripod.Stance.centroid",
         "pkdyn.viewer.OfflineWindow.commands", "pkdyn.viewer.OfflineWindow.get_scene",
         "pkdyn.viewer.OfflineWindow.connect_zmq", "pkdyn.viewer.OfflineWindow.open",
         "pkdyn.viewer.OfflineWindow.close", "pkdyn.viewer.Scene.clear_highlights",
         "pkdyn.viewer.Scene.html", "pkdyn.viewer.Scene.close",
         "pkdyn.workspace.ClavelFigures.dimensionless", "pkdyn.workspace.ClavelFigures.as_json",
         "pkdyn.workspace.OrientationWorkspace.full_circles",
         "pkdyn.workspace.OrientationWorkspace.allowed_fraction",
         "pkdyn.workspace.OrientationWorkspace.bounds",
         "pkdyn.workspace.OrientationWorkspace.tilt_max",
         "pkdyn.workspace.OrientationWorkspace.as_json",
         "pkdyn.workspace.TranslationWorkspace.boundary_mask",
         "pkdyn.workspace.TranslationWorkspace.boundary",
         "pkdyn.workspace.TranslationWorkspace.as_json", "pkdyn.library.Family.make_params",
         "pkdyn.library.Family.build_urdf", "pkdyn.library.Family.home",
         "pkdyn.library.Family.forward_position", "pkdyn.library.Family.configuration",
         "pkdyn.library.Family.inverse_actuators", "pkdyn.library.Family.layout",
         "pkdyn.calibration.CalibrationResult.provenance",
         "pkdyn.precision.VibrationResult.animation"),
    *_ex(VIEW, *[f"{c}.{m}" for c in (
        "pkdyn.GeometryResult", "pkdyn.analysis.CollisionReport", "pkdyn.analysis.KinematicModels",
        "pkdyn.analysis.MapSamples", "pkdyn.analysis.MobilityResult",
        "pkdyn.calibration.CalibrationResult", "pkdyn.calibration.ErrorStats",
        "pkdyn.calibration.Identifiability", "pkdyn.design.StudyResult",
        "pkdyn.dynamics.EffortTrajectory", "pkdyn.identification.IdentificationResult",
        "pkdyn.precision.Accuracy", "pkdyn.precision.ActuatorAccuracy",
        "pkdyn.precision.GeometricAccuracy", "pkdyn.precision.GridMap",
        "pkdyn.precision.MonteCarlo", "pkdyn.precision.PoseFigures",
        "pkdyn.precision.ToleranceRanking", "pkdyn.precision.Validity",
        "pkdyn.precision.VibrationResult", "pkdyn.workspace.ClavelFigures",
        "pkdyn.workspace.OrientationWorkspace", "pkdyn.workspace.TranslationWorkspace",
    ) for m in ("table", "to_json")
      if (c, m) not in {("pkdyn.analysis.CollisionReport", "table"),
                        ("pkdyn.design.StudyResult", "table"),
                        ("pkdyn.identification.IdentificationResult", "table"),
                        ("pkdyn.calibration.ErrorStats", "table")}
      and not (c.endswith(("ErrorStats", "Validity")) and m == "table")],
      "pkdyn.analysis.SingularityReport.table", "pkdyn.analysis.StaticsResult.table",
      "pkdyn.precision.Stiffness.table", "pkdyn.calibration.ErrorStats.table",
      "pkdyn.calibration.Identifiability.formulas",
      "pkdyn.calibration.Identifiability.indices_line",
      "pkdyn.precision.ActuatorAccuracy.headline", "pkdyn.precision.GeometricAccuracy.headline",
      "pkdyn.precision.GridMap.counts", "pkdyn.precision.Validity.lines",
      "pkdyn.precision.PlaneGrid.positions"),
    *_ex(RECORD, "pkdyn.precision.Accuracy", "pkdyn.precision.AccuracyMap",
         "pkdyn.precision.ActuatorAccuracy", "pkdyn.precision.GeometricAccuracy",
         "pkdyn.precision.GridMap", "pkdyn.precision.MonteCarlo", "pkdyn.precision.PlaneGrid",
         "pkdyn.precision.ToleranceRanking", "pkdyn.precision.Validity",
         "pkdyn.precision.VibrationResult"),
    *_ex(INTERNAL, "solvers.Closure", "solvers.LinearCoupling", methods=True),
    *_ex("the command line itself: driven by test_contract_cli.py", "pkdyn.cli.main",
         "pkdyn.cli.run", "pkdyn.cli.commands"),
    *_ex("the viewer's message sink (meshcat's protocol), no user input",
         "pkdyn.viewer.OfflineWindow", "pkdyn.viewer.OfflineWindow.send"),
    *_ex(INTERNAL, "solvers.Actuation", "solvers.ClosureSet", "solvers.Drives",
         "solvers.ForwardResult", "solvers.FramePoseTask", "solvers.FrameSpring",
         "solvers.InverseDynamics", "solvers.InverseResult", "solvers.InverseTrajectory",
         "solvers.JointCoupling", "solvers.PassiveForces", "solvers.SampledKinematics",
         "solvers.SolveResult", "solvers.solve_lm", "solvers.ForwardDynamics.passive_forces",
         "solvers.ForwardDynamics.closure_forces",
         "solvers.ForwardDynamics.acceleration", methods=True),
    *_ex(INTERNAL + " (its public boundary is pkdyn.dynamics.ForwardDynamics, driven)",
         "solvers.ForwardDynamics", "solvers.ForwardDynamics.simulate",
         "solvers.ForwardDynamics.project_state", "solvers.ForwardDynamics.step",
         "solvers.ForwardDynamics.reference_rank", "solvers.simulate"),
]  # fmt: skip


def _fd(s: Scratch) -> Any:
    from pkdyn.dynamics import ForwardDynamics

    return ForwardDynamics(s.robot, "euler")


ROBOT_R = ROBOT()
POSED_Q = Q("q", DELTA_POSE)

API: list[Api] = [
    # ---- pkdyn: loading, geometric models
    Api(
        "pkdyn.load",
        {
            "name_or_path": Arg(
                PathIn(key="robot.urdf", fmt="urdf"),
                Lazy(lambda s: s.inputs["robot.urdf"]),
                names=("name_or_path", "robot", "robot.urdf", ".urdf", "variant"),
            ),
            "geometry": Arg(Flag(), False, names=("geometry",)),
            "home": Arg(Vector((2, 4), optional=True), None, names=("home",)),
            "tol": Arg(Real(sign="positive"), 1e-4, names=("tol",)),
            "sidecar": Arg(PathIn(key="sidecar.yaml", fmt="yaml", optional=True), None,
                           names=("sidecar",)),
            "package_dirs": Arg(Names(optional=True, empty_ok=True), None, names=("package_dirs",)),
            "xacro_args": Arg(Mapping({"x": "1"}, optional=True), None, names=("xacro",)),
        },
        robot="five_bar",
        inputs={"robot.urdf": lambda: fx.urdf_text("five_bar"),
                "sidecar.yaml": lambda: b"name_mot: [proximal1, proximal2]\n"},
    ),
    Api(
        "pkdyn.load_string",
        {
            "xml": Arg(Text(), Lazy(lambda s: fx.urdf_text("five_bar").decode()), names=("xml",)),
            "source": Arg(Text(), "five_bar.urdf", names=("source",)),
            "geometry": Arg(Flag(), False, names=("geometry",)),
            "home": Arg(Vector((2, 4), optional=True), None, names=("home",)),
            "tol": Arg(Real(sign="positive"), 1e-4, names=("tol",)),
        },
        robot="five_bar",
    ),
    Api(
        "pkdyn.forward_geometry",
        {"robot": ROBOT_R, "qa": QA(), "q_init": Q("q_init", optional=True),
         "tol": Arg(Real(sign="positive"), 1e-12, names=("tol",)),
         "check_limits": Arg(Flag(), True, names=("check_limits",)),
         "keep_mode": Arg(Flag(), True, names=("keep_mode",))},
    ),
    Api(
        "pkdyn.inverse_geometry",
        {"robot": ROBOT_R,
         "pose": Arg(Pose(), list(DELTA_POSE), names=("pose", "reach", "components")),
         "q_init": Q("q_init", optional=True),
         "tol": Arg(Real(sign="positive"), 1e-12, names=("tol",)),
         "check_limits": Arg(Flag(), True, names=("check_limits",))},
    ),
    Api("pkdyn.project", {"robot": ROBOT_R, "q": Q(),
                          "tol": Arg(Real(sign="positive"), 1e-12, names=("tol",))}),
    Api("pkdyn.closure_residual", {"robot": ROBOT_R, "q": Q()}),
    Api(
        "pkdyn.assembly_modes",
        {"robot": ROBOT_R, "qa": QA(), "starts": Arg(Count(), 4, names=("starts",)),
         "seed": Arg(Count(minimum=0), 0, names=("seed",)),
         "spread": Arg(Real(sign="positive"), 1.5, names=("spread",))},
        robot="five_bar",
    ),
    Api("pkdyn.Robot.dof", {"q": Q(optional=True),
                            "tol": Arg(Real(sign="positive"), 1e-9, names=("tol",))},
        obj=lambda s: s.robot),
    Api("pkdyn.Robot.mobility", {"q": Q(optional=True),
                                 "tol": Arg(Real(sign="positive"), 1e-9, names=("tol",))},
        obj=lambda s: s.robot),
    Api("pkdyn.Robot.closure_tolerance",
        {"rtol": Arg(Real(sign="positive"), 1e-10, names=("rtol",))}, obj=lambda s: s.robot),
    Api("pkdyn.Robot.mobility_split", {"q": Q(optional=True),
                                       "tol": Arg(Real(sign="positive"), 1e-9, names=("tol",))},
        obj=lambda s: s.robot),
    Api("pkdyn.Robot.platform_placement", {"q": Q()}, obj=lambda s: s.robot),
    # ---- actuation maps of legs
    Api(
        "pkdyn.actuation_map",
        {"robot": ROBOT_R,
         "joints": Arg(Names(), ["ankle_pitch", "ankle_roll"], names=("joints", "joint")),
         "actuators": Arg(Names("actuators", optional=True), None, names=("actuators", "actuator")),
         "q_ref": Q("q_ref", optional=True)},
        robot="parallel_ankle",
    ),
    Api(
        "pkdyn.ActuationMap",
        {"robot": ROBOT_R,
         "joints": Arg(Names(), ["ankle_pitch", "ankle_roll"], names=("joints", "joint")),
         "actuators": Arg(Names("actuators", optional=True), None, names=("actuators", "actuator")),
         "q_ref": Q("q_ref", optional=True)},
        robot="parallel_ankle",
    ),
    Api(
        "pkdyn.ActuationMap.from_joints",
        {"qj": Arg(Matrix(2, 2), [[0.1, 0.0], [0.0, 0.1]], names=("qj", "joint")),
         "q_init": Q("q_init", optional=True),
         "strict": Arg(Flag(), True, names=("strict",))},
        robot="parallel_ankle", obj=lambda s: _ankle_map(),
    ),
    Api(
        "pkdyn.ActuationMap.from_actuators",
        {"qa": Arg(Matrix(1, 2), Lazy(lambda s: [s.robot.q_home[s.robot.actuated_q]]),
                   names=("qa", "actuat")),
         "q_init": Q("q_init", optional=True),
         "strict": Arg(Flag(), True, names=("strict",))},
        robot="parallel_ankle", obj=lambda s: _ankle_map(),
    ),
    Api("pkdyn.analysis.MapSamples.actuator_torques",
        {"tau_joint": Arg(Vector(2), [1.0, 0.5], names=("tau_joint",))},
        robot="parallel_ankle", obj=lambda s: _ankle_samples()),
    Api("pkdyn.analysis.MapSamples.joint_torques",
        {"tau_act": Arg(Vector(2), [1.0, 0.5], names=("tau_act",))},
        robot="parallel_ankle", obj=lambda s: _ankle_samples()),
    # ---- analysis
    Api("pkdyn.analysis.classify",
        {"robot": ROBOT_R, "q": POSED_Q,
         "tol": Arg(Real(sign="positive"), 1e-7, names=("tol",)),
         "near_tol": Arg(Real(sign="positive"), 1e-4, names=("near_tol",)),
         "near_serial_tol": Arg(Real(sign="positive"), 1e-2, names=("near_serial_tol",))}),
    Api("pkdyn.analysis.distance_report",
        {"robot": ROBOT_R, "q": POSED_Q,
         "margin": Arg(Real(sign="non_negative"), 0.0, names=("margin",)),
         "pairs": Arg(Names(optional=True), None, names=("pairs", "pair"))},
        geometry=True),
    Api("pkdyn.analysis.kinematic_models", {"robot": ROBOT_R, "q": POSED_Q}),
    Api("pkdyn.analysis.platform_jacobian", {"robot": ROBOT_R, "q": POSED_Q}),
    Api("pkdyn.analysis.static_equilibrium",
        {"robot": ROBOT_R, "q": POSED_Q,
         "F": Arg(Vector((3, 6), optional=True), [0, 0, -5.0, 0, 0, 0], names=("F", "wrench")),
         "gravity": Arg(Flag(), False, names=("gravity",)),
         "passive": Arg(Flag(), True, names=("passive",))}),
    # ---- dynamics
    Api("pkdyn.dynamics.actuation", {"robot": ROBOT_R}),
    Api("pkdyn.dynamics.elastic_energy", {"robot": ROBOT_R, "q": Q()}),
    Api("pkdyn.dynamics.mechanical_energy", {"robot": ROBOT_R, "q": Q(), "v": V()}),
    Api("pkdyn.dynamics.with_payload",
        {"robot": ROBOT_R, "mass": Arg(Real(sign="non_negative"), 0.5, names=("mass", "payload")),
         "offset": Arg(Vector(3), [0.0, 0.0, 0.0], names=("offset",)),
         "inertia": Arg(Vector(9, optional=True), None, names=("inertia",))}),
    Api("pkdyn.dynamics.simulate",
        {"robot": ROBOT_R, "duration": Arg(Real("s", sign="positive"), 0.02, names=("duration",)),
         "dt": Arg(Real("s", sign="positive"), 0.01, names=("dt",)),
         "q0": Q("q0", optional=True), "v0": Arg(Vector("nv", optional=True), None, names=("v0",)),
         "torque": Arg(Callback(optional=True), None, names=("torque",)),
         "viscous": Arg(Vector((1, 4)), 0.0, names=("viscous",)),
         "coulomb": Arg(Vector((1, 4)), 0.0, names=("coulomb",)),
         "integrator": Arg(Choice(("dopri5", "rk4", "euler")), "dopri5", names=("integrator",)),
         "record_every": Arg(Count(), 1, names=("record_every",)),
         "passive": Arg(Flag(), True, names=("passive",)),
         "step": Arg(Real("s", sign="positive", optional=True), None, names=("step",)),
         "motor_torque": Arg(Callback(optional=True), None, names=("motor_torque",))},
        robot="five_bar"),
    Api("pkdyn.dynamics.inverse_dynamics",
        {"robot": ROBOT_R,
         "trajectory": Arg(Obj("JointTrajectory"), Lazy(lambda s: _adept()),
                           names=("trajectory",)),
         "wrench": Arg(Vector(6, optional=True), None, names=("wrench",)),
         "limits": Arg(Flag(), False, names=("limits",)),
         "weights": Arg(Vector("n_a", optional=True), None, names=("weights",)),
         "progress": PROGRESS(),
         "passive": Arg(Flag(), True, names=("passive",)),
         "allocation": Arg(Choice(("norm", "max")), "norm", names=("allocation",))}),
    Api("pkdyn.dynamics.ForwardDynamics",
        {"robot": ROBOT_R,
         "integrator": Arg(Choice(("dopri5", "rk4", "euler")), "euler", names=("integrator",)),
         "passive": Arg(Flag(), True, names=("passive",)),
         "viscous": Arg(Vector((1, 4)), 0.0, names=("viscous",)),
         "coulomb": Arg(Vector((1, 4)), 0.0, names=("coulomb",)),
         "warn_events": Arg(Flag(), True, names=("warn_events",))},
        robot="five_bar"),
    Api("pkdyn.dynamics.ForwardDynamics.step",
        {"t": Arg(Real("s"), 0.0, names=("t",)), "q": Q(), "v": V(),
         "dt": Arg(Real("s", sign="positive"), 1e-3, names=("dt",)),
         "tau": Arg(Callback(optional=True), None, names=("tau",))},
        robot="five_bar", obj=_fd),
    Api("pkdyn.dynamics.ForwardDynamics.simulate",
        {"q0": Q("q0"), "v0": V("v0"),
         "duration": Arg(Real("s", sign="positive"), 0.01, names=("duration",)),
         "dt": Arg(Real("s", sign="positive"), 1e-3, names=("dt",)),
         "tau": Arg(Callback(optional=True), None, names=("tau",)),
         "record_every": Arg(Count(), 1, names=("record_every",)),
         "t0": Arg(Real("s"), 0.0, names=("t0",)),
         "step": Arg(Real("s", sign="positive", optional=True), None, names=("step",))},
        robot="five_bar", obj=_fd),
    Api("pkdyn.dynamics.ForwardDynamics.project_state",
        {"q": Q(), "v": V(), "tol": Arg(Real(sign="positive", optional=True), None,
                                        names=("tol",))},
        robot="five_bar", obj=_fd),
    # ---- calibration
    Api("pkdyn.calibration.Measurements",
        {"kind": Arg(Choice(("pose", "position", "point", "plane", "joints")), "position",
                     names=("kind",)),
         "qa": Arg(Matrix(3, "n_a"), Lazy(lambda s: _cal_measurements().qa[:3].copy()),
                   names=("qa",), skip={"wrong_size": NO_ROBOT}),
         "position": Arg(Matrix(3, 3, optional=True),
                         Lazy(lambda s: _cal_measurements().position[:3].copy()),
                         names=("position",)),
         "rpy": Arg(Matrix(3, 3, optional=True), None, names=("rpy",)),
         "group": Arg(Vector(3, optional=True), None, names=("group",)),
         "joints": Arg(Names(optional=True, empty_ok=True), (), names=("joints",),
                       skip={"unknown": NO_ROBOT})}),
    Api("pkdyn.calibration.Measurements.subset",
        {"idx": Arg(Vector(None, empty_ok=True), [0, 1, 2], names=("idx", "index"))},
        obj=lambda s: _cal_measurements()),
    Api("pkdyn.calibration.Measurements.from_placements",
        {"qa": Arg(Matrix(2, "n_a"), Lazy(lambda s: _cal_measurements().qa[:2].copy()),
                   names=("qa",), skip={"wrong_size": NO_ROBOT}),
         "placements": Arg(Obj("pin.SE3 list"), Lazy(lambda s: [
             pkdyn.forward_geometry(s.robot, q, check_limits=False).placement
             for q in _cal_measurements().qa[:2]]), names=("placements",)),
         "kind": Arg(Choice(("pose", "position")), "position", names=("kind",))},
        call=lambda s, **kw: pkdyn.calibration.Measurements.from_placements(**kw)),
    Api("pkdyn.calibration.calibrate",
        {"robot": ROBOT_R,
         "measurements": Arg(Obj("Measurements"), Lazy(lambda s: _cal_measurements()),
                             names=("measurements",)),
         "model": Arg(Choice(("auto", "placements", "shortcuts", "family")), "auto",
                      names=("model",)),
         "noise": Arg(Real("m", sign="positive", optional=True), 1e-5, names=("noise",)),
         "holdout": Arg(Real(sign="non_negative"), 0.2, names=("holdout",)),
         "robust": Arg(Choice(("huber", "cauchy", "none")), "huber", names=("robust",)),
         "rtol": Arg(Real(sign="positive"), 1e-7, names=("rtol",)),
         "gains": Arg(Flag(), False, names=("gains",)),
         "max_iter": Arg(Count(), 30, names=("max_iter",)),
         "seed": Arg(Count(minimum=0), 0, names=("seed",))},
        timeout=30, nan_ok=True),
    Api("pkdyn.calibration.identifiability",
        {"W": Arg(Matrix(12, 4), Lazy(_W), names=("W",)),
         "names": Arg(Names(), ["a", "b", "c", "d"], names=("names",)),
         "poses": Arg(Count(), 4, names=("poses",)),
         "scale": Arg(Vector(4, optional=True), None, names=("scale",)),
         "rtol": Arg(Real(sign="positive"), 1e-7, names=("rtol",))},
        robot=None),
    Api("pkdyn.calibration.Identifiability.combination",
        {"j": Arg(Count(minimum=0), 0, names=("j",)),
         "tol": Arg(Real(sign="positive"), 1e-6, names=("tol",)),
         "top": Arg(Count(), 6, names=("top",))},
        robot=None,
        obj=lambda s: pkdyn.calibration.identifiability(_W(s), ["a", "b", "c", "d"], 4)),
    Api("pkdyn.calibration.observability",
        {"s": Arg(Vector(None, empty_ok=True), [3.0, 2.0, 1.0], names=("s", "singular")),
         "poses": Arg(Count(), 4, names=("poses",))},
        robot=None),
    Api("pkdyn.calibration.read_csv",
        {"path": Arg(PathIn(key="measurements.csv"), Lazy(lambda s: s.inputs["measurements.csv"]),
                     names=("path", "measurements")),
         "robot": ROBOT_R,
         "kind": Arg(Choice(("pose", "position", "point", "plane", "joints"), optional=True),
                     None, names=("kind",))},
        inputs={"measurements.csv": fx.calibration_csv}),
    Api("pkdyn.calibration.write_csv",
        # (it reads no file: the measurements are given)
        {"path": Arg(PathOut(".csv"), Lazy(lambda s: s.dir / "out.csv"), names=("path",)),
         "robot": ROBOT_R,
         "m": Arg(Obj("Measurements"), Lazy(lambda s: _cal_measurements()), names=("m",))}),
    # ---- identification
    Api("pkdyn.identification.Measurements",
        {"t": Arg(Vector(None), Lazy(lambda s: _id_measurements().t[:50].copy()), names=("t",)),
         "qa": Arg(Matrix(50, "n_a"), Lazy(lambda s: _id_measurements().qa[:50].copy()),
                   names=("qa", "tau")),
         "qa_dot": Arg(Matrix(50, "n_a", optional=True), None, names=("qa_dot",)),
         "qa_ddot": Arg(Matrix(50, "n_a", optional=True), None, names=("qa_ddot",)),
         "tau": Arg(Matrix(50, "n_a", optional=True),
                    Lazy(lambda s: _id_measurements().tau[:50].copy()), names=("tau",)),
         "source": Arg(Text(), "data", names=("source",))},
        robot="five_bar"),
    Api("pkdyn.identification.identify",
        {"robot": ROBOT_R,
         "measurements": Arg(Obj("Measurements"), Lazy(lambda s: _id_measurements()),
                             names=("measurements",)),
         "parameters": Arg(Names(optional=True), None, names=("parameters", "group")),
         "cutoff": Arg(Real("Hz", sign="positive", optional=True), None, names=("cutoff",)),
         "progress": PROGRESS(),
         "workers": Arg(Count(optional=True), None, names=("workers",))},
        robot="five_bar", timeout=30),
    Api("pkdyn.identification.parameter_set",
        {"robot": ROBOT_R, "groups": Arg(Names(optional=True), None, names=("groups", "group"))},
        robot="five_bar"),
    Api("pkdyn.identification.predict_efforts",
        {"robot": ROBOT_R,
         "ps": Arg(Obj("ParameterSet"), Lazy(lambda s: _identified().parameters), names=("ps",)),
         "theta": Arg(Vector(None), Lazy(lambda s: _identified().parameters.nominal.copy()),
                      names=("theta",)),
         "t": Arg(Vector(20), Lazy(lambda s: _id_measurements().t[:20].copy()), names=("t",)),
         "qa": Arg(Matrix(20, "n_a"), Lazy(lambda s: _id_measurements().qa[:20].copy()),
                   names=("qa",)),
         "qa_dot": Arg(Matrix(20, "n_a"), Lazy(lambda s: _id_measurements().qa_dot[:20].copy()),
                       names=("qa_dot",)),
         "qa_ddot": Arg(Matrix(20, "n_a"), Lazy(lambda s: _id_measurements().qa_ddot[:20].copy()),
                        names=("qa_ddot",))},
        robot="five_bar"),
    Api("pkdyn.identification.read_measurements",
        {"path": Arg(PathIn(key="data.csv"), Lazy(lambda s: s.inputs["data.csv"]),
                     names=("path", "data")),
         "actuators": Arg(Names(), Lazy(lambda s: list(s.robot.actuator_names)),
                          names=("actuators", "qa_", "tau_")),
         "need_tau": Arg(Flag(), True, names=("need_tau",))},
        robot="five_bar", inputs={"data.csv": fx.identification_csv}),
    Api("pkdyn.identification.IdentificationResult.predict",
        {"t": Arg(Vector(20), Lazy(lambda s: _id_measurements().t[:20].copy()), names=("t",)),
         "qa": Arg(Matrix(20, "n_a"), Lazy(lambda s: _id_measurements().qa[:20].copy()),
                   names=("qa",)),
         "qa_dot": Arg(Matrix(20, "n_a"), Lazy(lambda s: _id_measurements().qa_dot[:20].copy()),
                       names=("qa_dot",)),
         "qa_ddot": Arg(Matrix(20, "n_a"), Lazy(lambda s: _id_measurements().qa_ddot[:20].copy()),
                        names=("qa_ddot",))},
        robot="five_bar", obj=lambda s: _identified()),
    Api("pkdyn.identification.IdentificationResult.table",
        {"limit": Arg(Count(), 40, names=("limit",))}, robot="five_bar",
        obj=lambda s: _identified()),
    Api("pkdyn.identification.IdentificationResult.write_urdf",
        {"path": Arg(PathOut(".urdf"), Lazy(lambda s: s.dir / "out.urdf"), names=("path",))},
        robot="five_bar", obj=lambda s: _identified()),  # (it reads no file)
    # ---- library
    Api("pkdyn.library.family", {"name": Arg(Choice(), "delta", names=("name", "family", "robot"))},
        robot=None),
    # ---- plotting
    Api("pkdyn.plotting.plot_modes",
        {"result": Arg(Obj("Modes"), Lazy(lambda s: _modes()), names=("result",)),
         "path": Arg(PathOut(".png", optional=True), Lazy(lambda s: s.dir / "m.png"),
                     names=("path", "figure")),
         "title": Arg(Text(optional=True), None, names=("title",), skip=TITLE),
         "length": Arg(Real("m", sign="positive"), 0.1, names=("length",))},
        timeout=30),
    Api("pkdyn.plotting.plot_precision_map",
        {"pmap": Arg(Obj("PrecisionMap"), Lazy(lambda s: _precision_map()), names=("pmap",)),
         "field": Arg(Choice(), "stiffness_min", names=("field",)),
         "path": Arg(PathOut(".png", optional=True), Lazy(lambda s: s.dir / "m.png"),
                     names=("path", "figure")),
         "title": Arg(Text(optional=True), None, names=("title",), skip=TITLE),
         "reference": Arg(Real(sign="positive", optional=True), None, names=("reference",))},
        robot="five_bar", timeout=30),
    Api("pkdyn.plotting.plot_accuracy_map",
        {"amap": Arg(Obj("AccuracyMap"), Lazy(lambda s: _accuracy_map()), names=("amap",)),
         "field": Arg(Choice(), "actuator_worst", names=("field",)),
         "path": Arg(PathOut(".png", optional=True), Lazy(lambda s: s.dir / "m.png"),
                     names=("path", "figure")),
         "title": Arg(Text(optional=True), None, names=("title",), skip=TITLE)},
        robot="five_bar", timeout=30),
    Api("pkdyn.plotting.plot_conditioning_map",
        {"cmap": Arg(Obj("ConditioningMap"), Lazy(lambda s: _conditioning_map()),
                     names=("cmap",)),
         "field": Arg(Choice(), "lci", names=("field",)),
         "path": Arg(PathOut(".png", optional=True), Lazy(lambda s: s.dir / "m.png"),
                     names=("path", "figure")),
         "title": Arg(Text(optional=True), None, names=("title",), skip=TITLE),
         "singular_loci": Arg(Flag(), True, names=("singular_loci",))},
        robot="delta", timeout=30),
    # ---- precision
    Api("pkdyn.precision.Material",
        {"name": Arg(Text(), "alloy", names=("name",)),
         "E": Arg(Real("Pa", sign="positive"), 7e10, names=("E",)),
         "G": Arg(Real("Pa", sign="positive"), 2.6e10, names=("G",)),
         "density": Arg(Real("kg/m^3", sign="positive"), 2700.0, names=("density",))},
        robot=None),
    Api("pkdyn.precision.Section",
        {"radius": Arg(Real("m", sign="positive"), 0.01, names=("radius",)),
         "inner_radius": Arg(Real("m", sign="non_negative"), 0.005, names=("inner_radius",))},
        robot=None),
    Api("pkdyn.precision.Section.shear_coefficient",
        {"poisson": Arg(Real(optional=True), 0.3, names=("poisson",))}, robot=None,
        obj=lambda s: pkdyn.precision.Section(0.01)),
    Api("pkdyn.precision.Section.mass",
        {"length": Arg(Real("m", sign="positive"), 0.3, names=("length",)),
         "material": Arg(Obj("Material"), Lazy(lambda s: pkdyn.precision.STEEL),
                         names=("material",))},
        robot=None, obj=lambda s: pkdyn.precision.Section(0.01)),
    Api("pkdyn.precision.as_material",
        {"value": Arg(Choice(("steel", "aluminium", "carbon")), "steel",
                      names=("value", "material"))}, robot=None),
    Api("pkdyn.precision.tip_compliance",
        {"length": Arg(Real("m", sign="positive"), 0.3, names=("length",)),
         "section": Arg(Obj("Section"), Lazy(lambda s: pkdyn.precision.Section(0.01)),
                        names=("section",)),
         "material": Arg(Obj("Material"), Lazy(lambda s: pkdyn.precision.STEEL),
                         names=("material",)),
         "shear": Arg(Flag(), True, names=("shear",))}, robot=None),
    Api("pkdyn.precision.centre_compliance",
        {"length": Arg(Real("m", sign="positive"), 0.3, names=("length",)),
         "section": Arg(Obj("Section"), Lazy(lambda s: pkdyn.precision.Section(0.01)),
                        names=("section",)),
         "material": Arg(Obj("Material"), Lazy(lambda s: pkdyn.precision.STEEL),
                         names=("material",)),
         "shear": Arg(Flag(), True, names=("shear",))}, robot=None),
    Api("pkdyn.precision.transport",
        {"K": Arg(Matrix(6, 6), Lazy(lambda s: np.eye(6)), names=("K",)),
         "r": Arg(Vector(3), [0.0, 0.0, 0.1], names=("r",))}, robot=None),
    Api("pkdyn.precision.actuator_stiffness",
        {"robot": ROBOT_R,
         "value": Arg(Vector((1, 3), inf_ok=True), 2e4, names=("value", "actuator_stiffness"))}),
    Api("pkdyn.precision.link_compliances",
        {"robot": ROBOT_R,
         "material": Arg(Choice(("steel", "aluminium", "carbon"), optional=True), "steel",
                         names=("material",)),
         "shear": Arg(Flag(), True, names=("shear",))}, geometry=True),
    Api("pkdyn.precision.elastic_model",
        {"robot": ROBOT_R,
         "actuator_stiffness": Arg(Vector((1, 3), inf_ok=True), 2e4,
                                   names=("actuator_stiffness",)),
         "material": Arg(Choice(("steel", "aluminium", "carbon"), optional=True), None,
                         names=("material",)),
         "links": Arg(Flag(), True, names=("links",)),
         "shear": Arg(Flag(), True, names=("shear",))}),
    Api("pkdyn.precision.ElasticModel.embed", {"q": Q()}, obj=lambda s: _elastic()),
    Api("pkdyn.precision.ElasticModel.restrict", {"q": Q()}, obj=lambda s: _elastic()),
    Api("pkdyn.precision.stiffness",
        {"robot": ROBOT_R, "q": POSED_Q,
         "actuator_stiffness": Arg(Vector((1, 3), inf_ok=True), 2e4,
                                   names=("actuator_stiffness",)),
         "material": Arg(Choice(("steel", "aluminium", "carbon"), optional=True), None,
                         names=("material",)),
         "links": Arg(Flag(), True, names=("links",)),
         "point": Arg(Vector(3, optional=True), None, names=("point",)),
         "wrench": Arg(Vector((3, 6), optional=True), None, names=("wrench",)),
         "loaded": Arg(Flag(), False, names=("loaded",)),
         "gravity": Arg(Flag(), False, names=("gravity",))}),
    Api("pkdyn.precision.stiffness_json",
        {"robot": ROBOT_R, "q": POSED_Q,
         "actuator_stiffness": Arg(Vector((1, 3), inf_ok=True), 2e4,
                                   names=("actuator_stiffness",))}),
    Api("pkdyn.precision.modes",
        {"robot": ROBOT_R, "q": POSED_Q,
         "actuator_stiffness": Arg(Vector((1, 3), inf_ok=True), 2e4,
                                   names=("actuator_stiffness",)),
         "material": Arg(Choice(("steel", "aluminium", "carbon"), optional=True), None,
                         names=("material",)),
         "links": Arg(Flag(), True, names=("links",)),
         "point": Arg(Vector(3, optional=True), None, names=("point",)),
         "gravity": Arg(Flag(), False, names=("gravity",))}),
    Api("pkdyn.precision.Modes.to_json", {"top": Arg(Count(optional=True), 3, names=("top",))},
        obj=lambda s: _modes()),
    Api("pkdyn.precision.mode_trajectory",
        {"em": Arg(Obj("ElasticModel"), Lazy(lambda s: _elastic()), names=("em",)),
         "result": Arg(Obj("Modes"), Lazy(lambda s: _modes()), names=("result",)),
         "index": Arg(Count(minimum=0), 0, names=("index", "mode")),
         "amplitude": Arg(Real(sign="positive", optional=True), None, names=("amplitude",)),
         "period": Arg(Real("s", sign="positive"), 2.0, names=("period",)),
         "cycles": Arg(Count(), 2, names=("cycles",)),
         "samples": Arg(Count(minimum=2), 12, names=("samples",))}),
    Api("pkdyn.precision.pose_figures",
        {"robot": ROBOT_R,
         "P": Arg(Matrix(2, 3), [[0.0, 0.0, -0.4], [0.02, 0.0, -0.4]], names=("P",)),
         "actuator_stiffness": Arg(Vector((1, 3), inf_ok=True), 2e4,
                                   names=("actuator_stiffness",)),
         "frequency": Arg(Flag(), False, names=("frequency",)),
         "method": Arg(Choice(("auto", "closed", "numeric")), "auto", names=("method",)),
         "progress": PROGRESS()},
        nan_ok=True),  # (NaN: a figure not asked for, or at an invalid pose; see ``valid``)
    Api("pkdyn.precision.precision_map",
        {"robot": ROBOT_R,
         "plane": Arg(Choice(("xy", "xz", "yz")), "xy", names=("plane",)),
         "value": Arg(Real("m", optional=True), None, names=("value",)),
         "samples": Arg(Count(minimum=2), 3, names=("samples",)),
         "bounds": Arg(Vector(4, optional=True), None, names=("bounds",)),
         "rpy": Arg(Vector(3), [0.0, 0.0, 0.0], names=("rpy",)),
         "actuator_stiffness": Arg(Vector((1, 2), inf_ok=True), 2e4,
                                   names=("actuator_stiffness",)),
         "limits": Arg(Names(empty_ok=True), ["stroke", "joint"], names=("limits",)),
         "method": Arg(Choice(("auto", "closed", "numeric")), "auto", names=("method",)),
         "progress": PROGRESS()},
        robot="five_bar", nan_ok=True),  # (NaN where not ``reachable``)
    Api("pkdyn.precision.PrecisionMap.extreme",
        {"name": Arg(Choice(), "stiffness_min", names=("name",))}, robot="five_bar",
        obj=lambda s: _precision_map()),
    # ---- workspace
    Api("pkdyn.workspace.translation_workspace",
        {"robot": ROBOT_R, "rpy": Arg(Vector(3), [0.0, 0.0, 0.0], names=("rpy",)),
         "bounds": Arg(Matrix(3, 2, optional=True), None, names=("bounds",)),
         "step": Arg(Real("m", sign="positive", optional=True), None, names=("step",)),
         "samples": Arg(Count(minimum=2), 5, names=("samples",)),
         "limits": Arg(Names(empty_ok=True), ["stroke"], names=("limits",)),
         "margin": Arg(Real("m", sign="non_negative"), 0.0, names=("margin",)),
         "method": Arg(Choice(("auto", "closed", "numeric")), "auto", names=("method",)),
         "progress": PROGRESS()}),
    Api("pkdyn.workspace.dextrous_workspace",
        {"robot": ROBOT_R, "bounds": Arg(Matrix(3, 2, optional=True), None, names=("bounds",)),
         "step": Arg(Real("m", sign="positive", optional=True), None, names=("step",)),
         "samples": Arg(Count(minimum=2), 3, names=("samples",)),
         "joint_limits": Arg(Flag(), False, names=("joint_limits",)),
         "progress": PROGRESS()},
        robot="gough_stewart", timeout=30),
    Api("pkdyn.workspace.orientation_workspace",
        {"robot": ROBOT_R, "center": Arg(Vector(3, optional=True), None, names=("center",)),
         "N": Arg(Vector(3), [0.0, 0.0, 1.0], names=("N",)),
         "X1": Arg(Vector(3), [1.0, 0.0, 0.0], names=("X1",)),
         "X2": Arg(Vector(3), [0.0, 0.0, 1.0], names=("X2",)),
         "rpy0": Arg(Vector(3), [0.0, 0.0, 0.0], names=("rpy0",)),
         "n1": Arg(Count(minimum=2), 6, names=("n1",)),
         "n2": Arg(Count(minimum=2), 12, names=("n2",)),
         "limits": Arg(Names(empty_ok=True), ["stroke"], names=("limits",)),
         "margin": Arg(Real("m", sign="non_negative"), 0.0, names=("margin",)),
         "tol": Arg(Real(sign="positive"), 1e-10, names=("tol",)),
         "progress": PROGRESS()},
        robot="gough_stewart"),
    Api("pkdyn.workspace.mel_study",
        {"robot": ROBOT_R, "center": Arg(Vector(3, optional=True), None, names=("center",)),
         "N": Arg(Vector(3), [0.0, 0.0, 1.0], names=("N",)),
         "n1": Arg(Count(minimum=2), 4, names=("n1",)),
         "n2": Arg(Count(minimum=2), 8, names=("n2",)),
         "progress": PROGRESS()},
        robot="gough_stewart", geometry=True, timeout=30),
    Api("pkdyn.workspace.clavel_closed_form",
        {"g": Arg(Obj("DeltaGeometry"), Lazy(lambda s: s.robot.params), names=("g",)),
         "gamma_max": Arg(Real("rad", sign="positive"), 0.7, names=("gamma_max",)),
         "ab_min": Arg(Real("rad"), 0.5, names=("ab_min",))}),
    Api("pkdyn.workspace.clavel_numeric",
        {"g": Arg(Obj("DeltaGeometry"), Lazy(lambda s: s.robot.params), names=("g",)),
         "gamma_max": Arg(Real("rad", sign="positive"), 0.7, names=("gamma_max",)),
         "ab_min": Arg(Real("rad"), 0.5, names=("ab_min",)),
         "rays": Arg(Count(minimum=3), 12, names=("rays",)),
         "fractions": Arg(Count(minimum=2), 5, names=("fractions",)),
         "heights": Arg(Count(minimum=2), 20, names=("heights",)),
         "tol": Arg(Real(sign="positive"), 1e-8, names=("tol",)),
         "refine": Arg(Flag(), True, names=("refine",)),
         "progress": PROGRESS()}),
    Api("pkdyn.workspace.TranslationWorkspace.points",
        {"mask": Arg(Obj("bool array", optional=True), None, names=("mask",))},
        obj=lambda s: _translation_ws()),
    Api("pkdyn.workspace.TranslationWorkspace.slice",
        {"axis": Arg(Choice(("x", "y", "z")), "z", names=("axis",)),
         "value": Arg(Real("m"), -0.4, names=("value",))},
        obj=lambda s: _translation_ws()),
    Api("pkdyn.workspace.OrientationWorkspace.direction",
        {"theta1": Arg(Vector(2), [0.1, 0.2], names=("theta1",)),
         "theta2": Arg(Vector(2), [0.0, 1.0], names=("theta2",))},
        robot="gough_stewart", obj=lambda s: _orientation_ws()),
    Api("pkdyn.workspace.OrientationWorkspace.jacobian",
        {"theta1": Arg(Vector(2), [0.1, 0.2], names=("theta1",)),
         "theta2": Arg(Vector(2), [0.0, 1.0], names=("theta2",))},
        robot="gough_stewart", obj=lambda s: _orientation_ws()),
    Api("pkdyn.workspace.OrientationWorkspace.solid_angle",
        {"half": Arg(Count(minimum=0, optional=True), 0, names=("half",))},
        robot="gough_stewart", obj=lambda s: _orientation_ws()),
    Api("pkdyn.workspace.OrientationWorkspace.arc_points",
        {"per_radian": Arg(Count(), 10, names=("per_radian",))},
        robot="gough_stewart", obj=lambda s: _orientation_ws()),
    # ---- tripod
    Api("pkdyn.tripod.branch_numbers", {"source": Arg(Count(), 3, names=("source", "branch"))},
        robot=None),
    Api("pkdyn.tripod.support_branches",
        {"branch": Arg(Count(), 1, names=("branch",)),
         "branches": Arg(Choice((3, 4)), 3, names=("branches",))}, robot=None),
    Api("pkdyn.tripod.locked_names",
        {"branch": Arg(Count(), 1, names=("branch",)),
         "branches": Arg(Choice((3, 4)), 3, names=("branches",))}, robot=None),
    Api("pkdyn.tripod.pp_mode", {}, robot=None),
    Api("pkdyn.tripod.be_mode",
        {"robot": ROBOT_R, "q": Q(), "branch": Arg(Count(), 1, names=("branch",)),
         "values": Arg(Vector(6, optional=True), None, names=("values",))},
        robot="tripod"),
    Api("pkdyn.tripod.foot_placement",
        {"robot": ROBOT_R, "q": Q(), "branch": Arg(Count(), 1, names=("branch",))},
        robot="tripod"),
    Api("pkdyn.tripod.foot_frame",
        {"foothold": Arg(Obj("pin.SE3"), Lazy(lambda s: __import__("pinocchio").SE3.Identity()),
                         names=("foothold",))}, robot=None),
    Api("pkdyn.tripod.lock_values",
        {"model": Arg(Obj("pin.Model"), Lazy(lambda s: s.robot.model), names=("model",)),
         "q": Q(), "joint": Arg(Choice(), Lazy(lambda s: pkdyn.tripod.be_mode(
             s.robot, s.robot.q_home, 1).locks[1].joint), names=("joint", "lock")),
         "coordinates": Arg(Vector(None), [0], names=("coordinates",))},
        robot="tripod"),
    Api("pkdyn.tripod.lock_constraint",
        {"model": Arg(Obj("pin.Model"), Lazy(lambda s: s.robot.model), names=("model",)),
         "lock": Arg(Obj("Lock"), Lazy(lambda s: pkdyn.tripod.be_mode(
             s.robot, s.robot.q_home, 1).locks[0]), names=("lock",)),
         "q": Q(optional=True), "arm": Arg(Real("m", sign="positive"), 0.1, names=("arm",))},
        robot="tripod"),
    Api("pkdyn.tripod.mode_robot",
        {"robot": ROBOT_R,
         "stance": Arg(Obj("Stance"), Lazy(lambda s: pkdyn.tripod.Stance.default(s.robot.params)),
                       names=("stance",)),
         "mode": Arg(Obj("Mode"), Lazy(lambda s: pkdyn.tripod.pp_mode()), names=("mode",)),
         "q": Q(optional=True)},
        robot="tripod"),
    Api("pkdyn.tripod.Mode",
        {"kind": Arg(Choice(("PP", "BE")), "PP", names=("kind",)),
         "branch": Arg(Count(optional=True), None, names=("branch",))}, robot=None),
    Api("pkdyn.tripod.Mode.lock_vector", {"robot": ROBOT_R, "q": Q()}, robot="tripod",
        obj=lambda s: pkdyn.tripod.be_mode(s.robot, s.robot.q_home, 1)),
    Api("pkdyn.tripod.Stance",
        {"footholds": Arg(Obj("pin.SE3 tuple"), Lazy(lambda s: pkdyn.tripod.Stance.default(
            s.robot.params).footholds), names=("footholds", "stance"))}, robot="tripod"),
    Api("pkdyn.tripod.Stance.default",
        {"p": Arg(Obj("tripod.Params"), Lazy(lambda s: s.robot.params), names=("p",))},
        robot="tripod", call=lambda s, **kw: pkdyn.tripod.Stance.default(**kw)),
    Api("pkdyn.tripod.Stance.moved",
        {"branch": Arg(Count(), 1, names=("branch",)),
         "foothold": Arg(Obj("pin.SE3"), Lazy(lambda s: __import__("pinocchio").SE3.Identity()),
                         names=("foothold",))},
        robot="tripod", obj=lambda s: pkdyn.tripod.Stance.default(s.robot.params)),
    # ---- viewer (offline: nothing served)
    Api("pkdyn.viewer.Scene",
        {"robot": ROBOT_R, "q": Q(optional=True),
         "collision": Arg(Flag(), False, names=("collision",)),
         "frames": Arg(Names(optional=True, empty_ok=True), None, names=("frames",)),
         "serve": Arg(Flag(), False, names=("serve",))},
        robot="five_bar", geometry=True),
    Api("pkdyn.viewer.Scene.nodes", {"name": Arg(Text(), "proximal1_0", names=("name",))},
        robot="five_bar", geometry=True, obj=_scene),
    Api("pkdyn.viewer.Scene.robot_box", {"q": Q(optional=True)}, robot="five_bar",
        geometry=True, obj=_scene),
    Api("pkdyn.viewer.Scene.set_background",
        {"top": Arg(Vector((3, 4)), [1.0, 1.0, 1.0], names=("top", "colo")),
         "bottom": Arg(Vector((3, 4)), [0.5, 0.5, 0.5], names=("bottom", "colo"))},
        robot="five_bar", geometry=True, obj=_scene),
    Api("pkdyn.viewer.Scene.look_at",
        {"camera": Arg(Obj("Camera"), Lazy(lambda s: pkdyn.viewer.frame_box(
            np.zeros(3), np.ones(3))), names=("camera",))},
        robot="five_bar", geometry=True, obj=_scene),
    Api("pkdyn.viewer.Scene.frame",
        {"direction": Arg(Vector(3, optional=True), None, names=("direction",)),
         "aspect": Arg(Real(sign="positive"), 4 / 3, names=("aspect",))},
        robot="five_bar", geometry=True, obj=_scene),
    Api("pkdyn.viewer.Scene.display", {"q": Q()}, robot="five_bar", geometry=True, obj=_scene),
    Api("pkdyn.viewer.Scene.add_points",
        {"name": Arg(Text(), "cloud", names=("name",)),
         "points": Arg(Matrix(4, 3), Lazy(lambda s: np.zeros((4, 3))), names=("points",)),
         "color": Arg(Vector((3, 4)), [0.1, 0.6, 0.3], names=("color", "colo")),
         "size": Arg(Real("m", sign="positive"), 0.005, names=("size",))},
        robot="five_bar", geometry=True, obj=_scene),
    Api("pkdyn.viewer.Scene.add_mesh",
        {"name": Arg(Text(), "mesh", names=("name",)),
         "vertices": Arg(Matrix(3, 3), Lazy(lambda s: np.eye(3)), names=("vertices",)),
         "faces": Arg(Matrix(1, 3), [[0, 1, 2]], names=("faces",)),
         "color": Arg(Vector((3, 4)), [0.2, 0.5, 0.9, 0.35], names=("color", "colo")),
         "wireframe": Arg(Flag(), False, names=("wireframe",))},
        robot="five_bar", geometry=True, obj=_scene),
    Api("pkdyn.viewer.Scene.highlight",
        {"names": Arg(Names(), ["proximal1_0"], names=("names", "name", "geometry")),
         "color": Arg(Vector((3, 4)), [0.85, 0.0, 0.85], names=("color", "colo"))},
        robot="five_bar", geometry=True, obj=_scene),
    Api("pkdyn.viewer.Scene.highlight_singular", {"q": Q(optional=True)}, robot="five_bar",
        geometry=True, obj=_scene),
    Api("pkdyn.viewer.Scene.highlight_closest", {"q": Q(optional=True)}, robot="five_bar",
        geometry=True, obj=_scene),
    Api("pkdyn.viewer.Scene.animate",
        {"t": Arg(Vector(3), [0.0, 0.1, 0.2], names=("t",)),
         "Q": Arg(Matrix(3, "nq"), Lazy(lambda s: np.tile(s.robot.q_home, (3, 1))), names=("Q",)),
         "max_rate": Arg(Real("Hz", sign="positive"), 60.0, names=("max_rate",)),
         "loop": Arg(Flag(), True, names=("loop",)), "progress": PROGRESS()},
        robot="five_bar", geometry=True, obj=_scene),
    Api("pkdyn.viewer.Scene.save_html",
        {"path": Arg(PathOut(".html"), Lazy(lambda s: s.dir / "scene.html"), names=("path",))},
        robot="five_bar", geometry=True, obj=_scene),
    Api("pkdyn.viewer.export_html",
        {"scene": Arg(Obj("Scene"), Lazy(_scene), names=("scene",)),
         "path": Arg(PathOut(".html"), Lazy(lambda s: s.dir / "scene.html"), names=("path",))},
        robot="five_bar", geometry=True),
    Api("pkdyn.viewer.animate",
        {"robot": ROBOT_R, "t": Arg(Vector(3), [0.0, 0.1, 0.2], names=("t",)),
         "Q": Arg(Matrix(3, "nq"), Lazy(lambda s: np.tile(s.robot.q_home, (3, 1))), names=("Q",)),
         "singular": Arg(Flag(), False, names=("singular",)),
         "closest": Arg(Flag(), False, names=("closest",)),
         "collision": Arg(Flag(), False, names=("collision",))},
        robot="five_bar", geometry=True),
    Api("pkdyn.viewer.animate_mode",
        {"model": Arg(Obj("ElasticModel"), Lazy(lambda s: _elastic_geo()), names=("model", "em")),
         "result": Arg(Obj("Modes"), Lazy(lambda s: _modes_geo()), names=("result",)),
         "index": Arg(Count(minimum=0), 0, names=("index", "mode")),
         "amplitude": Arg(Real(sign="positive", optional=True), None, names=("amplitude",)),
         "period": Arg(Real("s", sign="positive"), 2.0, names=("period",)),
         "cycles": Arg(Count(), 1, names=("cycles",))},
        robot="five_bar", geometry=True, timeout=30),
    Api("pkdyn.viewer.bounding_box",
        {"model": Arg(Obj("pin.Model"), Lazy(lambda s: s.robot.model), names=("model",)),
         "geometry_model": Arg(Obj("pin.GeometryModel"), Lazy(lambda s: s.robot.visual_model),
                               names=("geometry_model",)),
         "q": Q()}, robot="five_bar", geometry=True),
    Api("pkdyn.viewer.chain",
        {"segments": Arg(Obj("(t, Q) segments"), Lazy(lambda s: [
            (np.array([0.0, 0.1]), np.zeros((2, 3))), (np.array([0.0, 0.1]), np.zeros((2, 3)))]),
            names=("segments",)),
         "pause": Arg(Real("s", sign="non_negative"), 0.5, names=("pause",))}, robot=None),
    Api("pkdyn.viewer.closest_pair", {"robot": ROBOT_R, "q": Q()}, robot="five_bar",
        geometry=True),
    Api("pkdyn.viewer.frame_box",
        {"lo": Arg(Vector(3), [0.0, 0.0, 0.0], names=("lo",)),
         "hi": Arg(Vector(3), [1.0, 1.0, 1.0], names=("hi",)),
         "direction": Arg(Vector(3, optional=True), None, names=("direction",)),
         "margin": Arg(Real(sign="positive"), 1.15, names=("margin",)),
         "aspect": Arg(Real(sign="positive"), 4 / 3, names=("aspect",))}, robot=None),
    Api("pkdyn.viewer.project",
        {"camera": Arg(Obj("Camera"), Lazy(lambda s: pkdyn.viewer.frame_box(
            np.zeros(3), np.ones(3))), names=("camera",)),
         "points": Arg(Matrix(2, 3), [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]], names=("points",)),
         "width": Arg(Count(), 640, names=("width",)),
         "height": Arg(Count(), 480, names=("height",))}, robot=None),
    Api("pkdyn.viewer.Camera",
        {"target": Arg(Vector(3), [0.0, 0.0, 0.0], names=("target",)),
         "position": Arg(Vector(3), [1.0, 1.0, 1.0], names=("position",)),
         "fov_deg": Arg(Real("deg", sign="positive"), 75.0, names=("fov_deg", "fov"))},
        robot=None),
    Api("pkdyn.viewer.singularity_labels",
        {"robot": ROBOT_R,
         "Q": Arg(Matrix(2, "nq"), Lazy(lambda s: np.tile(s.robot.q_home, (2, 1))), names=("Q",)),
         "progress": PROGRESS()}, robot="five_bar"),
    Api("pkdyn.viewer.static_html",
        {"commands": Arg(Obj("bytes list"), [b"\x00"], names=("commands",)),
         "title": Arg(Text(), "pkdyn viewer", names=("title",))}, robot=None),
    # ---- design studies
    Api("pkdyn.design.Range",
        {"name": Arg(Text(), "la", names=("name",)),
         "low": Arg(Real("m"), 0.2, names=("low", "range")),
         "high": Arg(Real("m"), 0.3, names=("high", "range"))}, robot=None),
    Api("pkdyn.design.Range.parse",
        {"text": Arg(Choice(), "la=0.2:0.3", names=("text", "range"))}, robot=None,
        call=lambda s, **kw: pkdyn.design.Range.parse(**kw)),
    Api("pkdyn.design.Range.at", {"u": Arg(Vector(None), [0.0, 0.5, 1.0], names=("u",))},
        robot=None, obj=lambda s: pkdyn.design.Range("la", 0.2, 0.3)),
    Api("pkdyn.design.Range.fraction", {"x": Arg(Vector(None), [0.2, 0.25], names=("x",))},
        robot=None, obj=lambda s: pkdyn.design.Range("la", 0.2, 0.3)),
    Api("pkdyn.design.Constraint",
        {"metric": Arg(Text(), "moving_mass", names=("metric",)),
         "op": Arg(Choice(("<=", ">=")), "<=", names=("op",)),
         "bound": Arg(Real(), 2.0, names=("bound",))}, robot=None),
    Api("pkdyn.design.Constraint.parse",
        {"text": Arg(Choice(), "moving_mass<=2", names=("text", "constraint"))}, robot=None,
        call=lambda s, **kw: pkdyn.design.Constraint.parse(**kw)),
    Api("pkdyn.design.Constraint.violation",
        {"value": Arg(Real(), 1.5, names=("value",),
                      skip={"non_finite": "documented: a metric that is not a number violates"})},
        robot=None, obj=lambda s: pkdyn.design.Constraint("moving_mass", "<=", 2.0)),
    Api("pkdyn.design.Objective",
        {"metric": Arg(Text(), "moving_mass", names=("metric",)),
         "sense": Arg(Choice(("min", "max")), "min", names=("sense",))}, robot=None),
    Api("pkdyn.design.Objective.parse",
        {"text": Arg(Choice(), "moving_mass", names=("text", "objective"),
                     skip={"unknown": UNRESOLVED})}, robot=None,
        call=lambda s, **kw: pkdyn.design.Objective.parse(**kw)),
    Api("pkdyn.design.Requirement",
        {"kind": Arg(Choice(("box", "cylinder", "orientation")), "box",
                     names=("kind", "requirement")),
         "size": Arg(Mapping({"dx": 0.05, "dy": 0.05, "dz": 0.05}),
                     {"dx": 0.05, "dy": 0.05, "dz": 0.05},
                     names=("size", "dx", "no_such_key", "requirement")),
         "center": Arg(Vector(3), (0.0, 0.0, -0.35), names=("center", "centre", "requirement")),
         "samples": Arg(Count(minimum=2), 3, names=("samples",))}, robot=None),
    Api("pkdyn.design.Requirement.parse",
        {"text": Arg(Choice(), "box:dx=0.05,dy=0.05,dz=0.05", names=("text", "require")),
         "samples": Arg(Count(minimum=2), 3, names=("samples",))}, robot=None,
        call=lambda s, **kw: pkdyn.design.Requirement.parse(**kw)),
    Api("pkdyn.design.Requirement.from_dict",
        {"data": Arg(Mapping({"kind": "box", "dx": 0.05, "dy": 0.05, "dz": 0.05}),
                     {"kind": "box", "dx": 0.05, "dy": 0.05, "dz": 0.05},
                     names=("requirement", "kind", "size", "no_such_key"))}, robot=None,
        call=lambda s, **kw: pkdyn.design.Requirement.from_dict(**kw)),
    Api("pkdyn.design.Requirement.count_at",
        {"samples": Arg(Count(minimum=2), 3, names=("samples",))}, robot=None,
        obj=lambda s: pkdyn.design.Requirement("box", {"dx": 0.05, "dy": 0.05, "dz": 0.05})),
    Api("pkdyn.design.Conditions",
        {"limits": Arg(Names(empty_ok=True), ("stroke", "joint"), names=("limits",)),
         "length": Arg(Real("m", sign="positive", optional=True), None, names=("length",)),
         "trajectory": Arg(Choice(("adept", "sine", "p2p")), "adept", names=("trajectory",)),
         "trajectory_options": Arg(Mapping({"cycle_time": 0.5}, optional=True), {},
                                   names=("trajectory_options", "cycle_time", "no_such_key",
                                          "trajectory")),
         "payload": Arg(Real("kg", sign="non_negative"), 0.0, names=("payload",)),
         "gamma_max": Arg(Real("rad", sign="positive"), 0.7, names=("gamma_max",)),
         "ab_min": Arg(Real("rad"), 0.5, names=("ab_min",)),
         "workspace_samples": Arg(Count(minimum=2), 5, names=("workspace_samples",)),
         "clavel_rays": Arg(Count(minimum=3), 12, names=("clavel_rays",)),
         "actuator_stiffness": Arg(Vector((1, 3), optional=True, inf_ok=True), None,
                                   names=("actuator_stiffness",),
                                   skip={"wrong_size": "conditions know no robot: the "
                                         "precision metrics check the count against it"}),
         "material": Arg(Choice(("steel", "aluminium", "carbon"), optional=True), None,
                         names=("material",))}, robot=None),
    Api("pkdyn.design.Conditions.from_dict",
        {"data": Arg(Mapping({"payload": 0.1}, optional=True), {"payload": 0.1},
                     names=("payload", "no_such_key", "conditions", "settings"))}, robot=None,
        call=lambda s, **kw: pkdyn.design.Conditions.from_dict(**kw)),
    Api("pkdyn.design.DesignSpace",
        {"family": Arg(Choice(), "delta", names=("family", "robot")),
         "ranges": Arg(Obj("Range tuple"), (pkdyn.design.Range("la", 0.2, 0.3),),
                       names=("ranges", "range")),
         "fixed": Arg(Mapping({"lb": 0.4}), {}, names=("fixed", "lb", "no_such_key")),
         "parametrisation": Arg(Choice(optional=True), None, names=("parametrisation",))},
        robot=None),
    Api("pkdyn.design.DesignSpace.values",
        {"u": Arg(Matrix(2, 1), [[0.0], [1.0]], names=("u",))}, robot=None,
        obj=lambda s: pkdyn.design.DesignSpace("delta", (pkdyn.design.Range("la", 0.2, 0.3),))),
    Api("pkdyn.design.DesignSpace.overrides", {"x": Arg(Vector(1), [0.25], names=("x",))},
        robot=None,
        obj=lambda s: pkdyn.design.DesignSpace("delta", (pkdyn.design.Range("la", 0.2, 0.3),))),
    Api("pkdyn.design.DesignSpace.params", {"x": Arg(Vector(1), [0.25], names=("x",))},
        robot=None,
        obj=lambda s: pkdyn.design.DesignSpace("delta", (pkdyn.design.Range("la", 0.2, 0.3),))),
    Api("pkdyn.design.DesignContext.cached",
        {"key": Arg(Text(), "k", names=("key",)),
         "compute": Arg(Callback(), lambda: 1.0, names=("compute", "cached"),
                        skip={"returns_garbage": "any value is a value to cache"})},
        obj=lambda s: pkdyn.design.DesignContext(s.robot, pkdyn.design.Conditions())),
    Api("pkdyn.design.Metric",
        {"name": Arg(Text(), "contract_metric", names=("name",)),
         "unit": Arg(Text(), "m", names=("unit",)),
         "fn": Arg(Callback(), lambda robot, ctx: 1.0, names=("fn",), skip=STORED),
         "summary": Arg(Text(), "", names=("summary",)),
         "geometry": Arg(Flag(), False, names=("geometry",))}, robot=None),
    Api("pkdyn.design.Parametrisation",
        {"name": Arg(Text(), "contract_param", names=("name",)),
         "inputs": Arg(Names(), ("s",), names=("inputs",), skip=OWN_NAMES),
         "fn": Arg(Callback(), lambda values, p: {"la": values["s"]}, names=("fn",),
                   skip=STORED),
         "summary": Arg(Text(), "", names=("summary",)),
         "optional": Arg(Names(empty_ok=True), (), names=("optional",), skip=OWN_NAMES)},
        robot=None),
    Api("pkdyn.design.metric",
        {"name": Arg(Text(), "contract_decorated", names=("name",)),
         "unit": Arg(Text(), "m", names=("unit",)),
         "summary": Arg(Text(), "", names=("summary",)),
         "geometry": Arg(Flag(), False, names=("geometry",))}, robot=None),
    Api("pkdyn.design.resolve_metrics",
        {"items": Arg(Names(empty_ok=True), ["moving_mass"], names=("items", "metric"))},
        robot=None),
    Api("pkdyn.design.load_plugin",
        {"name": Arg(PathIn(key="plugin.py", fmt="py"), Lazy(lambda s: str(s.inputs["plugin.py"])),
                     names=("plugin", "name"))},
        robot=None, inputs={"plugin.py": fx.plugin_py}),
    Api("pkdyn.design.Study",
        {"family": Arg(Choice(), "delta", names=("family", "robot")),
         "ranges": Arg(Mapping({"la": (0.2, 0.3)}), {"la": (0.2, 0.3)},
                       names=("ranges", "range", "la", "no_such_key")),
         "fixed": Arg(Mapping({"lb": 0.4}, optional=True), {},
                      names=("fixed", "lb", "no_such_key")),
         "metrics": Arg(Names(), ["moving_mass"], names=("metrics", "metric")),
         "constraints": Arg(Names(empty_ok=True), [], names=("constraints", "constraint")),
         "objectives": Arg(Names(empty_ok=True), [], names=("objectives", "objective", "metric")),
         "trajectory": Arg(Choice(("adept", "sine", "p2p")), "adept", names=("trajectory",)),
         "trajectory_options": Arg(Mapping({"cycle_time": 0.5}, optional=True), {},
                                   names=("trajectory_options", "cycle_time", "no_such_key")),
         "payload": Arg(Real("kg", sign="non_negative"), 0.0, names=("payload",)),
         "sampler": Arg(Choice(("lhs", "sobol", "random")), "lhs", names=("sampler",)),
         "n": Arg(Count(), 4, names=("n",)),
         "generations": Arg(Count(), 10, names=("generations",)),
         "seed": Arg(Count(minimum=0), 0, names=("seed",)),
         "parametrisation": Arg(Choice(optional=True), None, names=("parametrisation",)),
         "settings": Arg(Mapping({"workspace_samples": 5}, optional=True), {},
                         names=("settings", "workspace_samples", "no_such_key")),
         "name": Arg(Text(), "", names=("name",))}, robot=None),
    Api("pkdyn.design.Study.from_dict",
        {"data": Arg(Mapping({"family": "delta"}), Lazy(lambda s: dict(
            family="delta", ranges={"la": [0.2, 0.3]}, metrics=["moving_mass"], n=4)),
            names=("study", "family", "no_such_key")),
         "source": Arg(Text(), "study", names=("source",))}, robot=None,
        call=lambda s, **kw: pkdyn.design.Study.from_dict(**kw)),
    Api("pkdyn.design.Study.load",
        {"path": Arg(PathIn(key="study.yaml", fmt="yaml"), Lazy(lambda s: s.inputs["study.yaml"]),
                     names=("path", "study"))},
        robot=None, inputs={"study.yaml": fx.study_yaml},
        call=lambda s, **kw: pkdyn.design.Study.load(**kw)),
    Api("pkdyn.design.run_study",
        {"study": Arg(Obj("Study"), Lazy(lambda s: _study()), names=("study",)),
         "out": Arg(PathOut(".csv", optional=True, onto=("study.yaml",)),
                    Lazy(lambda s: s.dir / "out.csv"), names=("out",)),
         "workers": Arg(Count(optional=True), 1, names=("workers",)),
         "scheduler": Arg(Choice(optional=True), None, names=("scheduler",)),
         "resume": Arg(Flag(), True, names=("resume",)),
         "progress": PROGRESS(),
         "scheduler_timeout": Arg(Real("s", sign="positive"), 10.0, names=("timeout",))},
        robot=None, inputs={"study.yaml": fx.study_yaml}, timeout=30),
    Api("pkdyn.design.StudyResult.verified_best",
        {"samples": Arg(Count(minimum=2), 2, names=("samples", "verify")),
         "candidates": Arg(Count(), 2, names=("candidates",))},
        robot=None, obj=lambda s: _study_result()),
    Api("pkdyn.design.StudyResult.verify",
        {"samples": Arg(Count(minimum=2), 2, names=("samples", "verify")),
         "candidates": Arg(Count(), 2, names=("candidates",))},
        robot=None, obj=lambda s: _study_result()),
    *[Api(f"pkdyn.design.StudyResult.{m}",
          {"i": Arg(Count(minimum=0, optional=True), 1, names=("i", "design", "index", "row"))},
          robot=None, obj=lambda s: _study_result())
      for m in ("record", "overrides", "params", "urdf", "param_args")],
    Api("pkdyn.design.StudyResult.robot",
        {"i": Arg(Count(minimum=0, optional=True), 1, names=("i", "design", "index", "row")),
         "geometry": Arg(Flag(), False, names=("geometry",))},
        robot=None, obj=lambda s: _study_result()),
    Api("pkdyn.design.StudyResult.write_urdf",
        {"path": Arg(PathOut(".urdf"), Lazy(lambda s: s.dir / "best.urdf"), names=("path",)),
         "i": Arg(Count(minimum=0, optional=True), 1, names=("i", "design", "index", "row"))},
        robot=None, obj=lambda s: _study_result()),
    Api("pkdyn.design.StudyResult.command",
        {"what": Arg(Choice(("urdf", "workspace", "size")), "urdf", names=("what",)),
         "i": Arg(Count(minimum=0, optional=True), 1, names=("i", "design", "index", "row"))},
        robot=None, obj=lambda s: _study_result()),
    Api("pkdyn.design.StudyResult.summary", {"top": Arg(Count(), 5, names=("top",))},
        robot=None, obj=lambda s: _study_result()),
    # ---- merged from main: readings, accuracy, vibration, result methods with arguments
    Api("pkdyn.Robot.joint_coordinates",
        {"readings": Arg(Vector("n_a"), Lazy(lambda s: s.robot.q_home[s.robot.actuated_q].copy()),
                         names=("readings", "reading")),
         "rates": Arg(Flag(), False, names=("rates",))}, obj=lambda s: s.robot),
    Api("pkdyn.Robot.readings",
        {"qa": Arg(Vector("n_a"), Lazy(lambda s: s.robot.q_home[s.robot.actuated_q].copy()),
                   names=("qa", "actuat")),
         "rates": Arg(Flag(), False, names=("rates",))}, obj=lambda s: s.robot),
    Api("pkdyn.calibration.Measurements.where", {"i": Arg(Count(minimum=0), 0, names=("i", "row"))},
        obj=lambda s: _cal_measurements()),
    Api("pkdyn.calibration.Measurements.with_readings",
        {"qa": Arg(Matrix(30, "n_a"), Lazy(lambda s: _cal_measurements().qa.copy()),
                   names=("qa",))}, obj=lambda s: _cal_measurements()),
    Api("pkdyn.identification.Measurements.where",
        {"k": Arg(Count(minimum=0), 0, names=("k", "sample", "row"))}, robot="five_bar",
        obj=lambda s: _id_measurements()),
    Api("pkdyn.calibration.CalibrationResult.urdf",
        {"xml": Arg(Text(optional=True), None, names=("xml",))},
        obj=lambda s: _calibrated(), nan_ok=True, timeout=30),
    Api("pkdyn.calibration.CalibrationResult.write_urdf",
        {"path": Arg(PathOut(".urdf"), Lazy(lambda s: s.dir / "cal.urdf"), names=("path",)),
         "xml": Arg(Text(optional=True), None, names=("xml",))},
        obj=lambda s: _calibrated(), nan_ok=True, timeout=30),
    Api("pkdyn.analysis.CollisionReport.table", {"top": Arg(Count(minimum=0), 10, names=("top",))},
        robot="five_bar", geometry=True,
        obj=lambda s: pkdyn.analysis.distance_report(s.robot, s.robot.q_home)),
    Api("pkdyn.design.StudyResult.report", {"top": Arg(Count(), 5, names=("top",))}, robot=None,
        obj=lambda s: _study_result()),
    Api("pkdyn.precision.Modes.table", {"top": Arg(Count(optional=True), 3, names=("top",))},
        obj=lambda s: _modes()),
    Api("pkdyn.precision.ElasticModel.at", {"q": POSED_Q}, obj=lambda s: _elastic()),
    Api("pkdyn.precision.Section.inertia",
        {"length": Arg(Real("m", sign="positive"), 0.3, names=("length",)),
         "material": Arg(Obj("Material"), Lazy(lambda s: pkdyn.precision.STEEL),
                         names=("material",))},
        robot=None, obj=lambda s: pkdyn.precision.Section(0.01)),
    Api("pkdyn.precision.GridMap.extreme",
        {"name": Arg(Choice(), "stiffness_min", names=("name",))},
        robot="five_bar", obj=lambda s: _precision_map()),
    Api("pkdyn.precision.GridMap.where",
        {"name": Arg(Choice(), "stiffness_min", names=("name",))},
        robot="five_bar", obj=lambda s: _precision_map()),
    Api("pkdyn.precision.GridMap.write_csv",
        {"path": Arg(PathOut(".csv"), Lazy(lambda s: s.dir / "map.csv"), names=("path",))},
        robot="five_bar", obj=lambda s: _precision_map()),
    Api("pkdyn.precision.AccuracyMap.field",
        {"name": Arg(Choice(), "actuator_worst", names=("name", "field"))},
        robot="five_bar", obj=lambda s: _accuracy_map()),
    Api("pkdyn.precision.GeometricAccuracy.ranked",
        {"top": Arg(Count(optional=True), 5, names=("top",))}, obj=lambda s: _geometric()),
    Api("pkdyn.precision.GeometricAccuracy.ranking",
        {"top": Arg(Count(optional=True), 5, names=("top",))}, obj=lambda s: _geometric()),
    Api("pkdyn.precision.Validity.warn", {"stacklevel": Arg(Count(), 3, names=("stacklevel",))},
        robot=None, obj=lambda s: pkdyn.precision.Validity()),
    Api("pkdyn.precision.VibrationResult.write_csv",
        {"path": Arg(PathOut(".csv"), Lazy(lambda s: s.dir / "vib.csv"), names=("path",))},
        obj=lambda s: _vibration()),
    Api("pkdyn.precision.actuator_errors",
        {"robot": ROBOT_R, "q": POSED_Q,
         "resolution": Arg(Vector((1, 3)), 1e-4, names=("resolution",)),
         "backlash": Arg(Vector((1, 3)), 0.0, names=("backlash",))}),
    Api("pkdyn.precision.geometric_errors",
        {"robot": ROBOT_R, "q": POSED_Q,
         "model": Arg(Obj("ParameterModel"), Lazy(lambda s: _delta_model()), names=("model",)),
         "tolerance": Arg(Vector(None), 1e-5, names=("tolerance",)),
         "distribution": Arg(Choice(("uniform", "normal")), "uniform", names=("distribution",))}),
    Api("pkdyn.precision.monte_carlo",
        {"robot": ROBOT_R, "q": POSED_Q,
         "model": Arg(Obj("ParameterModel"), Lazy(lambda s: _delta_model()), names=("model",)),
         "tolerance": Arg(Vector(None), 1e-5, names=("tolerance",)),
         "samples": Arg(Count(minimum=2), 5, names=("samples",)),
         "distribution": Arg(Choice(("uniform", "normal")), "uniform", names=("distribution",)),
         "seed": Arg(Count(minimum=0), 0, names=("seed",)),
         "progress": Arg(Flag(optional=True), False, names=("progress",))}),
    Api("pkdyn.precision.accuracy_budget",
        {"robot": ROBOT_R, "q": POSED_Q,
         "model": Arg(Obj("ParameterModel"), Lazy(lambda s: _delta_model()), names=("model",)),
         "resolution": Arg(Vector((1, 3), optional=True), 1e-4, names=("resolution",)),
         "backlash": Arg(Vector((1, 3), optional=True), None, names=("backlash",)),
         "tolerance": Arg(Vector(None, optional=True), 1e-5, names=("tolerance",)),
         "samples": Arg(Count(minimum=0), 0, names=("samples",)),
         "top": Arg(Count(optional=True), 10, names=("top",))}),
    Api("pkdyn.precision.accuracy_map",
        {"robot": ROBOT_R,
         # (a plane name, or the (N, 3) positions themselves: a wrong type names either)
         "plane": Arg(Choice(("xy", "xz", "yz")), "xy", names=("plane", "positions")),
         "extent": Arg(Real("m", sign="positive", optional=True), None, names=("extent",)),
         "samples": Arg(Count(minimum=2), 3, names=("samples",)),
         "resolution": Arg(Vector((1, 2)), 1e-4, names=("resolution",)),
         "backlash": Arg(Vector((1, 2)), 0.0, names=("backlash",)),
         "progress": Arg(Flag(optional=True), False, names=("progress",))},
        robot="five_bar", nan_ok=True),  # (NaN where a cell is not evaluated: its status)
    Api("pkdyn.precision.vibration",
        {"robot": ROBOT_R,
         "cycle_time": Arg(Real("s", sign="positive", optional=True), None, names=("cycle",)),
         "payload": Arg(Real("kg", sign="non_negative"), 0.0, names=("payload",)),
         "actuator_stiffness": Arg(Vector((1, 3), inf_ok=True), 2e4,
                                   names=("actuator_stiffness",)),
         "band": Arg(Real("m", sign="positive"), 1e-4, names=("band",)),
         "dwell": Arg(Real("s", sign="positive"), 0.1, names=("dwell",)),
         "method": Arg(Choice(("modal", "multibody")), "modal", names=("method",)),
         "dt": Arg(Real("s", sign="positive"), 0.004, names=("dt",)),
         "damping_ratio": Arg(Real(sign="non_negative", optional=True), None,
                              names=("damping_ratio",)),
         "progress": PROGRESS()},
        timeout=60, slow=True),
    Api("pkdyn.viewer.animate_vibration",
        {"result": Arg(Obj("VibrationResult"), Lazy(lambda s: _vibration(True)),
                       names=("result",)),
         "scale": Arg(Real(sign="positive", optional=True), None, names=("scale",)),
         "slow": Arg(Real(sign="positive"), 20.0, names=("slow",))},
        timeout=60, slow=True),
    *[Api(f"pkdyn.plotting.{fn}", {arg: Arg(Obj("a result"), None, names=(arg, "result"))},
          robot=None, baseline=False)
      for fn, arg in (
          ("plot_calibration", "result"), ("plot_calibration_plan", "plan"),
          ("plot_clavel", "comparison"), ("plot_comparison", "comparison"),
          ("plot_efforts", "result"), ("plot_grid_map", "result"),
          ("plot_identification", "result"), ("plot_mel_study", "study"),
          ("plot_monte_carlo", "result"), ("plot_operating_points", "selection"),
          ("plot_orientation_workspace", "ow"), ("plot_pareto", "result"),
          ("plot_ranking", "result"), ("plot_scenario", "report"),
          ("plot_translation_workspace", "ws"), ("plot_vibration", "result"),
      )],
    Api("pkdyn.plotting.plot_simulation",
        {"robot": Arg(RobotArg(), 3, names=("robot", "result")),
         "result": Arg(Obj("a simulation"), 3, names=("result", "robot"))},
        robot=None, baseline=False),
]  # fmt: skip
