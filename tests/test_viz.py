"""The viewer: lazy import, geometry, convergence traces, scenes, CLI, and the static HTML
export drawn by a real headless browser."""

from __future__ import annotations

import base64
import collections
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import pytest

import swarm_ik
from swarm_ik import cli

viz = pytest.importorskip("swarm_ik.viz")
pytest.importorskip("meshcat", reason="meshcat (the [viz] extra) is not installed")

Q_YUMI = np.array([0.3, -0.8, 0.4, 0.6, -0.5, 1.2, 0.7])
BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


# ----------------------------------------------------------------------------- helpers
def html_commands(html: str) -> list[dict[str, Any]]:
    """The meshcat commands embedded in a static export (base64 msgpack blobs)."""
    import umsgpack

    blobs = re.findall(r'base64,([A-Za-z0-9+/=]+)"', html)
    return [umsgpack.unpackb(base64.b64decode(b)) for b in blobs]


def find_browser() -> str | None:
    for name in BROWSERS:
        path = shutil.which(name)
        if path:
            return path
    return None


def screenshot(html_path: Path, png_path: Path, budget_ms: int = 4000) -> np.ndarray:
    """Load a page in headless Chromium and return its screenshot as an (H, W, 3) array."""
    from PIL import Image

    browser = find_browser()
    if browser is None:
        pytest.skip("no Chromium found (install Debian's with `apt-get install -y chromium`)")
    profile = png_path.parent / f"profile-{png_path.stem}"
    cmd = [
        browser,
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        f"--user-data-dir={profile}",
        f"--screenshot={png_path}",
        "--window-size=800,600",
        f"--virtual-time-budget={budget_ms}",
        html_path.resolve().as_uri(),
    ]
    proc = subprocess.run(
        cmd, capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL
    )
    assert png_path.is_file(), (
        f"Chromium wrote no screenshot (rc {proc.returncode}): {proc.stderr[-2000:]}"
    )
    return np.asarray(Image.open(png_path).convert("RGB"), dtype=np.int16)


@pytest.fixture(scope="module")
def yumi() -> swarm_ik.RobotModel:
    return swarm_ik.load_robot("yumi_left")


@pytest.fixture(scope="module")
def panda() -> swarm_ik.RobotModel:
    return swarm_ik.load_robot("panda")


@pytest.fixture(autouse=True)
def _no_wait(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("SWARM_IK_NO_WAIT", "1")


# ------------------------------------------------------------------------- lazy import
def test_import_swarm_ik_does_not_import_meshcat() -> None:
    code = (
        "import sys, swarm_ik, swarm_ik.viz, swarm_ik.cli; "
        "assert 'meshcat' not in sys.modules, sorted(m for m in sys.modules if 'meshcat' in m)"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr


def test_missing_meshcat_names_the_extra(monkeypatch: pytest.MonkeyPatch, capsys: Any) -> None:
    monkeypatch.setitem(sys.modules, "meshcat", None)  # makes `import meshcat` fail
    with pytest.raises(viz.VizUnavailableError, match=r"pip install swarm_ik\[viz\]"):
        viz.require_meshcat()
    assert isinstance(viz.VizUnavailableError("x"), ImportError)
    rc = cli.main(["show", "--robot", "yumi_left", "--q", *map(str, Q_YUMI)])
    assert rc == 2
    assert "swarm_ik[viz]" in capsys.readouterr().err


# ---------------------------------------------------------------------------- geometry
def test_full_configuration_matches_chain_fk(panda: swarm_ik.RobotModel) -> None:
    """The full model (gripper fingers locked) puts the tool where the chain's FK says."""
    assert panda.locked_joints, "panda should have locked finger joints"
    q = panda.random_q(np.random.default_rng(0))
    full = viz.full_configuration(panda, q)
    assert full.shape == (panda.full_model.nq,)
    data = panda.full_model.createData()
    pin.framesForwardKinematics(panda.full_model, data, full)
    fid = panda.full_model.getFrameId(panda.ee_frame)
    np.testing.assert_allclose(data.oMf[fid].homogeneous, panda.fk(q), atol=1e-10)


def test_visual_model_resolves_package_meshes(panda: swarm_ik.RobotModel) -> None:
    geom = viz.visual_model(panda)
    paths = [g.meshPath for g in geom.geometryObjects if g.meshPath.endswith(".dae")]
    assert len(paths) >= 8
    assert all(Path(p).is_file() for p in paths)


def test_missing_mesh_is_a_clear_error(tmp_path: Path) -> None:
    urdf = tmp_path / "arm.urdf"
    urdf.write_text("""<?xml version="1.0"?>
<robot name="arm"><link name="a"/><link name="b">
<visual><geometry><mesh filename="package://nowhere_pkg/meshes/b.stl"/></geometry></visual></link>
<joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>""")
    robot = swarm_ik.load_robot(urdf)
    with pytest.raises(swarm_ik.RobotModelError, match="b.stl"):
        viz.visual_model(robot)


# ------------------------------------------------------------------------------ traces
@pytest.mark.parametrize("solver", ["pso", "hlfoa", "dls", "swarm"])
def test_trace_is_the_best_so_far_per_iteration(yumi: swarm_ik.RobotModel, solver: str) -> None:
    problem = swarm_ik.IKProblem.from_q(yumi, Q_YUMI)
    plain = swarm_ik.solve(problem, solver, seed=3, max_evals=2000)
    res, trace = viz.solve_traced(problem, solver, seed=3, max_evals=2000)
    # recording does not change the answer
    np.testing.assert_array_equal(res.q, plain.q)
    np.testing.assert_array_equal(res.history, plain.history)
    assert trace.q.shape == (len(trace), yumi.nq)
    assert len(trace) >= len(res.history) >= 1
    np.testing.assert_array_equal(trace.fitness[: len(res.history)], res.history)
    # each frame's configuration really has the fitness recorded for its iteration
    f = problem.fitness(trace.q)
    finite = np.isfinite(trace.fitness)
    np.testing.assert_allclose(f[finite], trace.fitness[finite], rtol=1e-7, atol=1e-12)
    assert np.all(np.diff(trace.fitness[finite]) <= 0)
    np.testing.assert_allclose(trace.q[-1], res.q)
    assert trace.improvements >= 1


def test_trace_subsample_keeps_ends(yumi: swarm_ik.RobotModel) -> None:
    problem = swarm_ik.IKProblem.from_q(yumi, Q_YUMI)
    _, trace = viz.solve_traced(problem, "hlfoa", seed=0, max_evals=5000)
    assert len(trace) > 20
    short = trace.subsample(10)
    assert len(short) == 10
    np.testing.assert_array_equal(short.q[0], trace.q[0])
    np.testing.assert_array_equal(short.q[-1], trace.q[-1])
    with pytest.raises(swarm_ik.InvalidArgumentError):
        trace.subsample(1)


def test_solve_traced_full_budget_without_stop_on_success(yumi: swarm_ik.RobotModel) -> None:
    """The recording does not rely on the success check: the whole budget is traced too."""
    problem = swarm_ik.IKProblem.from_q(yumi, Q_YUMI)
    plain = swarm_ik.solve(problem, "pso", seed=1, max_evals=1200, stop_on_success=False)
    res, trace = viz.solve_traced(problem, "pso", seed=1, max_evals=1200, stop_on_success=False)
    assert res.n_evals == plain.n_evals == 1200
    np.testing.assert_array_equal(res.q, plain.q)
    np.testing.assert_array_equal(trace.fitness[: len(res.history)], res.history)
    finite = np.isfinite(trace.fitness)
    np.testing.assert_allclose(problem.fitness(trace.q)[finite], trace.fitness[finite], rtol=1e-7)


def test_trace_recorder_keeps_only_improvements() -> None:
    rec = viz.TraceRecorder()
    for q, f in ((0.0, 3.0), (1.0, 4.0), (2.0, 2.0), (3.0, np.nan), (4.0, 2.0), (5.0, 1.0)):
        rec([q], f)
    assert rec.fitness == [3.0, 2.0, 1.0]
    assert [float(q[0]) for q in rec.q] == [0.0, 2.0, 5.0]
    rec.offer(np.array([[7.0], [8.0]]), np.array([0.5, 0.2]))
    assert rec.fitness[-1] == 0.2 and float(rec.q[-1][0]) == 8.0


# ------------------------------------------------------------------------------ scenes
def test_show_result_scene_content(yumi: swarm_ik.RobotModel) -> None:
    """Every visual is placed where Pinocchio puts it; target, reached, ghost and animation
    are in the export."""
    problem = swarm_ik.IKProblem.from_q(yumi, Q_YUMI)
    res, trace = viz.solve_traced(problem, "pso", seed=0, max_evals=1500)
    dls = swarm_ik.solve(problem, "dls", seed=0)
    with viz.show_result(problem, res, trace=trace, compare=dls) as scene:
        assert scene.url.startswith("http://127.0.0.1:")
        cmds = html_commands(scene.to_html())
    transforms = {
        c["path"]: np.array(c["matrix"]).reshape(4, 4).T
        for c in cmds
        if c["type"] == "set_transform"
    }
    objects = {c["path"] for c in cmds if c["type"] == "set_object"}
    geom = viz.visual_model(yumi)
    data, gdata = yumi.full_model.createData(), pin.GeometryData(geom)
    for name, q in (("robot", res.q), ("ghost", dls.q)):
        pin.forwardKinematics(yumi.full_model, data, viz.full_configuration(yumi, q))
        pin.updateGeometryPlacements(yumi.full_model, data, geom, gdata)
        for k, g in enumerate(geom.geometryObjects):
            node = f"/meshcat/swarm_ik/{name}/visuals/{g.name}"
            assert f"{node}/shape" in objects
            np.testing.assert_allclose(transforms[node], gdata.oMg[k].homogeneous, atol=1e-9)
    np.testing.assert_allclose(transforms["/meshcat/swarm_ik/target"], problem.target)
    np.testing.assert_allclose(transforms["/meshcat/swarm_ik/reached"], yumi.fk(res.q))
    assert "/meshcat/swarm_ik/label/shape" in objects
    anim = [c for c in cmds if c["type"] == "set_animation"]
    assert len(anim) == 1
    clips = {a["path"]: a["clip"] for a in anim[0]["animations"]}
    reached_clip = clips["/meshcat/swarm_ik/reached"]
    times = [k["time"] for k in reached_clip["tracks"][0]["keys"]]
    assert len(times) == min(len(trace), 200) + 1  # one key per frame + the final hold
    first = np.array(reached_clip["tracks"][0]["keys"][0]["value"])
    np.testing.assert_allclose(first, yumi.fk(trace.q[0])[:3, 3])


def test_show_solutions_side_by_side_and_steps(yumi: swarm_ik.RobotModel) -> None:
    problem = swarm_ik.IKProblem.from_q(yumi, Q_YUMI)
    sols = viz.several_solutions(problem, 3, min_distance=0.5)
    assert 1 <= len(sols) <= 3 and all(s.success for s in sols)
    with viz.show_solutions(problem, sols, layout="side") as scene:
        cmds = html_commands(scene.to_html())
    paths = {c["path"] for c in cmds}
    for k in range(len(sols)):
        assert f"/meshcat/swarm_ik/solutions/{k}/robot" in paths
    with viz.show_solutions(problem, sols, layout="steps") as scene:
        cmds = html_commands(scene.to_html())
    assert sum(c["type"] == "set_animation" for c in cmds) == 1
    with pytest.raises(swarm_ik.UnknownNameError, match="side, steps"):
        viz.show_solutions(problem, sols, layout="grid")


def test_export_needs_no_server_and_replays_in_order(yumi: swarm_ik.RobotModel) -> None:
    scene = viz.Scene()
    scene.add_robot(yumi, Q_YUMI)
    scene.add_triad("t", np.eye(4))
    scene.add_triad("t", yumi.fk(Q_YUMI))  # replaces the first one
    html = scene.to_html()
    assert not scene.is_live  # writing the page started no meshcat server
    cmds = html_commands(html)
    tfs = [c for c in cmds if c["type"] == "set_transform" and c["path"] == "/meshcat/swarm_ik/t"]
    assert len(tfs) == 1
    np.testing.assert_allclose(np.array(tfs[0]["matrix"]).reshape(4, 4).T, yumi.fk(Q_YUMI))
    scene.node("t").delete()
    assert not any(c.get("path", "").startswith("/meshcat/swarm_ik/t") for c in scene.commands)
    scene.close()


def test_several_robots_share_their_meshes(panda: swarm_ik.RobotModel, tmp_path: Path) -> None:
    """Three Pandas in one page cost little more than one: each mesh file is embedded once."""
    q = np.array([0.3, -0.5, 0.2, -2.0, 0.1, 1.6, 0.7])
    with viz.show_pose(panda, q) as one:
        size_one = one.save_html(tmp_path / "one.html").stat().st_size
    with viz.show_configurations(panda, [q, q + 0.2, q - 0.2]) as three:
        path = three.save_html(tmp_path / "three.html")
    size_three = path.stat().st_size
    assert size_three < 1.2 * size_one, (size_one, size_three)
    cmds = html_commands(path.read_text())
    shared = [c for c in cmds if c["type"] == viz.export.SHARED_COMMAND]
    assert len(shared) == 1
    store = shared[0]["data"]
    refs = [
        c["object"]["object"]["data"]
        for c in cmds
        if c["type"] == "set_object"
        and c["object"].get("object", {}).get("type", "") == "_meshfile_object"
    ]
    assert len(refs) >= 3 * 8  # every Panda draws its meshes ...
    assert all(r.startswith(viz.export.SHARED_PREFIX) for r in refs)
    counts = collections.Counter(refs)  # ... from one copy of each (the fingers share one)
    assert all(c % 3 == 0 for c in counts.values()) and len(counts) <= len(refs) // 3
    assert set(r[len(viz.export.SHARED_PREFIX) :] for r in refs) <= set(store)


def test_save_html_refuses_bad_paths(yumi: swarm_ik.RobotModel, tmp_path: Path) -> None:
    with viz.show_pose(yumi, Q_YUMI) as scene:
        with pytest.raises(swarm_ik.InvalidArgumentError, match="does not exist"):
            scene.save_html(tmp_path / "missing" / "a.html")
        with pytest.raises(swarm_ik.InvalidArgumentError, match="is a folder"):
            scene.save_html(tmp_path)
        with pytest.raises(swarm_ik.InvalidArgumentError, match="valid: .html, .htm"):
            scene.save_html(tmp_path / "a.png")


# ---------------------------------------------------------------------------------- CLI
def test_cli_solve_html_animate_compare(tmp_path: Path, capsys: Any) -> None:
    out = tmp_path / "scene.html"
    rc = cli.main(
        [
            "solve",
            "--robot",
            "yumi_left",
            "--from-q",
            *map(str, Q_YUMI),
            "--solver",
            "pso",
            "--max-evals",
            "1500",
            "--animate",
            "--compare",
            "dls",
            "--html",
            str(out),
        ]
    )
    text = capsys.readouterr().out
    assert rc in (0, 1)
    assert "compare dls: reached" in text
    assert f"wrote {out}" in text
    assert "meshcat viewer" not in text  # --html alone: no live viewer
    cmds = html_commands(out.read_text())
    assert any(c["type"] == "set_animation" for c in cmds)
    assert any(c.get("path", "").startswith("/meshcat/swarm_ik/ghost/") for c in cmds)


def test_cli_animate_without_html_or_show_does_not_block(capsys: Any) -> None:
    """No viewer is started (it would wait for Ctrl-C): a note on stderr, the solve's code."""
    rc = cli.main(
        ["solve", "--robot", "yumi_left", "--from-q", *map(str, Q_YUMI), "--animate"]
        + ["--compare", "dls", "--json"]
    )
    cap = capsys.readouterr()
    assert rc == 0
    assert json.loads(cap.out)["success"] is True
    assert "add --html FILE" in cap.err and "--show" in cap.err
    assert "meshcat viewer" not in cap.err + cap.out


def test_cli_html_path_checked_before_drawing(tmp_path: Path, capsys: Any) -> None:
    bad = tmp_path / "missing" / "scene.html"
    args = ["--robot", "yumi_left", "--from-q", *map(str, Q_YUMI), "--html", str(bad)]
    assert cli.main(["solve", *args, "--animate"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "does not exist" in err
    assert cli.main(["show", *args]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_cli_show_prints_url_and_keeps_json_clean(capsys: Any) -> None:
    rc = cli.main(
        ["solve", "--robot", "yumi_left", "--from-q", *map(str, Q_YUMI), "--show", "--json"]
    )
    cap = capsys.readouterr()
    assert rc == 0
    assert json.loads(cap.out)["success"] is True  # stdout is the JSON object alone
    assert re.search(r"meshcat viewer: http://127\.0\.0\.1:\d+/static/", cap.err)


def test_cli_show_command(tmp_path: Path, capsys: Any) -> None:
    out = tmp_path / "two.html"
    q2 = Q_YUMI + 0.3
    rc = cli.main(
        [
            "show",
            "--robot",
            "yumi_left",
            "--q",
            *map(str, Q_YUMI),
            "--q",
            *map(str, q2),
            "--html",
            str(out),
        ]
    )
    assert rc == 0 and out.is_file()
    rc = cli.main(
        ["show", "--robot", "yumi_left", "--from-q", *map(str, Q_YUMI), "--solutions", "2"]
    )
    text = capsys.readouterr().out
    assert rc == 0
    assert "#1 " in text and "meshcat viewer: http://127.0.0.1:" in text
    assert cli.main(["show", "--robot", "yumi_left"]) == 2  # nothing to show
    assert cli.main(["show", "--robot", "yumi_left", "--q", "0.1", "0.2"]) == 2  # wrong length
    assert "7 values" in capsys.readouterr().err


# ------------------------------------------------------------------- headless browser
def test_static_html_draws_the_robot_in_a_browser(
    yumi: swarm_ik.RobotModel, tmp_path: Path
) -> None:
    """The exported page, opened from a file with no server, draws the robot mid-image: the
    robot's pixels are what differs from the same page with the robot hidden."""
    if find_browser() is None:
        pytest.skip("no Chromium found (install Debian's with `apt-get install -y chromium`)")
    problem = swarm_ik.IKProblem.from_q(yumi, Q_YUMI)
    res = swarm_ik.solve(problem, seed=0)
    with viz.show_result(problem, res) as scene:
        with_robot = scene.save_html(tmp_path / "with.html")
        scene.visualizer[f"{viz.ROOT}/robot"].set_property("visible", False)
        without = scene.save_html(tmp_path / "without.html")
    img = screenshot(with_robot, tmp_path / "with.png")
    ref = screenshot(without, tmp_path / "without.png")
    assert img.shape == (600, 800, 3)
    mid = (slice(150, 450), slice(200, 600))
    # the page is not blank: the middle has far more than one colour
    assert len(np.unique(img[mid].reshape(-1, 3), axis=0)) > 50
    diff = np.abs(img - ref).max(axis=-1) > 40
    assert diff[mid].sum() > 2000, f"only {diff[mid].sum()} robot pixels in the middle"
    ys, xs = np.nonzero(diff)
    assert 150 < ys.mean() < 450 and 200 < xs.mean() < 600  # drawn in the middle
    if os.environ.get("SWARM_IK_KEEP_SCREENSHOTS"):
        shutil.copy(tmp_path / "with.png", os.environ["SWARM_IK_KEEP_SCREENSHOTS"])


def test_collision_view_draws_obstacles_and_contacts(tmp_path: Path) -> None:
    """Obstacles are drawn, the one in contact and the robot bodies touching it in red."""
    pytest.importorskip("meshcat")
    from swarm_ik.scene import Box, Scene, Sphere
    from swarm_ik.viz.obstacles import CONTACT_RGBA

    r = swarm_ik.load_robot("panda")
    q = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.785])
    obstacles = Scene([Box([0.6, 0.6, 0.04], [0.55, 0.0, -0.02]), Sphere(0.08, r.fk(q)[:3, 3])])
    report = r.collision_model().check(q, obstacles)
    assert report.pairs_in_contact and not report.collision_free
    scene = viz.show_collision(r, q, obstacles, report)
    from swarm_ik.viz.geometry import rgb_int

    red = rgb_int(CONTACT_RGBA)
    colour = {}
    for c in scene.commands:
        mats = c.get("object", {}).get("materials") if c["type"] == "set_object" else None
        if mats:
            colour[c["path"]] = mats[0].get("color")
    base = "/meshcat/swarm_ik/"
    assert colour[base + "obstacles/sphere1/part0"] == red  # in contact with the hand
    assert colour[base + "obstacles/box0/part0"] != red  # the table is clear
    assert any(p.startswith(base + "contacts/") and "hand" in p for p in colour)
    path = scene.save_html(tmp_path / "contacts.html")
    assert path.stat().st_size > 0


@pytest.mark.parametrize("bad", [np.zeros((3, 3)), "abc", np.full((4, 4), np.nan)])
def test_show_pose_refuses_a_bad_target_and_takes_seven_numbers(bad: Any) -> None:
    """``viz.show_pose(target=...)`` read any array: a 3×3 or 7 numbers raised IndexError, a
    NaN pose was drawn; it takes what ``IKProblem`` takes, and refuses the rest in one line."""
    from swarm_ik import viz
    from swarm_ik.errors import InvalidTargetError

    robot = swarm_ik.load_robot("panda")
    q = robot.mid_q()
    seven = [0.3, 0.0, 0.4, 0.0, 0.0, 0.0, 1.0]
    with pytest.raises(InvalidTargetError, match="target"):
        viz.show_pose(robot, q, target=bad)
    with pytest.raises(InvalidTargetError, match="target"):
        viz.show_configurations(robot, [q, q], target=bad)  # (the side layout's own drawing)
    viz.show_pose(robot, q, target=seven)
    viz.show_configurations(robot, [q, q], target=seven)
    skewed = robot.fk(q)
    skewed[0, :3] *= 1.01  # (a problem of a loose orth_tol is drawn as it was given)
    problem = swarm_ik.IKProblem(robot, skewed, orth_tol=0.1)
    viz.show_result(problem, swarm_ik.solve(problem, max_evals=100))


def test_show_q_outside_the_limits_is_drawn_with_a_note(tmp_path: Path, capsys: Any) -> None:
    """``show --q`` outside the limits was drawn with no word (``solve --q0`` warns and
    clips): one note names the joints, and the configuration is drawn as given."""
    q = list(map(str, Q_YUMI))
    q[0] = "9"
    assert (
        cli.main(["show", "--robot", "yumi_left", "--q", *q, "--html", str(tmp_path / "s.html")])
        == 0
    )
    err = capsys.readouterr().err
    assert (  # (9 rad: beyond a full turn, so degrees are hinted, review 136)
        "--q #1 lies outside the joint limits at ['yumi_joint_1'] (radians and metres are "
        "expected: degrees?); drawn as given" in err
    )
