"""A figure only where it is defined (issue 35, items 1 and 5; issue 34, item 4).

- the five-bar with both chains stretched (a serial singularity the kinematic models see) and
  the geared five-bar whose task coordinate never moves: stiffness refused in one line naming
  the pose; modes flagged; the same decision for the mechanism at ten times the size (the rule
  is scale-aware); near the singularity the figure is given with a warning;
- ``inf`` actuators: rigid, reported as such (not 0, not a huge number), in the API and the CLI;
- maps far from the workspace: every cell unreachable, no "up to nan";
- the error budget at a serial singularity is flagged not valid.
"""

import json
import re

import numpy as np
import pytest

import pkdyn
from pkdyn.analysis.singularity import classify
from pkdyn.cli import main
from pkdyn.exceptions import SingularConfigurationError
from pkdyn.precision import PrecisionWarning, actuator_errors, modes, stiffness
from pkdyn.precision.accuracy_maps import accuracy_map
from pkdyn.precision.maps import precision_map


def _stretched(robot, eps=0.0):
    """Both chains of a five-bar stretched (``eps`` [m] below the meeting point)."""
    p = robot.params
    y = np.sqrt((p.l1 + p.l2) ** 2 - (p.d / 2) ** 2) - eps
    th1 = np.arctan2(y, p.d / 2)
    q = pkdyn.forward_geometry(robot, [th1, np.pi - th1], check_limits=False).q
    return q if eps == 0.0 else pkdyn.inverse_geometry(robot, [0.0, y], check_limits=False).q


def _scaled_five_bar(s):
    return pkdyn.load("five_bar", d=0.2 * s, l1=0.2 * s, l2=0.3 * s)


def test_both_chains_stretched_is_refused_and_modes_flagged(capsys):
    five = pkdyn.load("five_bar")
    q = _stretched(five)
    assert classify(five, q).kind == "serial"
    with pytest.raises(SingularConfigurationError, match=r"x y = \[0, 0\.4899\] m.*unbounded"):
        stiffness(five, q, 1e3)
    with pytest.warns(PrecisionWarning, match="unbounded"):
        result = modes(five, q, 1e3)
    assert not result.valid and result.frequencies.size == 2
    payload = result.to_json()
    assert payload["valid"] is False and payload["warnings"]
    assert "NOT VALID" in result.table()
    qa = [str(float(x)) for x in q[five.actuated_q]]
    assert main(["stiffness", "five_bar", "--qa", *qa, "--actuator-stiffness", "1e3"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unbounded" in err and "inf" not in err.split(":")[-1][:3]
    assert main(["modes", "five_bar", "--qa", *qa, "--actuator-stiffness", "1e3", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["valid"] is False


@pytest.mark.parametrize("size", [1.0, 10.0])
def test_the_rule_is_scale_aware(size):
    """The same decisions for the robot ten times larger (springs scaled alike)."""
    robot = _scaled_five_bar(size)
    k = 1e3 * size**2  # the same platform stiffness scale k / L^2
    with pytest.raises(SingularConfigurationError, match="unbounded"):
        stiffness(robot, _stretched(robot), k)
    near = _stretched(robot, 1e-6 * size)
    with pytest.warns(PrecisionWarning, match="near a serial singularity"):
        S = stiffness(robot, near, k)
    assert S.valid and S.warnings and np.all(np.isfinite(S.K))
    regular = stiffness(robot, robot.q_home, k)
    assert regular.valid and not regular.warnings


def test_the_geared_five_bar_whose_task_never_moves(tmp_path):
    from test_coupled_precision import geared_xml

    xml = geared_xml().replace('multiplier="-0.7"', 'multiplier="-1"')  # symmetric: x = 0
    path = tmp_path / "geared.urdf"
    path.write_text(xml)
    robot = pkdyn.load(str(path))
    assert classify(robot, robot.q_home).kind == "serial"
    with pytest.raises(SingularConfigurationError, match=r"x = \[0\] m.*unbounded"):
        stiffness(robot, robot.q_home, 1e3)
    with pytest.warns(PrecisionWarning):
        assert not modes(robot, robot.q_home, 1e3).valid


def test_rigid_actuators_are_rigid(capsys):
    delta = pkdyn.load("delta")
    S = stiffness(delta, delta.q_home, np.inf)
    assert S.rigid and np.all(S.compliance == 0.0) and np.all(np.isinf(np.diag(S.K)))
    assert S.translational_min == np.inf
    payload = S.to_json()
    assert payload["rigid"] is True
    assert payload["principal"]["translation"]["stiffness"] == [None] * 3
    json.dumps(payload, allow_nan=False)
    M = modes(delta, delta.q_home, np.inf)
    assert M.rigid and M.frequencies.size == 0 and M.f1 == np.inf
    # one arm rigid: the direction it holds is rigid, the others finite
    part = stiffness(delta, delta.q_home, [np.inf, 2e4, 2e4])
    assert part.rigid_directions.shape == (1, 3) and not part.rigid
    k = part.translation.stiffness
    assert np.isinf(k[-1]) and np.all(np.isfinite(k[:2])) and np.all(k[:2] > 0)
    assert main(["stiffness", "delta", "--qa", "0", "0", "0", "--actuator-stiffness", "inf"]) == 0
    out = capsys.readouterr().out
    assert "rigid" in out and "nan" not in out


def test_maps_far_from_the_workspace_say_so(capsys, tmp_path):
    delta = pkdyn.load("delta", geometry=False)
    amap = accuracy_map(delta, "xy", center=[0.0, 0.0, -3.0], extent=0.1, samples=3,
                        resolution=1e-4)  # fmt: skip
    assert not amap.evaluated.any() and not amap.valid.any()
    assert np.isnan(amap.extreme("actuator_worst")) and amap.where("actuator_worst") is None
    text = amap.table()
    assert "nan" not in text and "no cell evaluated" in text
    assert set(np.ravel(amap.to_json()["status"])) == {"unreachable"}
    pmap = precision_map(delta, "xz", center=[0, 0, -3.0], extent=0.05, samples=3,
                         actuator_stiffness=2e4)  # fmt: skip
    assert not pmap.valid and "no cell" in pmap.table()
    argv = ["accuracy", "delta", "--map", "xy", "--center", "0", "0", "-3", "--grid", "3",
            "--extent", "0.1", "--plot", str(tmp_path / "m.png")]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "nan" not in out and "no cell evaluated" in out and "no plot written" in out
    assert not (tmp_path / "m.png").exists()


def test_error_budget_at_a_serial_singularity_is_flagged():
    five = pkdyn.load("five_bar", geometry=False)
    with pytest.warns(PrecisionWarning):
        act = actuator_errors(five, _stretched(five), 1e-4)
    assert not act.valid and "second order" in act.warnings[0]
    assert actuator_errors(five, five.q_home, 1e-4).valid


def test_messages_name_the_pose():
    five = pkdyn.load("five_bar")
    with pytest.raises(SingularConfigurationError) as err:
        stiffness(five, _stretched(five), 1e3)
    assert re.search(r"five_bar at x y = \[[-0-9.e, ]+\] m", str(err.value))
