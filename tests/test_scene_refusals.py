"""Refusals found by review 46b: ``--solver dls`` with a problem it cannot solve (refused up
front, in words naming what dls solves), obstacle sizes and positions beyond
``scene.MAX_LENGTH`` in every format, scene files that hold no obstacles (URDF of visuals
only, MoveIt without shapes), a CSV named ``.npy``, a MoveIt shape count that disagrees with
the shapes given, and the ``scene`` of an ``AvoidCollisions`` goal in a goals file (inline
scenes refused in JSON terms, relative paths read from the goals file's folder)."""

from __future__ import annotations

import functools
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import cli_error, never, robot

import swarm_ik
from swarm_ik import goals as G
from swarm_ik.batch import read_targets_file
from swarm_ik.errors import InvalidArgumentError, SwarmIKError
from swarm_ik.scene import MAX_LENGTH, Box, Capsule, Cylinder, Mesh, Scene, Sphere

POSE = ["--pose", "0.5", "0", "0.3", "1", "0", "0", "0"]
TABLE = {"obstacles": [{"type": "Box", "name": "table", "size": [0.6, 0.6, 0.04],
                        "pose": [0.55, 0.0, -0.02]}]}  # fmt: skip


def _one_line(exc: BaseException, *words: str) -> str:
    msg = str(exc)
    assert isinstance(exc, SwarmIKError), type(exc)
    assert "\n" not in msg, msg
    for w in words:
        assert w in msg, (w, msg)
    return msg


def _load_refusal(path: Path, data: str | bytes, *words: str, read: Any = None) -> str:
    """Write ``data`` to ``path``, read it (``Scene.load`` by default) and check the
    refusal: one line naming the file and ``words``; returns the message."""
    if isinstance(data, bytes):
        path.write_bytes(data)
    else:
        path.write_text(data)
    with pytest.raises(InvalidArgumentError) as info:
        (read or Scene.load)(path)
    return _one_line(info.value, str(path), *words)


# ----------------------------------------------------------------------------- 1. dls
def _dls_refusal(problem: swarm_ik.IKProblem) -> str:
    with pytest.raises(InvalidArgumentError) as info:
        swarm_ik.solve(problem, "dls", max_evals=50)
    msg = _one_line(info.value, "solver 'dls' solves one exact Pose or Position goal", "'swarm'")
    assert "fitness_of_poses" not in msg and "single-pose" not in msg, msg
    return msg


def test_dls_refuses_a_collision_goal_saying_what_it_solves() -> None:
    r = robot("panda")
    problem = swarm_ik.IKProblem(
        r, r.fk(r.mid_q()), goals=[G.AvoidCollisions(Scene.from_dict(TABLE))]
    )
    assert "AvoidCollisions" in _dls_refusal(problem)


def test_dls_refuses_several_goals_and_tolerance_bands() -> None:
    r = swarm_ik.load_robot("panda", ee_frame=["panda_hand_tcp", "panda_link5"])
    poses = r.fk_all(r.mid_q() + 0.1)
    two = swarm_ik.IKProblem(
        r, goals=[G.Pose(r.frames[0], poses[0]), G.Pose(r.frames[1], poses[1])]
    )
    assert "2 goals (Pose(panda_hand_tcp), Pose(panda_link5))" in _dls_refusal(two)
    band = swarm_ik.IKProblem(
        r, goals=[G.Pose(r.frames[0], poses[0], tolerance=(0.01,) * 3 + (0.1,) * 3)]
    )
    assert "tolerance band" in _dls_refusal(band)
    axis = swarm_ik.IKProblem(r, goals=[G.Axis(r.frames[0], [0, 0, 1], [0, 0, -1])])
    assert "a Axis(panda_hand_tcp) goal, not a pose" in _dls_refusal(axis)


def test_dls_solves_one_pose_of_any_goal_frame_and_one_position_goal() -> None:
    """What dls takes it solves: a Pose goal of the second goal frame (it used to step along
    the first frame's Jacobian, never reaching it) and a Position goal of a goal list (it used
    to be refused as no pose target)."""
    r = swarm_ik.load_robot("panda", ee_frame=["panda_hand_tcp", "panda_link5"])
    poses = r.fk_all(r.mid_q() + 0.1)
    for goal in (G.Pose("panda_link5", poses[1]), G.Position("panda_hand_tcp", poses[0][:3, 3])):
        res = swarm_ik.solve(swarm_ik.IKProblem(r, goals=[goal]), "dls", max_evals=2000)
        assert res.success, (goal, res.position_error, res.rotation_error)


def test_cli_dls_with_a_scene_or_several_frames_is_refused_before_loading(
    tmp_path: Path, refused: Callable[..., str]
) -> None:
    scene = tmp_path / "table.json"
    scene.write_text(json.dumps(TABLE))
    line = refused("solve", "--robot", "panda", *POSE, "--scene", str(scene), "--solver", "dls")
    assert "--solver dls solves one exact Pose or Position goal" in line
    assert "--scene" in line and "default solver swarm" in line, line
    assert "fitness_of_poses" not in line
    line = refused("solve", "--robot", "baxter", "--frame", "left_gripper", "--frame",
                   "right_gripper", "--from-q", *["0.1"] * 14, "--solver", "dls")  # fmt: skip
    assert "--from-q with 2 --frame" in line and "--solver dls" in line, line
    line = refused("solve", "--robot", "panda", *POSE, "--scene", str(scene), "--compare", "dls")
    assert "--compare dls" in line and "--scene" in line, line


def test_cli_dls_with_a_goals_file_of_other_goals_is_refused_before_solving(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    goals = tmp_path / "g.json"
    goals.write_text(json.dumps([
        {"type": "Position", "frame": "panda_hand_tcp", "point": [0.4, 0, 0.3]},
        {"type": "Axis", "frame": "panda_hand_tcp", "axis": [0, 0, 1], "direction": [0, 0, -1]},
    ]))  # fmt: skip
    monkeypatch.setattr(swarm_ik, "solve", never)
    line = cli_error(capsys, "solve", "--robot", "panda", "--goals", str(goals), "--solver", "dls")
    assert "--solver dls" in line and str(goals) in line and "2 goals" in line, line


# --------------------------------------------------------------------------- 2. sizes
@pytest.mark.parametrize(
    "make, words",
    [
        (lambda: Sphere(1e308), ["sphere: radius", "at most 10000 m", "1e+308"]),
        (lambda: Sphere(0.1, (0.0, -2e4, 0.0)), ["sphere: center", "±10000 m", "-20000.0"]),
        (lambda: Box((1e300, 1.0, 1.0)), ["box: size", "at most 10000 m", "1e+300"]),
        (lambda: Box((1.0, 1.0, 1.0), (1e16, 0.0, 0.0)), ["box: pose position", "1e+16"]),
        (lambda: Capsule(0.1, 1e5), ["capsule: length", "100000"]),
        (lambda: Cylinder(1e5, 0.1), ["cylinder: radius", "100000"]),
    ],
)
def test_shapes_beyond_max_length_are_refused(make: Callable[[], object], words: list[str]) -> None:
    with pytest.raises(InvalidArgumentError) as info:
        make()
    _one_line(info.value, *words, "swarm_ik.scene.MAX_LENGTH")


def test_max_length_itself_is_accepted(tmp_path: Path) -> None:
    assert MAX_LENGTH == 1e4
    Box((MAX_LENGTH, MAX_LENGTH, 0.1), (MAX_LENGTH, -MAX_LENGTH, 0.0))
    Sphere(MAX_LENGTH, (0.0, 0.0, -MAX_LENGTH))
    mesh = tmp_path / "t.obj"
    mesh.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(InvalidArgumentError, match="mesh: pose position"):
        Mesh(str(mesh), (0.0, 2e4, 0.0))


_URDF = '<robot name="cell"><link name="base"><collision>{}<geometry>{}</geometry></collision></link></robot>'  # noqa: E501


@pytest.mark.parametrize(
    "name, text, words",
    [
        ("s.json", '{"obstacles": [{"type": "Sphere", "radius": 1e308}]}',
         ["obstacle 0 (Sphere)", "radius", "1e+308"]),
        ("s.json", '{"obstacles": [{"type": "Box", "size": [1, 1, 1], "pose": [0, 0, 1e16]}]}',
         ["obstacle 0 (Box)", "pose position", "1e+16"]),
        ("w.yml", "cuboid:\n  t: {dims: [1e300, 1, 1], pose: [0, 0, 0, 1, 0, 0, 0]}\n",
         ["cuboid 't'", "size", "1e+300"]),
        ("w.yml", "sphere:\n  s: {radius: 0.1, position: [0, 2e4, 0]}\n",
         ["sphere 's'", "center", "20000.0"]),
        ("m.scene", "s\n* a\n1\nsphere\n1e308\n0 0 0\n0 0 0 1\n0 0 0 0\n.\n",
         ["line 4", "object 'a'", "radius", "1e+308"]),
        ("m.scene", "s\n* a\n1\nbox\n1 1 1\n1e5 0 0\n0 0 0 1\n0 0 0 0\n.\n",
         ["object 'a'", "pose position", "100000.0"]),
        ("c.urdf", _URDF.format("", '<box size="1e300 1 1"/>'), ["base_0", "size", "1e+300"]),
        ("c.urdf", _URDF.format('<origin xyz="0 0 1e16"/>', '<sphere radius="1"/>'),
         ["base_0", "center", "1e+16"]),
    ],
)  # fmt: skip
def test_every_format_refuses_sizes_beyond_max_length(
    tmp_path: Path, name: str, text: str, words: list[str]
) -> None:
    read = functools.partial(Scene.load, mesh_dir=tmp_path)
    _load_refusal(tmp_path / name, text, *words, "MAX_LENGTH", read=read)


def test_cli_huge_sphere_is_one_line_before_solving(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    scene = tmp_path / "huge.json"
    scene.write_text('{"obstacles": [{"type": "Sphere", "radius": 1e308, "center": [0,0,0]}]}')
    monkeypatch.setattr(swarm_ik, "solve", never)
    line = cli_error(capsys, "solve", "--robot", "panda", *POSE, "--scene", str(scene))
    assert "huge.json" in line and "radius must be at most 10000 m" in line, line


# ---------------------------------------------------------------------- 3. empty scenes
@pytest.mark.parametrize(
    "name, text, words",
    [
        ("v.urdf", '<robot name="cell"><link name="table"><visual><geometry><box size="1 1 0.02"/>'
         "</geometry></visual></link></robot>",
         ["no link has a <collision> element", "no obstacles", "<visual> elements (1 here)"]),
        ("n.urdf", '<robot name="cell"><link name="table"/></robot>',
         ["no link has a <collision> element"]),
        ("e.scene", "s\n.\n", ["holds no obstacles", "no object"]),
        ("z.scene", "s\n* a\n0\n.\n", ["holds no obstacles", "its 1 object has no shapes"]),
        ("z2.scene", "s\n* a\n0 0 0\n0 0 0 1\n0\n0\n.\n", ["holds no obstacles"]),
        ("c.yml", "# nothing\n", ["holds no cuRobo world"]),
    ],
)  # fmt: skip
def test_files_without_obstacles_are_refused(
    tmp_path: Path, name: str, text: str, words: list[str]
) -> None:
    _load_refusal(tmp_path / name, text, *words)


@pytest.mark.parametrize("name", ["e.json", "e.yml"])
def test_an_empty_scene_saved_reads_back(tmp_path: Path, name: str) -> None:
    path = Scene().save(tmp_path / name)
    assert len(Scene.load(path)) == 0
    (tmp_path / "list.json").write_text("[]")
    assert len(Scene.load(tmp_path / "list.json")) == 0


# ----------------------------------------------------------------------- 4a. .npy files
@pytest.mark.parametrize(
    "name, data, words",
    [
        ("t.npy", b"x,y,z,qx,qy,qz,qw\n0.5,0.3,0.3,1,0,0,0\n",
         ["not a valid .npy file", "holds text", "named .csv"]),
        ("t.npz", b"x,y,z,qx,qy,qz,qw\n0.5,0.3,0.3,1,0,0,0\n", ["not a valid .npz file"]),
        ("t.npy", b"", ["not a valid .npy file", "empty"]),
        ("t.npy", bytes(range(200, 256)), ["not a valid .npy file", "starts with"]),
    ],
)  # fmt: skip
def test_a_file_named_npy_that_is_not_npy_says_so(
    tmp_path: Path, name: str, data: bytes, words: list[str]
) -> None:
    msg = _load_refusal(tmp_path / name, data, *words, read=read_targets_file)
    assert "object array" not in msg and "pickle" not in msg, msg


def test_real_npy_files_still_read_and_object_arrays_are_named(tmp_path: Path) -> None:
    np.save(tmp_path / "ok.npy", np.array([[0.5, 0.3, 0.3, 1.0, 0.0, 0.0, 0.0]]))
    assert read_targets_file(tmp_path / "ok.npy").shape == (1, 4, 4)
    np.save(tmp_path / "obj.npy", np.array([{"a": 1}], dtype=object), allow_pickle=True)
    with pytest.raises(InvalidArgumentError, match="object array of Python objects"):
        read_targets_file(tmp_path / "obj.npy")


def test_cli_path_with_a_csv_named_npy(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    poses = tmp_path / "csv_named.npy"
    poses.write_text("x,y,z,qx,qy,qz,qw\n0.5,0.3,0.3,1,0,0,0\n0.5,0.35,0.3,1,0,0,0\n")
    monkeypatch.setattr("swarm_ik.path.solve_path", never)
    line = cli_error(capsys, "path", "--robot", "ur5", "--poses", str(poses), "--out",
                     str(tmp_path / "q.csv"))  # fmt: skip
    assert "csv_named.npy" in line and "not a valid .npy file" in line, line


# ---------------------------------------------------------------- 4b. MoveIt counts
BOX = "box\n0.1 0.1 0.1\n0 0 0\n0 0 0 1\n0 0 0 0\n"


@pytest.mark.parametrize(
    "text, words",
    [
        ("sc\n* box\n0 0 0\n0 0 0 1\n2\n" + BOX + "0\n.\n",  # (the subframe count read next)
         ["line 11", "object 'box'", "2 shapes declared (line 5) but 1 given", "'0'"]),
        ("s\n* a\n2\n" + BOX + ".\n", ["2 shapes declared (line 3) but 1 given", "'.'"]),
        ("s\n* a\n2\n" + BOX + "* b\n1\n" + BOX + ".\n", ["object 'a'", "2 shapes", "'*'"]),
        ("s\n* a\n2\n" + BOX, ["2 shapes declared", "the file ends"]),
        ("s\n* a\n1\n.\n", ["1 shape declared (line 3) but 0 given", "'.'"]),
        ("s\n* a\n1\n" + BOX + BOX + ".\n",
         ["line 9", "1 shape declared (line 3), but another shape follows: 'box'"]),
        ("s\n* a\n0 0 0\n0 0 0 1\n1\n" + BOX + BOX + "0\n.\n",
         ["line 11", "1 shape declared (line 5), but another shape follows"]),
    ],
)  # fmt: skip
def test_a_moveit_shape_count_that_disagrees_is_named(
    tmp_path: Path, text: str, words: list[str]
) -> None:
    msg = _load_refusal(tmp_path / "count.scene", text, *words)
    assert "unknown shape type" not in msg and "unknown marker" not in msg, msg


# ------------------------------------------------------------ 4c/d. goals files' scenes
@pytest.mark.parametrize(
    "scene, got", [({"obstacles": []}, "got an object"), (TABLE["obstacles"], "got a list"),
                   (3, "got 3")],
)  # fmt: skip
def test_an_inline_scene_in_a_goals_file_is_refused_in_json_terms(
    tmp_path: Path, scene: object, got: str
) -> None:
    path = tmp_path / "g.json"
    path.write_text(json.dumps([{"type": "AvoidCollisions", "scene": scene}]))
    with pytest.raises(InvalidArgumentError) as info:
        G.load_goals(path)
    msg = _one_line(info.value, '"scene" must be a scene file\'s path', "null", got)
    assert "from_dict" not in msg and "Scene.load" not in msg, msg


def test_a_relative_scene_path_is_read_from_the_goals_files_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    folder = tmp_path / "cell"
    (folder / "scenes").mkdir(parents=True)
    (folder / "scenes" / "table.json").write_text(json.dumps(TABLE))
    goals = folder / "goals.json"
    goals.write_text(json.dumps({"goals": [
        {"type": "Position", "frame": "panda_hand_tcp", "point": [0.4, 0, 0.3]},
        {"type": "AvoidCollisions", "scene": "scenes/table.json"},
    ]}))  # fmt: skip
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    loaded = G.load_goals(goals)
    assert loaded[1].scene.names == ("table",)
    # an absolute path is kept; a parsed list reads a relative one from the working directory
    data = json.loads(goals.read_text())["goals"]
    data[1]["scene"] = str(folder / "scenes" / "table.json")
    assert G.load_goals(data)[1].scene.names == ("table",)
    data[1]["scene"] = "scenes/table.json"
    with pytest.raises(SwarmIKError, match="not found"):
        G.load_goals(data)
    monkeypatch.chdir(folder)
    assert G.load_goals(data)[1].scene.names == ("table",)


def test_a_mesh_path_naming_a_folder_is_called_a_folder(tmp_path: Path) -> None:
    from swarm_ik.errors import InvalidArgumentError
    from swarm_ik.scene import Scene

    path = tmp_path / "s.json"
    path.write_text(json.dumps({"obstacles": [{"type": "Mesh", "path": str(tmp_path)}]}))
    with pytest.raises(InvalidArgumentError, match="is a folder, not a mesh file"):
        Scene.load(path)


def test_a_moveit_box_with_two_sizes_names_its_own_line(tmp_path: Path) -> None:
    """A box's sizes are one line, as MoveIt writes them: two numbers are refused on their
    own line (the next line's position was taken as the third, and that line blamed)."""
    text = "x\n* a\n0 0 0\n0 0 0 1\n1\nbox\n0.1 0.2\n0 0 0\n0 0 0 1\n0 0 0 0\n0\n.\n"
    msg = _load_refusal(tmp_path / "b.scene", text, "line 7", "box size must be 3 numbers")
    assert "line 8" not in msg, msg


def test_a_rotation_given_with_few_digits_is_refused_with_how_far_off_and_what_to_do() -> None:
    pose = [[0.866, -0.5, 0, 0], [0.5, 0.866, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
    with pytest.raises(InvalidArgumentError) as info:
        Box([0.1, 0.1, 0.1], pose)
    _one_line(info.value, "off by 4e-05", "more digits", "quaternion")
    c, s = np.cos(np.pi / 6), np.sin(np.pi / 6)
    Box([0.1, 0.1, 0.1], [[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
