"""Family dispatch: closed forms are chosen by ``robot.family`` through per-concept registries;
robots described by their users (no family) take the general path."""

from pathlib import Path

import numpy as np
import pytest

import pkdyn
from pkdyn.analysis.kinematics import kinematic_models
from pkdyn.analysis.screws import RECIPROCAL_SCREWS, reciprocal_screws
from pkdyn.model.families import FAMILIES
from pkdyn.workspace.delta import DeltaEvaluator
from pkdyn.workspace.legs import HexapodEvaluator
from pkdyn.workspace.numeric import NumericEvaluator
from pkdyn.workspace.translation import CLOSED_FORM_EVALUATORS, evaluator_for

URDF = Path(__file__).resolve().parents[1] / "urdf"


def user_described(name: str) -> str:
    """The committed URDF of a family without its ``<pkdyn:family>`` element: the same robot
    described by a user (the committed file itself loads as the family, issue 18)."""
    text = (URDF / f"{name}.urdf").read_text()
    start, end = (
        text.index("  <pkdyn:family"),
        text.index("</pkdyn:family>") + len("</pkdyn:family>"),
    )
    return text[:start] + text[end:]


def test_registry_keys_are_families():
    assert set(RECIPROCAL_SCREWS) <= set(FAMILIES)
    assert {k for k in CLOSED_FORM_EVALUATORS if k is not None} <= set(FAMILIES)


def test_family_of_library_and_user_robots(delta):
    assert delta.family == "delta"
    assert pkdyn.load(URDF / "delta.urdf").family == "delta"  # written by pkdyn urdf delta
    assert pkdyn.load_string(user_described("delta"), "user.urdf").family is None


def test_user_delta_takes_the_general_path(delta):
    user = pkdyn.load_string(user_described("delta"), "user.urdf", geometry=False)
    with pytest.raises(pkdyn.InvalidInputError, match="kinematic_models"):
        reciprocal_screws(user, user.q_home)
    assert isinstance(evaluator_for(user), NumericEvaluator)
    assert isinstance(evaluator_for(delta), DeltaEvaluator)
    # the general path gives the relations the closed form gives for the library robot
    A, B = reciprocal_screws(delta, delta.q_home)
    km = kinematic_models(user, delta.q_home)
    np.testing.assert_allclose(km.J, np.linalg.solve(A, B), atol=1e-9)


def test_user_hexapod_is_recognised_by_its_legs(gough_stewart):
    user = pkdyn.load_string(user_described("gough_stewart"), "user.urdf")
    assert isinstance(evaluator_for(user), HexapodEvaluator)
    assert isinstance(evaluator_for(gough_stewart), HexapodEvaluator)
    assert isinstance(evaluator_for(gough_stewart, "numeric"), NumericEvaluator)


def test_four_arm_delta_has_no_closed_form():
    robot = pkdyn.load("delta", arms=4, geometry=False)
    assert isinstance(evaluator_for(robot), NumericEvaluator)
    with pytest.raises(pkdyn.InvalidInputError, match="no reciprocal-screw model"):
        reciprocal_screws(robot, robot.q_home)
