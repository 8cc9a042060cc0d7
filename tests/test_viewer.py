"""Viewer: scene, keyframes, overlays, highlights, self-contained HTML, and a real browser.

The browser tests open the exported pages in headless Chromium (WebGL on SwiftShader) with the
network routed to a dead proxy and a NetLog, take a screenshot and dump the DOM. They check what a
user would see: the robot drawn where the camera model says (against the same page with the robot
hidden), the animation moving it, the highlight colours on screen, markers at the pixels
:func:`pkdyn.viewer.project` predicts, no console message (uncaught errors included) and no
network request. They skip, saying why, only when Chromium is not installed.
"""

from __future__ import annotations

import base64
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

import meshcat.geometry as mg
import numpy as np
import pinocchio as pin
import pytest
import umsgpack
from support.browser import CHROMIUM, Browser, H, Page, W

import pkdyn
from pkdyn.cli import main
from pkdyn.viewer import Scene, animate, bounding_box, chain, frame_box, project
from pkdyn.viewer import highlight as hl
from pkdyn.viewer.animation import AnimationCommand, Clip, keyframes
from pkdyn.viewer.window import OfflineWindow

ROOT = Path(__file__).resolve().parents[1]


# --------------------------------------------------------------------------------------------
# helpers


def decoded(commands: list[bytes]) -> list[dict]:
    return [umsgpack.unpackb(c) for c in commands]


def page_commands(html: str) -> list[dict]:
    """The meshcat commands a page replays, decoded."""
    block = re.search(r"var commands = \[(.*?)\];", html, re.S)
    assert block is not None
    return decoded([base64.b64decode(s) for s in re.findall(r'"([A-Za-z0-9+/=]+)"', block[1])])


def animation_of(scene: Scene) -> dict:
    (anim,) = [c for c in decoded(scene.record.commands()) if c["type"] == "set_animation"]
    return {
        a["path"]: {t["name"]: t["keys"] for t in a["clip"]["tracks"]} for a in anim["animations"]
    }


def footprint(scene: Scene, Q: np.ndarray, grow: int = 3) -> np.ndarray:
    """Pixels (H, W) covered by the projected box of each drawn object and triad, over Q.

    Boxes come from coal's local AABBs and the model's kinematics, projected with the camera
    model: where the robot must be if the page draws what the scene says.
    """
    from scipy import ndimage

    robot = scene.robot
    model, gm = robot.model, robot.visual_model
    data, gdata = model.createData(), gm.createData()
    unit = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], dtype=float)
    frames = [0] + ([] if robot.platform_frame is None else [robot.platform_frame])
    mask = np.zeros((H, W), dtype=bool)
    for q in np.atleast_2d(Q):
        pin.updateGeometryPlacements(model, data, gm, gdata, q)
        pin.updateFramePlacements(model, data)
        clouds = []
        for gid, obj in enumerate(gm.geometryObjects):
            obj.geometry.computeLocalAABB()
            box = obj.geometry.aabb_local
            lo, hi = np.asarray(box.min_), np.asarray(box.max_)
            M = gdata.oMg[gid]
            clouds.append((lo + unit * (hi - lo)) @ M.rotation.T + M.translation)
        for fid in frames:
            M = data.oMf[fid]
            clouds.append(
                M.translation + np.vstack([np.zeros(3), scene.triad_scale * M.rotation.T])
            )
        for pts in clouds:
            px = project(scene.camera, pts, W, H)
            c0, r0 = np.clip(np.floor(px.min(axis=0)), 0, [W, H]).astype(int)
            c1, r1 = np.clip(np.ceil(px.max(axis=0)) + 1, 0, [W, H]).astype(int)
            mask[r0:r1, c0:c1] = True
    return ndimage.binary_dilation(mask, iterations=grow)


def changed(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.abs(a - b).sum(axis=2) > 40


def inside(mask: np.ndarray, region: np.ndarray) -> tuple[int, int]:
    """Set pixels of ``mask`` inside and outside ``region``."""
    n_in = int((mask & region).sum())
    return n_in, int(mask.sum()) - n_in


def magenta(img: np.ndarray) -> np.ndarray:
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    return (r > 100) & (b > 100) & (g < 0.45 * np.minimum(r, b)) & (np.abs(r - b) < 60)


def red(img: np.ndarray) -> np.ndarray:
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    return (r > 120) & (g < 0.35 * r) & (b < 0.35 * r)


def green(img: np.ndarray) -> np.ndarray:
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    return (g > 90) & (g > r + 50) & (g > b + 30)


def assert_clean(page: Page, n_commands: int) -> None:
    assert page.problems() == [], f"the page reported: {page.problems()}"
    assert page.requests() == [], f"the page used the network: {page.requests()}"
    # the replay ran to its end
    assert page.eval("document.body.getAttribute('data-pkdyn-commands')") == str(n_commands)


# --------------------------------------------------------------------------------------------
# the recording window and the page


def test_offline_window_keeps_latest_state_and_plays_animations_last():
    import meshcat

    w = OfflineWindow()
    vis = meshcat.Visualizer(window=w)
    vis["a/b"].set_object(mg.Box([1, 1, 1]))
    vis["a/b"].set_property("visible", False)
    w.send(AnimationCommand([Clip("/meshcat/a/b")]))
    vis["a/b"].set_transform(np.eye(4))
    vis["a/b"].set_object(mg.Sphere(0.1))  # replaces the box and forgets its properties
    vis["a/c"].set_object(mg.Box([1, 1, 1]))
    vis["a/c"].delete()
    cmds = decoded(w.commands())
    assert [(c["type"], c["path"]) for c in cmds] == [
        ("set_object", "/meshcat/a/b"),
        ("set_transform", "/meshcat/a/b"),
        ("set_animation", "/pkdyn_animation"),
    ]
    assert cmds[0]["object"]["geometries"][0]["type"] == "SphereGeometry"
    with pytest.raises(ValueError, match="capture_image"):
        from meshcat.commands import CaptureImage

        w.send(CaptureImage())


def test_page_is_self_contained(delta):
    page = Scene(delta).html()
    # every script is inline; nothing is loaded by URL (the browser tests check it at run time)
    assert not re.search(r"<(script|link|img|iframe|source)\b[^>]*\b(src|href)\s*=", page, re.I)
    assert "<link" not in page and "cdn" not in page.lower().replace("cdnjs", "")
    assert page.count("<script>") == 2 and "MeshCat.Viewer" in page
    assert len(page_commands(page)) > delta.visual_model.ngeoms
    # docs/guide/viewer.md: "meshcat's viewer code is inlined (about 0.9 MB)" (recorded: 0.88 MB)
    assert 0.8e6 < len(page.encode()) < 1.0e6


# --------------------------------------------------------------------------------------------
# camera


def test_bounding_box_of_a_rotated_box():
    urdf = """<robot name="one_box">
      <link name="world"/>
      <link name="b"><visual><origin xyz="0.1 0 0"/><geometry><box size="0.2 0.1 0.04"/>
      </geometry></visual></link>
      <joint name="j" type="revolute"><parent link="world"/><child link="b"/>
      <origin xyz="0 0 0.5"/><axis xyz="0 0 1"/>
      <limit lower="-4" upper="4" effort="1" velocity="1"/></joint></robot>"""
    robot = pkdyn.load_string(urdf, "one_box")
    lo, hi = bounding_box(robot.model, robot.visual_model, np.array([np.pi / 2]))
    # box centre at (0, 0.1, 0.5), its 0.2 m side along y after the quarter turn
    np.testing.assert_allclose(lo, [-0.05, 0.0, 0.48], atol=1e-12)
    np.testing.assert_allclose(hi, [0.05, 0.2, 0.52], atol=1e-12)


@pytest.mark.parametrize("aspect", [0.6, 4 / 3, 2.0])
def test_framed_box_projects_inside_the_view(aspect):
    rng = np.random.default_rng(7)
    w, h = int(600 * aspect), 600
    for _ in range(20):
        lo = rng.uniform(-1, 0, 3)
        hi = lo + rng.uniform(0.05, 1.0, 3)
        cam = frame_box(lo, hi, direction=rng.normal(size=3), aspect=aspect)
        corners = np.array(
            [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
        )
        px = project(cam, corners, w, h)
        assert np.all(px >= 0) and np.all(px[:, 0] <= w) and np.all(px[:, 1] <= h)
        np.testing.assert_allclose(project(cam, cam.target, w, h)[0], [w / 2, h / 2], atol=1e-9)
        up = project(cam, cam.target + [0, 0, 0.01], w, h)[0]
        assert up[1] < h / 2  # world z is up on screen


# --------------------------------------------------------------------------------------------
# animation


def test_keyframes_cap_the_rate_and_keep_the_ends():
    t = np.linspace(0.0, 2.0, 2001)
    k = keyframes(t, 30.0)
    assert k[0] == 0 and k[-1] == 2000
    assert np.all(np.diff(t[k[:-1]]) >= 1 / 30 - 1e-12)
    assert 55 <= k.size <= 62
    np.testing.assert_array_equal(keyframes(t[:3], 1e6), [0, 1, 2])


def test_chain_holds_between_segments():
    t1, Q1 = np.array([1.0, 2.0]), np.array([[0.0], [1.0]])
    t2, Q2 = np.array([0.0, 0.5]), np.array([[5.0], [6.0]])
    t, Q = chain([(t1, Q1), (t2, Q2)], pause=0.25)
    np.testing.assert_allclose(t, [0.0, 1.0, 1.25, 1.251, 1.751])
    np.testing.assert_allclose(Q[:, 0], [0.0, 1.0, 1.0, 5.0, 6.0])


def test_animation_moves_the_platform_along_the_task_trajectory(delta):
    """The platform triad's keyframes are the Adept cycle's task positions (from the task law)."""
    from pkdyn.dynamics.trajectory import named_task, named_trajectory

    task = named_task(delta, "adept")
    traj = named_trajectory(delta, "adept")
    np.testing.assert_allclose(traj.t, task.t)
    scene = Scene(delta)
    keep = scene.animate(traj.t, traj.q)
    tracks = animation_of(scene)["/meshcat/delta/triads/platform"]
    times = np.array([k["time"] for k in tracks[".position"]])
    pos = np.array([k["value"] for k in tracks[".position"]])
    quat = np.array([k["value"] for k in tracks[".quaternion"]])
    np.testing.assert_allclose(times, task.t[keep] - task.t[0])
    np.testing.assert_allclose(pos, task.pose[keep, :3], atol=1e-7)
    np.testing.assert_allclose(np.linalg.norm(quat, axis=1), 1.0, atol=1e-12)
    # the nacelle stays level: its rotation is the home one (quaternion up to sign)
    q0 = pin.Quaternion(delta.platform_placement(delta.q_home).rotation).coeffs()
    np.testing.assert_allclose(np.abs(quat @ q0), 1.0, atol=1e-7)
    assert np.ptp(pos[:, 2]) > 0.02  # it does move


def test_animation_input_errors(delta):
    scene = Scene(delta)
    Q = np.tile(delta.q_home, (3, 1))
    with pytest.raises(pkdyn.InvalidInputError, match="backwards"):
        scene.animate([0.0, 1.0, 0.5], Q)
    with pytest.raises(pkdyn.InvalidInputError, match="shape"):
        scene.animate([0.0, 1.0, 2.0], Q[:, :-1])
    with pytest.raises(pkdyn.InvalidInputError, match="NaN"):
        scene.animate([0.0, np.nan, 2.0], Q)
    with pytest.raises(pkdyn.InvalidInputError, match="q"):
        scene.display(delta.q_home[:-1])


# --------------------------------------------------------------------------------------------
# highlights and overlays


def rrr_towards_singularity(rrr):
    """3-RRR poses (0, 0, phi) from home to phi* = acos(0.8), where the distal lines meet."""
    phi_star = float(np.arccos(0.8))
    q, Q = rrr.q_home, []
    for phi in np.linspace(0.0, phi_star, 9):
        q = pkdyn.inverse_geometry(rrr, [0, 0, 0, 0, 0, phi], q_init=q, check_limits=False).q
        Q.append(q)
    return np.array(Q)


def distal_lines_meet(rrr, q) -> bool:
    """Pasqui's parallel singularity of the 3-RRR: the three distal lines through one point."""
    m, d = rrr.model, rrr.data
    pin.framesForwardKinematics(m, d, q)
    P = rrr.platform_placement(q).translation[:2]
    out = []
    for i in range(3):
        O2 = d.oMi[m.getJointId(f"distal{i + 1}")].translation[:2]
        cm = rrr.constraint_models[2 * i]
        O3 = d.oMi[cm.joint1_id].act(cm.joint1_placement.translation)[:2]
        u, v = O3 - O2, P - O3
        out.append(abs(u[0] * v[1] - u[1] * v[0]) < 1e-7)
    return all(out)


@pytest.fixture(scope="module")
def rrr():
    return pkdyn.load("planar_3rrr")


def test_singular_samples_turn_the_robot_red(rrr):
    Q = rrr_towards_singularity(rrr)
    assert distal_lines_meet(rrr, Q[-1]) and not distal_lines_meet(rrr, Q[0])
    scene = Scene(rrr)
    scene.animate(np.arange(len(Q), dtype=float), Q, singular=True)
    labels, kinds = hl.singularity_labels(rrr, Q)
    assert labels[0] == hl.REGULAR and labels[-1] == hl.SINGULAR and kinds[-1] == "parallel"
    anim = animation_of(scene)
    moving = [
        f"/meshcat/planar_3rrr/visuals/{o.name}"
        for o in rrr.visual_model.geometryObjects
        if o.parentJoint != 0  # the base stays as it is
    ]
    assert len(moving) >= 7
    assert {p for p in anim if ".material.color" in anim[p]} == {f"{n}/<object>" for n in moving}
    for node in moving:
        colours = np.array([k["value"] for k in anim[f"{node}/<object>"][".material.color"]])
        base = np.asarray(scene._base[node][:3])
        for c, label in zip(colours, labels, strict=True):
            want = {hl.SINGULAR: hl.SINGULAR_COLOR, hl.NEAR: hl.NEAR_COLOR}.get(label, base)
            np.testing.assert_allclose(c, want)
    # a static check says the same
    assert Scene(rrr, Q[-1]).highlight_singular() == "singular"
    assert Scene(rrr).highlight_singular() == "regular"


@pytest.mark.parametrize("name", ["gough_stewart", "five_bar"])
def test_closest_legs_are_coloured_at_every_keyframe(name, gough_stewart):
    """Changing pairs (hexapod legs) and a pair closest all along (five-bar base and link)."""
    from pkdyn.analysis.collisions import distance_report
    from pkdyn.dynamics.trajectory import named_trajectory

    robot = gough_stewart if name == "gough_stewart" else pkdyn.load(name)
    traj = named_trajectory(robot, "sine", amplitude=0.03, frequency=0.5, dt=0.01)
    scene = Scene(robot)
    keep = scene.animate(traj.t, traj.q, closest=True, max_rate=20)
    anim = animation_of(scene)
    colour = {
        p[: -len("/<object>")]: np.array([k["value"] for k in tr[".material.color"]])
        for p, tr in anim.items()
        if ".material.color" in tr
    }
    assert colour, "the closest pair never changed colour"
    for k, q in enumerate(traj.q[keep]):
        pairs = distance_report(robot, q).pairs
        ties = [p for p in pairs if p.distance < pairs[0].distance + 1e-9]  # symmetric robots
        lit = {n for n, C in colour.items() if np.allclose(C[k], hl.CLOSEST_COLOR)}
        assert any(lit == set(scene.nodes(p.a) + scene.nodes(p.b)) for p in ties), (k, lit)


def test_highlight_and_overlay_commands(delta):
    scene = Scene(delta)
    scene.highlight(["arm1_0", "bar2a_0"])
    props = [c for c in decoded(scene.record.commands()) if c["type"] == "set_property"]
    lit = {c["path"] for c in props if c["property"] == "color"}
    assert lit == {
        "/meshcat/delta/visuals/arm1_0/<object>",
        "/meshcat/delta/visuals/bar2a_0/<object>",
    }
    # a collision name not drawn maps to the drawn objects on the same body
    assert set(Scene(delta).nodes("arm1_0")) == {"/meshcat/delta/visuals/arm1_0"}
    coll = Scene(delta, collision=True)
    assert coll.nodes("arm1_1") == ["/meshcat/delta/collisions/arm1_0"]
    with pytest.raises(pkdyn.InvalidInputError, match="no geometry object 'leg9'"):
        scene.highlight(["leg9"])
    with pytest.raises(pkdyn.InvalidInputError, match="color"):
        scene.highlight(["arm1_0"], color=(2.0, 0.0, 0.0))
    # overlays: a point cloud and a boundary mesh, the camera reframed to include them
    P = np.random.default_rng(0).uniform([-0.6, -0.6, -0.6], [0.6, 0.6, -0.3], (200, 3))
    scene.add_points("workspace", P)
    from scipy.spatial import ConvexHull

    scene.add_mesh("boundary", P, ConvexHull(P).simplices)
    objs = {
        c["path"]: c["object"]
        for c in decoded(scene.record.commands())
        if c["type"] == "set_object"
    }
    assert objs["/meshcat/overlays/workspace"]["object"]["type"] == "Points"
    assert objs["/meshcat/overlays/boundary"]["object"]["type"] == "Mesh"
    px = project(scene.camera, P, W, H)
    assert np.all((px >= 0) & (px <= [W, H]))
    with pytest.raises(pkdyn.InvalidInputError, match="points"):
        scene.add_points("bad", P[:, :2])
    with pytest.raises(pkdyn.InvalidInputError, match="faces"):
        scene.add_mesh("bad", P, np.array([[0, 1, 999]]))


def test_scene_errors():
    with pytest.raises(pkdyn.PkdynError, match="no geometry"):
        Scene(pkdyn.load("delta", geometry=False))
    with pytest.raises(pkdyn.PkdynError, match="no frame 'tool'"):
        Scene(pkdyn.load("five_bar"), frames=["tool"])


# --------------------------------------------------------------------------------------------
# command line and packaging


def test_cli_writes_html_with_chained_trajectories(tmp_path, capsys):
    out = tmp_path / "delta.html"
    pts = tmp_path / "cloud.csv"
    np.savetxt(pts, np.array([[0.0, 0.0, -0.4], [0.05, 0.0, -0.45]]), delimiter=",")
    code = main(
        ["view", "delta", "--trajectory", "adept", "p2p", "--points", str(pts), "--html", str(out)]
    )
    assert code == 0
    text = capsys.readouterr().out
    assert f"wrote {out}" in text and "adept + p2p" in text
    cmds = page_commands(out.read_text())
    (anim,) = [c for c in cmds if c["type"] == "set_animation"]
    duration = max(
        k["time"] for a in anim["animations"] for tr in a["clip"]["tracks"] for k in tr["keys"]
    )
    assert duration == pytest.approx(0.5 + 0.5 + 0.5 + 1e-3, abs=1e-6)  # adept, pause, p2p
    assert any(c["type"] == "set_object" and c["path"] == "/meshcat/overlays/points" for c in cmds)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["view", "delta", "--trajectory", "nope", "--html", "x.html"],
            "unknown trajectory 'nope'",
        ),
        (["view", "delta", "--html", "/no/such/dir/x.html"], "cannot write"),
        (["view", "delta", "--points", "/no/such.npy", "--html", "x.html"], "--points"),
    ],
)
def test_cli_user_errors_are_one_line(argv, message, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def listening(port: int) -> set[str]:
    """Local addresses of the TCP sockets listening on ``port`` (from /proc/net/tcp, tcp6)."""
    out = set()
    for table, width in (("/proc/net/tcp", 8), ("/proc/net/tcp6", 32)):
        if not os.path.exists(table):
            continue
        for line in Path(table).read_text().splitlines()[1:]:
            local, state = line.split()[1], line.split()[3]
            addr, hexport = local.split(":")
            if state != "0A" or int(hexport, 16) != port:
                continue
            raw = bytes.fromhex(addr)
            if width == 8:
                out.add(".".join(str(b) for b in raw[::-1]))
            else:  # four little-endian 32-bit words
                words = [raw[i : i + 4][::-1] for i in range(0, 16, 4)]
                out.add(socket.inet_ntop(socket.AF_INET6, b"".join(words)))
    return out


def outside_address() -> str | None:
    """An address of this machine other than loopback (None if it has none)."""
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            s.connect(("192.0.2.1", 9))  # no packet is sent: this only picks the interface
            addr = s.getsockname()[0]
    except OSError:
        return None
    return None if addr.startswith("127.") or addr == "0.0.0.0" else addr


@pytest.mark.skipif(not os.path.exists("/proc/net/tcp"), reason="needs Linux /proc/net/tcp")
def test_live_viewer_listens_on_loopback_only(delta):
    scene = Scene(delta, serve=True)
    try:
        url = scene.url
        assert url is not None and url.startswith("http://127.0.0.1:")
        port = int(url.split(":")[2].split("/")[0])
        assert listening(port) == {"127.0.0.1"}
        zmq_port = int(scene._process.zmq_url.rsplit(":", 1)[1])
        assert listening(zmq_port) == {"127.0.0.1"}
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/static/", timeout=10) as r:
            assert r.status == 200
        other = outside_address()
        if other is not None:  # from another address of this machine: refused
            with pytest.raises(OSError):
                socket.create_connection((other, port), timeout=2).close()
    finally:
        scene.close()
    assert listening(port) == set()


@pytest.mark.skipif(not os.path.exists("/proc/net/tcp"), reason="needs Linux /proc/net/tcp")
def test_live_viewer_on_every_interface_only_on_request_with_a_warning(delta):
    with pytest.warns(UserWarning, match="anyone who can reach this machine"):
        scene = Scene(delta, serve=True, host="0.0.0.0")
    try:
        port = int(scene.url.split(":")[2].split("/")[0])
        assert listening(port) == {"0.0.0.0"}
        zmq_port = int(scene._process.zmq_url.rsplit(":", 1)[1])
        assert listening(zmq_port) == {"127.0.0.1"}  # the command socket stays local
    finally:
        scene.close()


def test_core_never_imports_the_viewer():
    """The core (pkdyn/ but the viewer and the CLI) never imports the viewer; CLI modules only
    inside their command functions, so that ``pkdyn --help`` and every other command stay light.
    """
    for path in (ROOT / "pkdyn").rglob("*.py"):
        rel = path.relative_to(ROOT / "pkdyn").as_posix()
        text = path.read_text()
        if rel.startswith("viewer/"):
            continue
        if rel.startswith("cli/"):
            assert not re.search(r"^(from|import)\s+pkdyn\.viewer", text, re.M), rel
        else:
            assert not re.search(r"^\s*(from|import)\s+pkdyn\.viewer", text, re.M), rel
    code = (
        "import sys, pkdyn, pkdyn.cli; pkdyn.cli._parser(); pkdyn.load('delta'); "
        "bad = [m for m in sys.modules if m.startswith(('pkdyn.viewer', 'meshcat'))]; "
        "assert not bad, bad"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


# --------------------------------------------------------------------------------------------
# in a real browser


@pytest.fixture(scope="module")
def work():
    """A private directory for pages and the browser profile.

    Not pytest's ``tmp_path``: concurrent pytest sessions on the machine prune old numbered
    base directories, possibly under a running browser.
    """
    with tempfile.TemporaryDirectory(prefix="pkdyn-viewer-") as d:
        yield Path(d)


@pytest.fixture(scope="module")
def browser(work):
    if not os.access(CHROMIUM, os.X_OK):
        pytest.skip(
            f"headless Chromium not found at {CHROMIUM}: `make test` installs Debian's chromium "
            "with apt-get when run as root with a package repository reachable"
        )
    b = Browser(work)
    yield b
    b.close()


def test_browser_harness_catches_errors_and_network_use(browser, delta, work):
    """The checks below can fail: a thrown error, a console call and a CDN script are caught."""
    page = Scene(delta).html()
    bad = page.replace(
        '<div id="meshcat-pane"></div>',
        '<div id="meshcat-pane"></div><script src="https://cdn.jsdelivr.net/npm/three/x.js">'
        '</script><script>console.warn("probe"); undefinedFunction();</script>',
    )
    (work / "bad.html").write_text(bad)
    tab = browser.open(str(work / "bad.html"))
    found = "\n".join(tab.problems())
    assert "probe" in found and "undefinedFunction" in found and "ERR_PROXY" in found
    assert tab.requests() == ["https://cdn.jsdelivr.net/npm/three/x.js"]


MARKERS = np.array([[0.0, 0.0, 0.0], [0.15, 0.1, -0.2], [-0.1, -0.12, -0.3], [0.05, -0.05, -0.42]])


def add_markers(scene: Scene) -> None:
    for i, p in enumerate(MARKERS):
        node = scene.vis[f"markers/m{i}"]
        node.set_object(mg.Sphere(0.006), mg.MeshBasicMaterial(color=0xFF0000))
        node.set_transform(pin.SE3(np.eye(3), p).homogeneous)


def near(t: np.ndarray, Q: np.ndarray, time_: float) -> np.ndarray:
    """The samples around ``time_`` (the page interpolates between keyframes)."""
    k = int(np.searchsorted(t, time_))
    return Q[max(k - 20, 0) : k + 20]


def test_browser_delta_page_draws_and_animates_the_robot(browser, delta, work):
    from pkdyn.dynamics.trajectory import named_trajectory

    traj = named_trajectory(delta, "adept", cycle_time=2.0, dt=0.01)
    scene = animate(delta, traj.t, traj.q)
    add_markers(scene)
    n = len(scene.record.commands())
    scene.save_html(work / "delta.html")
    scene.vis[scene.root].set_property("visible", False)
    scene.save_html(work / "hidden.html")

    tab = browser.open(str(work / "delta.html"))
    assert_clean(tab, n)
    # the animation plays by itself, a clip per moving node, as long as the trajectory
    clips = len(delta.visual_model.geometryObjects) + 2  # the triads too
    assert tab.eval("viewer.animator.actions.length") == clips
    assert tab.eval("viewer.animator.duration") == pytest.approx(traj.t[-1] - traj.t[0])
    # it plays by itself: the page's own render loop advances it. The animation clock is driven
    # (three frames of 0.1 s, then frozen) so the check does not depend on the machine's load
    # (a 2 s animation loops during a wall-clock wait).
    assert tab.eval("viewer.animator.playing")
    tab.call("Page.bringToFront")  # background tabs get no animation frames
    tab.eval(
        "(() => { const a = viewer.animator; a.seek(0); let n = 0;"
        " a.clock.getDelta = () => (n++ < 3 ? 0.1 : 0); })()"
    )
    advanced = "Math.abs(viewer.animator.time - 0.3) < 1e-9"
    for _ in range(600):
        if tab.eval(advanced):
            break
        time.sleep(0.05)
    assert tab.eval(advanced), tab.eval("viewer.animator.time")
    tab.seek(0.3)
    early = tab.shot("delta_t0.3")
    tab.seek(1.2)
    late = tab.shot("delta_t1.2")
    blank_tab = browser.open(str(work / "hidden.html"))
    assert_clean(blank_tab, n + 1)
    blank = blank_tab.shot("delta_hidden")

    # the robot, where the camera model puts it: inside the projected boxes of its parts
    for image, when in ((early, 0.3), (late, 1.2)):
        region = footprint(scene, near(traj.t, traj.q, when))
        n_in, n_out = inside(changed(image, blank), region)
        assert n_in > 0.15 * region.sum() and n_out < 0.002 * n_in, (when, n_in, n_out)
    # and it moved between the two instants
    moved = changed(early, late)
    assert moved.sum() > 0.02 * footprint(scene, traj.q).sum()
    # the markers land on the pixels project() predicts (robot hidden: nothing occludes them)
    from scipy import ndimage

    mask = red(blank)
    lab, k = ndimage.label(mask)
    centres = np.array(ndimage.center_of_mass(mask, lab, range(1, k + 1)))[:, ::-1]
    for p in project(scene.camera, MARKERS, W, H):
        assert np.min(np.linalg.norm(centres - p, axis=1)) < 2.0, (p, centres)


def test_browser_gough_stewart_closest_legs_and_workspace_cloud(browser, gough_stewart, work):
    scene = Scene(gough_stewart)
    scene.highlight_closest()
    z0 = gough_stewart.platform_placement(gough_stewart.q_home).translation[2]
    rng = np.random.default_rng(1)
    P = rng.uniform([-0.05, -0.05, z0 - 0.05], [0.05, 0.05, z0 + 0.05], (400, 3))
    P[:, :2] += [0.35, 0.0]  # beside the platform, so the cloud does not hide the legs
    scene.add_points("workspace", P, size=0.008)
    n = len(scene.record.commands())
    scene.save_html(work / "gs.html")
    scene.vis[scene.root].set_property("visible", False)
    scene.save_html(work / "gs_hidden.html")
    tab, blank_tab = browser.open(str(work / "gs.html")), browser.open(str(work / "gs_hidden.html"))
    assert_clean(tab, n)
    assert_clean(blank_tab, n + 1)
    shot, blank = tab.shot("gough_stewart"), blank_tab.shot("gough_stewart_hidden")

    region = footprint(scene, gough_stewart.q_home)
    n_in, n_out = inside(changed(shot, blank), region)
    assert n_in > 0.15 * region.sum() and n_out < 0.002 * n_in, (n_in, n_out, region.sum())
    # the two closest legs in magenta, nothing magenta once the robot is hidden
    assert magenta(shot).sum() > 300 and magenta(blank).sum() == 0
    # the workspace cloud, with or without the robot, where its points project
    assert green(blank).sum() > 300 and green(shot).sum() > 300
    cols, rows = np.nonzero(green(blank).T)
    px = project(scene.camera, P, W, H)
    assert px[:, 0].min() - 8 <= cols.min() and cols.max() <= px[:, 0].max() + 8
    assert px[:, 1].min() - 8 <= rows.min() and rows.max() <= px[:, 1].max() + 8


def test_browser_singular_configuration_in_red(browser, rrr, work):
    Q = rrr_towards_singularity(rrr)
    t = np.arange(len(Q), dtype=float) * 0.25  # regular, then near-singular, then singular
    scene = Scene(rrr)
    scene.animate(t, Q, singular=True)
    scene.save_html(work / "rrr.html")
    tab = browser.open(str(work / "rrr.html"))
    assert_clean(tab, len(scene.record.commands()))
    tab.seek(0.0)
    start = tab.shot("planar_3rrr_start")
    tab.seek(t[-1])
    end = tab.shot("planar_3rrr_singular")
    region = footprint(scene, Q[-1:])
    robot_px = changed(end, start) | red(end)
    n_red, n_red_start = int((red(end) & region).sum()), int((red(start) & region).sum())
    # at the singular end the robot is red; at the regular start only the world triad's x axis
    assert n_red > 1500 and n_red > 10 * n_red_start, (n_red, n_red_start, robot_px.sum())


def test_browser_served_viewer_matches_the_page_and_stops(browser, work):
    """`pkdyn view` serves the scene and its animation (replayed after the objects it colours);
    it shows what the exported page shows; SIGTERM stops it and its meshcat server."""
    args = ["view", "delta", "--trajectory", "adept", "--closest"]
    assert main([*args, "--html", str(work / "served_static.html")]) == 0
    n = len(page_commands((work / "served_static.html").read_text()))
    static_tab = browser.open(str(work / "served_static.html"))
    assert_clean(static_tab, n)
    static_tab.seek(0.2)
    static = static_tab.shot("delta_static")
    assert magenta(static).sum() > 100
    exe = str(Path(sys.executable).with_name("pkdyn"))
    proc = subprocess.Popen([exe, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline() if proc.stdout else ""
        url = re.search(r"(http://127\.0\.0\.1:\d+)/static/", line)
        assert url, f"no URL in {line!r}"
        tab = browser.open(url[0], ready=f"viewer.num_messages_received >= {n}")
        time.sleep(0.3)
        assert tab.eval("viewer.num_messages_received") == n  # the same scene, command for command
        host = url[1].removeprefix("http://")
        assert all(u.split("/")[2] == host for u in tab.requests()), tab.requests()
        # meshcat's server has no favicon: the browser's own request for it is the only 404
        favicon = "404 (Not Found)" if f"{url[1]}/favicon.ico" in tab.requests() else "-"
        assert [p for p in tab.problems() if favicon not in p] == [], tab.requests()
        tab.seek(0.2)
        diff = changed(tab.shot("delta_served"), static)
        assert diff.sum() < 0.001 * W * H, diff.sum()
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=20)
        assert proc.returncode == 143 and "viewer stopped" in out  # (EXIT_CODES: SIGTERM)
        with pytest.raises(OSError):
            urllib.request.urlopen(url[0] + "/static/", timeout=2)
    finally:
        if proc.poll() is None:  # SIGTERM first: pkdyn then stops meshcat's server too
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
