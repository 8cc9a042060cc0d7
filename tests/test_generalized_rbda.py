"""Every URDF+ model of generalized_rbda loads with its hand-counted mobility (issue 36, item 4).

The files and the counting (tree coordinates minus the rank of the loops minus the couplings)
are in ``tests/data/public/generalized_rbda/README.md``. Each file is loaded as a user loads it
-- ``pkdyn.load(path)`` and ``pkdyn mobility FILE --json`` -- and its mobility, loops, couplings
and actuators (the ``independent`` joints) are those counted from the file. A model that loaded
as a tree (the loops and couplings ignored) would have the tree's coordinates as mobility: every
row below with loops or couplings would fail.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import pytest

import pkdyn
from pkdyn.cli import main

DATA = Path(__file__).parent / "data" / "public" / "generalized_rbda"

# file: (tree velocity coordinates, mobility, loops, couplings, actuators), counted by hand
COUNTS = {
    "robot-models/double_pendulum": (2, 2, 0, 0, 0),
    "robot-models/four_bar": (3, 1, 1, 0, 1),
    "robot-models/six_bar": (5, 3, 1, 0, 3),
    "robot-models/planar_leg_linkage": (4, 2, 1, 0, 2),
    "robot-models/revolute_rotor_chain": (6, 3, 0, 3, 3),
    "robot-models/mini_cheetah_leg": (6, 3, 0, 3, 0),
    "robot-models/mini_cheetah_fl_leg": (6, 3, 0, 3, 3),
    "robot-models/mini_cheetah_fr_leg": (6, 3, 0, 3, 3),
    "robot-models/mini_cheetah_hl_leg": (6, 3, 0, 3, 3),
    "robot-models/mini_cheetah_hr_leg": (6, 3, 0, 3, 3),
    "robot-models/mini_cheetah": (30, 18, 0, 12, 12),
    "robot-models/mini_cheetah_approximate": (18, 18, 0, 0, 0),
    "robot-models/mini_cheetah_base": (6, 6, 0, 0, 0),
    "robot-models/mit_humanoid_leg": (10, 5, 0, 5, 5),
    "robot-models/mit_humanoid": (42, 24, 0, 18, 18),
    "robot-models/mit_humanoid_approximate": (24, 24, 0, 0, 0),
    "robot-models/jvrc1_humanoid": (63, 38, 0, 25, 32),
    "robot-models/jvrc1_humanoid_approximate": (38, 38, 0, 0, 32),
    "robot-models/tello_legs": (20, 20, 0, 0, 10),
    "robot-models/tello_humanoid": (42, 42, 0, 0, 18),
    "robot-models/tello_humanoid_approximate": (24, 24, 0, 0, 18),
    "history/cassie_v4": (26, 25, 0, 1, 25),
    "history/four_bar_loop_constraint": (3, 1, 1, 0, 1),
    "history/four_bar_constraint_position": (3, 1, 1, 0, 1),
    "history/mini_cheetah_leg_joint_constraint": (6, 3, 0, 3, 3),
    "history/mini_cheetah_leg_constraint_rolling": (6, 3, 0, 3, 0),
    "parallel_chains/explicit_depth5_approx_loop_size2": (10, 10, 0, 0, 10),
    "parallel_chains/explicit_depth5_loop_size2": (10, 9, 0, 1, 9),
    "parallel_chains/explicit_depth5_loop_size4": (10, 9, 0, 1, 9),
    "parallel_chains/explicit_depth5_loop_size6": (10, 9, 0, 1, 9),
    "parallel_chains/explicit_depth5_loop_size8": (10, 9, 0, 1, 9),
    "parallel_chains/explicit_depth5_loop_size10": (10, 9, 0, 1, 9),
    "parallel_chains/explicit_depth10_loop_size12": (20, 19, 0, 1, 19),
    "parallel_chains/explicit_depth20_loop_size20": (40, 39, 0, 1, 39),
    "parallel_chains/explicit_depth40_loop_size2": (80, 79, 0, 1, 79),
    "parallel_chains/explicit_depth40_loop_size40": (80, 79, 0, 1, 79),
    "parallel_chains/implicit_depth5_approx_loop_size3": (10, 10, 0, 0, 9),
    "parallel_chains/implicit_depth5_loop_size3": (11, 9, 1, 0, 9),
    "parallel_chains/implicit_depth5_loop_size5": (11, 9, 1, 0, 9),
    "parallel_chains/implicit_depth5_loop_size7": (11, 9, 1, 0, 9),
    "parallel_chains/implicit_depth5_loop_size9": (11, 9, 1, 0, 9),
    "parallel_chains/implicit_depth5_loop_size11": (11, 9, 1, 0, 9),
    "parallel_chains/implicit_depth10_loop_size13": (21, 19, 1, 0, 19),
    "parallel_chains/implicit_depth20_loop_size21": (41, 39, 1, 0, 39),
    "parallel_chains/implicit_depth40_loop_size41": (81, 79, 1, 0, 79),
    "variable_four_bar/four_bar_branch_1_1": (9, 7, 1, 0, 1),
    "variable_four_bar/four_bar_branch_2_3": (24, 12, 6, 0, 6),
    "variable_four_bar/four_bar_branch_4_5": (66, 26, 20, 0, 20),
    "variable_four_bar/approx_four_bar_branch_2_3": (12, 12, 0, 0, 6),
}


def test_every_vendored_file_is_counted():
    files = {str(p.relative_to(DATA).with_suffix("")) for p in DATA.glob("*/*.urdf")}
    assert files == set(COUNTS)


def _load(path: Path) -> pkdyn.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # inertias, rotors, free dependent joints: said on load
        return pkdyn.load(path)


@pytest.mark.parametrize("name", list(COUNTS))
def test_loads_with_its_hand_counted_mobility(name):
    nv, mobility, loops, couplings, actuators = COUNTS[name]
    robot = _load(DATA / f"{name}.urdf")
    assert robot.nv == nv
    assert len(robot.closures) == loops
    assert len(robot.couplings) == couplings
    assert len(robot.actuators) == actuators
    assert robot.mobility() == mobility
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-9


@pytest.mark.parametrize("name", list(COUNTS))
def test_pkdyn_mobility_command_counts_the_same(name, capsys):
    code = main(["mobility", str(DATA / f"{name}.urdf"), "--json"])
    out = capsys.readouterr().out
    assert code in (0, None), out
    assert json.loads(out)["mobility"] == COUNTS[name][1]
