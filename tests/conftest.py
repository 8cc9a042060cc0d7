"""Shared fixtures and helpers of the test suite.

Helpers used by several test modules live here (import them with ``from conftest import ...``);
the headless-browser client of the viewer tests is in :mod:`support.browser`.
"""

import signal

import numpy as np
import pinocchio as pin
import pytest

import pkdyn

if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    # started in the background by a non-interactive shell (`make test &`): SIGINT is ignored,
    # and the ignored disposition is inherited by every process the signal tests start (a
    # Ctrl-C would then never reach them); the tests need the interactive default
    signal.signal(signal.SIGINT, signal.default_int_handler)


@pytest.fixture(scope="session")
def delta() -> pkdyn.Robot:
    return pkdyn.load("delta")


@pytest.fixture(scope="session")
def gough_stewart() -> pkdyn.Robot:
    return pkdyn.load("gough_stewart")


def simpson_work(t: np.ndarray, power: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cumulative integral of a power by Simpson's rule at every second sample.

    The samples must be uniform; with an even number of them the last is dropped.

    Returns:
        ``(work, idx)``: the work [J] at the samples ``idx`` (0, 2, 4, ...).

    """
    if len(t) % 2 == 0:
        t, power = t[:-1], power[:-1]
    h = t[1] - t[0]
    assert np.allclose(np.diff(t), h), "Simpson's rule here needs uniform samples"
    seg = h / 3.0 * (power[:-2:2] + 4.0 * power[1:-1:2] + power[2::2])
    return np.concatenate([[0.0], np.cumsum(seg)]), np.arange(0, len(t), 2)


def null_space(J: np.ndarray, rtol: float = 1e-9) -> np.ndarray:
    """Orthonormal basis (n, k) of the null space of ``J`` (numpy SVD, relative cut-off)."""
    _, s, Vt = np.linalg.svd(J)
    return Vt[int(np.sum(s > rtol * s[0])) :].T


def random_configs(
    robot: pkdyn.Robot, n: int, seed: int, spread: tuple[float, float]
) -> list[np.ndarray]:
    """Assembled configurations at random reachable poses around the home pose (IK).

    Args:
        robot: The robot (with a platform).
        n: Number of configurations.
        seed: Seed of the random poses.
        spread: Largest offsets of the controlled pose components: translation [m], rotation
            [rad]; poses out of reach are drawn again.

    """
    rng = np.random.default_rng(seed)
    dp, dr = spread
    M0 = robot.platform_placement(robot.q_home)
    out = []
    while len(out) < n:
        d = np.zeros(6)
        d[:3] = rng.uniform(-dp, dp, 3)
        d[3:] = rng.uniform(-dr, dr, 3)
        d6 = np.zeros(6)
        d6[robot.task_rows] = d[robot.task_rows]
        target = pin.SE3(M0.rotation @ pin.exp3(d6[3:]), M0.translation + d6[:3])
        try:
            out.append(pkdyn.inverse_geometry(robot, target, q_init=robot.q_home).q)
        except pkdyn.PkdynError:
            continue
    return out


def parallelogram_normals_det(robot: pkdyn.Robot, q: np.ndarray) -> float:
    """``det [n1 n2 n3]`` of the unit normals of the Delta's three parallelograms at ``q``.

    Each parallelogram is spanned by its bars (direction ``u``) and its elbow axle (the segment
    between the two bars' upper joints, ``d``): ``n = u x d``. Where the three normals are
    coplanar the parallelograms no longer hold the nacelle's orientation (it may turn about the
    line normal to all three): the closures lose rank whatever the arms do. A closed form,
    independent of the dynamics and of the conditioning figure.
    """
    model, data = robot.model, robot.model.createData()
    pin.forwardKinematics(model, data, q)
    normals = []
    for i in (1, 2, 3):
        ja, jb = model.getJointId(f"bar{i}a_upper"), model.getJointId(f"bar{i}b_upper")
        a, b = data.oMi[ja].translation, data.oMi[jb].translation
        cm = next(c for c in robot.constraint_models if c.joint1_id == ja)
        end = (data.oMi[ja] * cm.joint1_placement).translation
        u, d = (end - a) / np.linalg.norm(end - a), (b - a) / np.linalg.norm(b - a)
        n = np.cross(u, d)
        normals.append(n / np.linalg.norm(n))
    return float(np.linalg.det(np.array(normals)))
