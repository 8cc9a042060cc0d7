"""Leg collisions: coal distances on the robot's geometry and the analytic segment distance."""

import coal
import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.analysis.collisions import (
    CollisionChecker,
    collision_pairs,
    distance_report,
    segment_distance,
)
from pkdyn.exceptions import InvalidInputError, PkdynError


def _capsule(p, q, r):
    """A coal capsule spanning the segment p -> q, and its placement."""
    L = float(np.linalg.norm(q - p))
    z = (q - p) / L
    h = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(h, z)
    x /= np.linalg.norm(x)
    R = np.column_stack([x, np.cross(z, x), z])
    return coal.Capsule(r, L), coal.Transform3s(R, 0.5 * (p + q))


def _coal_segment_distance(p1, q1, p2, q2, r=1e-4):
    """Segment distance through coal: capsule distance plus both radii."""
    req = coal.DistanceRequest()
    req.gjk_tolerance = 1e-12
    c1, T1 = _capsule(p1, q1, r)
    c2, T2 = _capsule(p2, q2, r)
    res = coal.DistanceResult()
    return coal.distance(c1, T1, c2, T2, req, res) + 2 * r, res


def test_segment_distance_matches_coal_on_random_samples():
    rng = np.random.default_rng(0)
    P = rng.uniform(-0.5, 0.5, (3000, 4, 3))
    d, s, t = segment_distance(P[:, 0], P[:, 1], P[:, 2], P[:, 3])
    checked = 0
    for n in range(len(P)):
        if d[n] < 1e-3:  # capsules would overlap; coal then returns a penetration depth
            continue
        dc, _ = _coal_segment_distance(*P[n])
        assert abs(dc - d[n]) < 1e-9, (n, dc, d[n])
        checked += 1
    assert checked > 2900
    # the closest points are the reported parameters
    a = P[:, 0] + s[:, None] * (P[:, 1] - P[:, 0])
    b = P[:, 2] + t[:, None] * (P[:, 3] - P[:, 2])
    np.testing.assert_allclose(np.linalg.norm(a - b, axis=1), d, atol=1e-12)
    assert np.all((0 <= s) & (s <= 1) & (0 <= t) & (t <= 1))


def _reference_distance(p1, q1, p2, q2):
    """Extended-precision reference: ternary search on s with the optimal clamped t."""
    L = np.longdouble
    p1, q1, p2, q2 = (np.asarray(v, dtype=L) for v in (p1, q1, p2, q2))
    d2 = q2 - p2

    def dist(s):
        a = p1 + s * (q1 - p1)
        t = np.clip(np.dot(a - p2, d2) / np.dot(d2, d2), L(0), L(1))
        return np.sqrt(np.sum((a - p2 - t * d2) ** 2))

    lo, hi = L(0), L(1)
    for _ in range(200):
        m1, m2 = lo + (hi - lo) / 3, hi - (hi - lo) / 3
        lo, hi = (lo, m2) if dist(m1) < dist(m2) else (m1, hi)
    return float(dist(lo))


def test_segment_distance_nearly_parallel_against_extended_precision():
    """Nearly parallel segments (1e-7 rad): exact to 1e-12 (coal's capsules lose ~5e-8 m here)."""
    rng = np.random.default_rng(4)
    P = rng.uniform(-0.5, 0.5, (40, 4, 3))
    P[:, 3] = P[:, 2] + (P[:, 1] - P[:, 0]) * rng.uniform(0.5, 2.0, (40, 1))
    P[:, 3] += rng.normal(0, 1e-7, (40, 3))
    d, _, _ = segment_distance(P[:, 0], P[:, 1], P[:, 2], P[:, 3])
    ref = np.array([_reference_distance(*x) for x in P])
    np.testing.assert_allclose(d, ref, atol=1e-12)


def test_segment_distance_is_the_minimum_over_points():
    """Independent of coal: no pair of sampled points on the segments is closer."""
    rng = np.random.default_rng(1)
    P = rng.uniform(-1, 1, (200, 4, 3))
    d, _, _ = segment_distance(P[:, 0], P[:, 1], P[:, 2], P[:, 3])
    u = np.linspace(0, 1, 201)
    A = P[:, None, 0] + u[None, :, None] * (P[:, None, 1] - P[:, None, 0])
    B = P[:, None, 2] + u[None, :, None] * (P[:, None, 3] - P[:, None, 2])
    brute = np.linalg.norm(A[:, :, None] - B[:, None, :], axis=3).min(axis=(1, 2))
    assert np.all(d <= brute + 1e-12)
    assert np.all(brute - d < 1e-2)


def test_segment_distance_degenerate_segments():
    p = np.array([0.0, 0.0, 0.0])
    q = np.array([1.0, 0.0, 0.0])
    pt = np.array([0.5, 2.0, 0.0])
    assert segment_distance(p, q, pt, pt)[0] == pytest.approx(2.0)
    assert segment_distance(pt, pt, p, q)[0] == pytest.approx(2.0)
    assert segment_distance(pt, pt, p, p)[0] == pytest.approx(np.hypot(0.5, 2.0))
    # parallel overlapping segments
    assert segment_distance(p, q, p + [0.2, 0.3, 0], q + [0.2, 0.3, 0])[0] == pytest.approx(0.3)


def _legs(robot, pose):
    p = robot.params
    M = pin.SE3(pin.rpy.rpyToMatrix(*pose[3:]), np.asarray(pose[:3]))
    return p.a, (M.rotation @ p.b.T).T + M.translation


def test_default_pairs_skip_touching_bodies(gough_stewart):
    names = [g.name for g in gough_stewart.collision_model.geometryObjects]
    pairs = {frozenset((names[i], names[j])) for i, j in collision_pairs(gough_stewart)}
    for i in range(1, 7):
        # prismatic joint, universal joint to the base, closure on the platform
        assert frozenset((f"leg{i}_cylinder_0", f"leg{i}_rod_0")) not in pairs
        assert frozenset((f"leg{i}_cylinder_0", "base_0")) not in pairs
        assert frozenset((f"leg{i}_rod_0", "platform_0")) not in pairs
        # leg against base and platform, legs against each other
        assert frozenset((f"leg{i}_rod_0", "base_0")) in pairs
        assert frozenset((f"leg{i}_cylinder_0", "platform_0")) in pairs
        for j in range(i + 1, 7):
            assert frozenset((f"leg{i}_rod_0", f"leg{j}_cylinder_0")) in pairs
    # the platform's free-flyer is a modelling device: platform vs base is checked
    assert frozenset(("platform_0", "base_0")) in pairs


def test_leg_distances_agree_with_analytic_leg_axes(gough_stewart):
    """Coal on the URDF cylinders vs the analytic distance of the leg axes minus 2 r."""
    robot = gough_stewart
    r = robot.params.leg_radius
    checker = CollisionChecker(robot)
    rng = np.random.default_rng(3)
    zh = robot.params.home_height()
    compared = 0
    for _ in range(15):
        pose = np.concatenate([rng.uniform(-0.04, 0.04, 3) + [0, 0, zh], rng.uniform(-0.2, 0.2, 3)])
        q = pkdyn.inverse_geometry(robot, pose, check_limits=False).q
        rep = checker.report(q)
        leg = {}
        for pd in rep.pairs:
            if pd.a.startswith("leg") and pd.b.startswith("leg"):
                key = (int(pd.a[3]), int(pd.b[3]))
                leg[key] = min(leg.get(key, np.inf), pd.distance)
        A, B = _legs(robot, pose)
        for (i, j), dist in leg.items():
            d, s, t = segment_distance(A[i - 1], B[i - 1], A[j - 1], B[j - 1])
            if 0.05 < s < 0.95 and 0.05 < t < 0.95 and d > 2 * r:  # flat caps not involved
                assert dist == pytest.approx(float(d) - 2 * r, abs=1e-8)
                compared += 1
    assert compared > 15


def test_crossing_legs_reported_and_clear_pose_not(gough_stewart):
    robot = gough_stewart
    zh = robot.params.home_height()
    # a yaw of 0.4 rad brings the axes of legs 2 and 4 within 1 mm of each other
    crossing = np.array([0.0, 0.0, zh, 0.0, 0.0, 0.4])
    A, B = _legs(robot, crossing)
    d_axes = float(segment_distance(A[1], B[1], A[3], B[3])[0])
    assert d_axes < 2e-3
    q = pkdyn.inverse_geometry(robot, crossing, check_limits=False).q
    rep = distance_report(robot, q, margin=0.0)
    assert rep.in_collision
    worst = rep.pairs[0]
    assert {worst.a[:4], worst.b[:4]} == {"leg2", "leg4"}
    # penetration depth of two crossing cylinders of radius r: 2 r - axis distance
    assert worst.distance == pytest.approx(d_axes - 2 * robot.params.leg_radius, abs=1e-6)
    # legs 1 and 6 cross too; every colliding pair matches the analytic leg axes
    for pd in rep.colliding:
        i, j = int(pd.a[3]) - 1, int(pd.b[3]) - 1
        assert {i, j} in ({1, 3}, {0, 5})
        d_ij = float(segment_distance(A[i], B[i], A[j], B[j])[0])
        assert pd.distance == pytest.approx(d_ij - 2 * robot.params.leg_radius, abs=1e-6)
    # home: clear; the closest legs are the rods of legs 2-4 and 1-6 (closest points inside
    # both rods), so the distance is that of the rod axes minus two radii: rods of length
    # min(rho_min, cylinder_length) ending at B_i on the leg lines (Merlet's MEL, Table 3.1)
    rep = distance_report(robot, robot.q_home)
    p = robot.params
    A, B = _legs(robot, np.array([0.0, 0.0, zh, 0.0, 0.0, 0.0]))
    u = (B - A) / np.linalg.norm(B - A, axis=1)[:, None]
    rod = np.minimum(p.rho_min, p.cylinder_length)[:, None]
    d, s, t = segment_distance(
        B[[1, 0]],
        B[[1, 0]] - rod[[1, 0]] * u[[1, 0]],
        B[[3, 5]],
        B[[3, 5]] - rod[[3, 5]] * u[[3, 5]],
    )
    assert np.all((0.05 < s) & (s < 0.95) & (0.05 < t) & (t < 0.95))
    expected = float(np.min(d)) - 2 * p.leg_radius  # 14.4 mm
    assert not rep.in_collision and rep.min_distance == pytest.approx(expected, abs=1e-8)
    assert {rep.pairs[0].a, rep.pairs[0].b} in (
        {"leg2_rod_0", "leg4_rod_0"},
        {"leg1_rod_0", "leg6_rod_0"},
    )
    assert distance_report(robot, robot.q_home, margin=0.02).in_collision
    # nearest points are on the surfaces, min_distance apart
    p0 = rep.pairs[0]
    assert np.linalg.norm(p0.point_a - p0.point_b) == pytest.approx(p0.distance, abs=1e-8)


def test_explicit_pairs_and_json(gough_stewart):
    rep = distance_report(
        gough_stewart, gough_stewart.q_home, pairs=[("leg1_rod", "leg6_rod"), ("base", "platform")]
    )
    assert [{p.a, p.b} for p in rep.pairs] == [
        {"leg1_rod_0", "leg6_rod_0"},
        {"base_0", "platform_0"},
    ]
    out = rep.to_json()
    assert set(out) >= {"min_distance", "pairs", "in_collision"}
    assert out["pairs"][0]["distance"] == out["min_distance"]
    assert len(out["pairs"][0]["point_a"]) == 3
    with pytest.raises(InvalidInputError, match="leg9"):
        distance_report(gough_stewart, gough_stewart.q_home, pairs=[("leg9", "base")])


def test_no_geometry_is_an_error():
    robot = pkdyn.load("five_bar", geometry=False)
    with pytest.raises(PkdynError, match="no collision geometry"):
        distance_report(robot, robot.q_home)


def _cylinder_axes(robot: pkdyn.Robot, q: np.ndarray) -> dict[str, tuple]:
    """Axis end points (world) and radius of every collision cylinder, from the placements."""
    gm = robot.collision_model
    gd = pin.GeometryData(gm)
    pin.updateGeometryPlacements(robot.model, robot.data, gm, gd, q)
    out = {}
    for k, g in enumerate(gm.geometryObjects):
        if isinstance(g.geometry, coal.Cylinder):
            h = g.geometry.halfLength
            ends = [gd.oMg[k].act(np.array([0.0, 0.0, z])) for z in (-h, h)]
            out[g.name] = (ends[0], ends[1], g.geometry.radius)
    return out


# Tripod pairs that overlap at home by construction (see pkdyn.library.tripod): in each branch
# the knuckle sphere is centred on A, where rod R ends (hinge closure on rod L, which carries the
# knuckle) and where the foot post starts (universal joint at A); the two actuator bodies
# converge on A in the triangle plane (the model puts both axes in that plane; hardware would
# stagger them along axis a), so their cylinders meet near their ends (11 mm at home).
TRIPOD_BY_DESIGN = {
    frozenset((f"branch{i}_{a}_0", f"branch{i}_{b}_0"))
    for i in (1, 2, 3)
    for a, b in (("knuckle", "rodR"), ("cylL", "cylR"), ("rodL", "foot"), ("rodR", "foot"))
}


@pytest.mark.parametrize(
    "name, closest, distance",
    [
        # recorded figures (coal); the three pairs are equal by the ternary symmetry
        ("delta", {("bar1b", "bar3a"), ("bar2a", "bar3b"), ("bar1a", "bar2b")}, 0.0058611),
        (
            "planar_3rrr",
            {("distal1", "distal2"), ("distal2", "distal3"), ("distal1", "distal3")},
            0.1583207,
        ),
        # the actuator body of one side and the rod of the other, in each branch (the rim of the
        # body's far end against the rod: closed form below)
        (
            "tripod",
            {
                (f"branch{i}_cyl{a}", f"branch{i}_rod{b}")
                for i in (1, 2, 3)
                for a, b in ("LR", "RL")
            },
            0.0036428,
        ),
    ],
)
def test_library_robots_clear_at_home(name, closest, distance):
    """At home only the by-design overlaps penetrate; every other pair is clear, the closest ones
    are the expected symmetric pairs, and each cylinder pair agrees with its axes: the axis
    distance minus both radii when the closest points are inside both cylinders, between that
    and the axis distance otherwise (flat ends)."""
    robot = pkdyn.load(name)
    rep = distance_report(robot, robot.q_home)
    by_design = TRIPOD_BY_DESIGN if name == "tripod" else set()
    # the by-design overlaps are left out of the interference definition, and listed
    assert {frozenset(p) for p in rep.excluded} == by_design
    assert not any(p.distance < 0.0 for p in rep.pairs) and not rep.in_collision
    full = CollisionChecker(robot).report(robot.q_home)
    assert {frozenset((p.a, p.b)) for p in full.pairs if p.distance < 0.0} == by_design
    clear = [p for p in rep.pairs if frozenset((p.a, p.b)) not in by_design]
    assert len(clear) > 20
    first = [p for p in clear if p.distance < clear[0].distance + 1e-9]
    assert {tuple(sorted((p.a[:-2], p.b[:-2]))) for p in first} == closest
    assert clear[0].distance == pytest.approx(distance, abs=1e-6)
    axes = _cylinder_axes(robot, robot.q_home)
    for p in clear:
        if p.a in axes and p.b in axes:
            (a0, a1, ra), (b0, b1, rb) = axes[p.a], axes[p.b]
            d, s, t = (float(x) for x in segment_distance(a0, a1, b0, b1))
            if 1e-3 < s < 1 - 1e-3 and 1e-3 < t < 1 - 1e-3 and d > ra + rb:
                assert p.distance == pytest.approx(d - ra - rb, abs=1e-8), (p.a, p.b)
            else:
                assert d - ra - rb - 1e-9 <= p.distance <= d + 1e-9, (p.a, p.b)
    if name == "tripod":
        # the actuator body and the other rod lie in the triangle plane: the closest point of
        # the body is the rim of its far end, in that plane, on the rod's side
        for p in first:
            cyl, rod = sorted((p.a, p.b), key=lambda n: "_rod" in n)
            (c0, c1, rc), (r0, r1, rr) = axes[cyl], axes[rod]
            normal = np.cross(c1 - c0, r1 - r0)
            assert abs(normal @ (r0 - c0)) < 1e-12 * np.linalg.norm(normal)  # coplanar axes
            end = min((c0, c1), key=lambda e: float(segment_distance(e, e, r0, r1)[0]))
            side = np.cross(normal, c1 - c0)
            side *= np.sign(side @ (0.5 * (r0 + r1) - end)) / np.linalg.norm(side)
            rim = end + rc * side
            expected = float(segment_distance(rim, rim, r0, r1)[0]) - rr
            assert p.distance == pytest.approx(expected, abs=1e-8)
        # across bodies of different branches: the knuckle spheres (radius 0.03, centred on A,
        # foot_height = 0.06 above the support) are closest to the support: 0.03 (closed form)
        other = [p for p in clear if p.a[:8] != p.b[:8]]
        assert other[0].distance == pytest.approx(robot.params.foot_height - 0.03, abs=1e-9)
        assert {other[0].a, other[0].b} <= {
            "support_0",
            *(f"branch{i}_knuckle_0" for i in (1, 2, 3)),
        }


def test_cli_collisions_json(capsys):
    import json

    from pkdyn.cli import main

    zh = pkdyn.load("gough_stewart", geometry=False).params.home_height()
    code = main(
        ["collisions", "gough_stewart", "--pose", "0", "0", str(zh), "0", "0", "0.4", "--json"]
    )
    out, _ = capsys.readouterr()
    assert code == 0
    rep = json.loads(out)
    assert set(rep) >= {"min_distance", "pairs"} and rep["in_collision"] is True
    assert {rep["pairs"][0]["a"][:4], rep["pairs"][0]["b"][:4]} in (
        {"leg2", "leg4"},
        {"leg1", "leg6"},
    )
    code = main(["collisions", "gough_stewart", "--pose", "0", "0", str(zh), "--pair", "leg1_rod"])
    _, err = capsys.readouterr()
    assert code == 1 and err.count("\n") == 1 and "--pair" in err
