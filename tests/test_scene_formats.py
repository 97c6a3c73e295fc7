"""Scene files people already have: swarm_ik JSON, cuRobo world YAML, MoveIt ``.scene`` (both
layouts) and URDFs of fixed obstacles, read by ``Scene.load``; their round trips through
JSON (and cuRobo YAML), what they mean (poses, sizes), and every refusal: one line, a
swarm_ik error."""

from __future__ import annotations

import json
import math
import random
import re
import sys
from pathlib import Path

import numpy as np
import pytest

from swarm_ik import scene as S
from swarm_ik.errors import InvalidArgumentError, SwarmIKError, UnknownNameError
from swarm_ik.goals import AvoidCollisions
from swarm_ik.scene import (
    Box,
    Capsule,
    Cylinder,
    Mesh,
    Scene,
    SceneDependencyError,
    SceneFileNotFoundError,
    Sphere,
    as_scene,
)

DATA = Path(__file__).parent / "data" / "scenes"
FIXTURES = ["table.json", "world.yml", "old_format.scene", "new_format.scene", "obstacles.urdf"]
DOCS = Path(__file__).parent.parent / "docs" / "scenes.md"


def _load(name: str, tmp_path: Path) -> Scene:
    return Scene.load(DATA / name, mesh_dir=tmp_path / "meshes")


def _pose(o) -> np.ndarray:
    return np.array(o.pose, dtype=float)


def _rot_z(deg: float) -> np.ndarray:
    a = math.radians(deg)
    return np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])


def _same_obstacles(a: Scene, b: Scene, tol: float = 1e-12) -> None:
    """Same names, shape classes, sizes and poses (to ``tol``), whatever the order."""
    assert sorted(a.names) == sorted(b.names)
    by_name = dict(zip(b.names, b, strict=True))
    for name, o in zip(a.names, a, strict=True):
        p = by_name[name]
        assert type(o) is type(p), name
        np.testing.assert_allclose(_pose(o), _pose(p), rtol=0, atol=tol, err_msg=name)
        for f in ("radius", "length", "size", "scale", "path"):
            if hasattr(o, f):
                va, vb = getattr(o, f), getattr(p, f)
                if isinstance(va, str):
                    assert va == vb, (name, f)
                else:
                    np.testing.assert_allclose(va, vb, rtol=0, atol=tol, err_msg=f"{name}.{f}")


# --------------------------------------------------------------------------- round trips
@pytest.mark.parametrize("name", FIXTURES)
def test_every_format_round_trips_through_json(name: str, tmp_path: Path) -> None:
    scene = _load(name, tmp_path)
    assert len(scene) >= 3
    path = scene.save(tmp_path / "scene.json")
    back = Scene.load(path)
    assert back == scene  # same shapes, names, sizes and poses, bit for bit
    _same_obstacles(scene, back)
    assert Scene.from_json(path) == scene
    written = json.loads(path.read_text())
    assert {o["type"] for o in written["obstacles"]} <= {"Box", "Sphere", "Capsule", "Cylinder",
                                                        "Mesh"}  # fmt: skip


@pytest.mark.parametrize("name", FIXTURES)
def test_every_format_round_trips_through_curobo_yaml(name: str, tmp_path: Path) -> None:
    scene = _load(name, tmp_path)
    path = scene.save(tmp_path / "world.yaml")
    back = Scene.load(path)
    _same_obstacles(scene, back)  # grouped by type and named: not == but the same obstacles
    again = back.save(tmp_path / "again.yml")
    _same_obstacles(back, Scene.load(again))  # stable: no drift on a second trip


def test_json_reads_the_lowercase_type_names_and_writes_the_class_names(tmp_path: Path) -> None:
    old = {"obstacles": [{"type": "box", "size": [1, 1, 1]}, {"type": "sphere", "radius": 1}]}
    new = {"obstacles": [{"type": "Box", "size": [1, 1, 1]}, {"type": "Sphere", "radius": 1}]}
    assert Scene.from_dict(old) == Scene.from_dict(new)
    assert [o["type"] for o in Scene.from_dict(old).to_dict()["obstacles"]] == ["Box", "Sphere"]


# --------------------------------------------------------------------- what files mean
def test_json_fixture(tmp_path: Path) -> None:
    s = _load("table.json", tmp_path)
    assert s.names == ("table", "ball", "post", "legacy_lowercase", "block")
    table, ball, post, leg, block = s
    assert isinstance(table, Box) and table.size == (1.0, 0.6, 0.02)
    np.testing.assert_allclose(_pose(table)[:3, :3], _rot_z(90), atol=1e-15)
    assert isinstance(ball, Sphere) and ball.center == (0.4, 0.0, 0.3)
    assert isinstance(post, Capsule) and _pose(post)[:3, 3].tolist() == [0.2, 0.3, 0.5]
    assert isinstance(leg, Cylinder) and (leg.radius, leg.length) == (0.03, 0.5)
    assert isinstance(block, Mesh) and block.path == str((DATA / "block.obj").resolve())
    assert block.scale == (1.0, 2.0, 1.0)


def test_curobo_fixture_poses_are_w_first_and_capsules_are_base_to_tip(tmp_path: Path) -> None:
    s = _load("world.yml", tmp_path)
    assert s.names == ("table", "ball", "ball2", "post", "rail", "leg", "block")
    o = dict(zip(s.names, s, strict=True))
    # [x y z qw qx qy qz] = 90 degrees about z (w first)
    np.testing.assert_allclose(_pose(o["table"])[:3, :3], _rot_z(90), atol=1e-15)
    assert o["table"].size == (1.0, 0.6, 0.02)
    assert o["ball"].center == (0.4, 0.0, 0.3) and o["ball2"].radius == 0.1  # "1e-1" a number
    # base (0,0,0.1), tip (0,0,0.5) in the frame at (0.2,0.3,0.2): 0.4 long, centred at z 0.5
    assert o["post"].length == pytest.approx(0.4, abs=1e-15)
    expected = np.eye(4)
    expected[:3, 3] = [0.2, 0.3, 0.5]
    np.testing.assert_allclose(_pose(o["post"]), expected, atol=1e-15)
    rail = _pose(o["rail"])  # base (-0.2,0,0) -> tip (0.2,0,0): the local z axis along world x
    np.testing.assert_allclose(rail[:3, :3] @ [0, 0, 1], [1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(rail[:3, 3], [0.0, -0.3, 0.6], atol=1e-15)
    assert o["rail"].length == pytest.approx(0.4, abs=1e-15)
    assert (o["leg"].radius, o["leg"].length) == (0.03, 0.5)
    assert o["block"].scale == (1.0, 2.0, 1.0)
    assert o["block"].path == str((DATA / "block.obj").resolve())


def test_moveit_old_layout_has_world_shape_poses(tmp_path: Path) -> None:
    s = _load("old_format.scene", tmp_path)
    assert s.names == ("table#0", "table#1", "ball")  # a 2-shape object: one obstacle per shape
    box, cyl, ball = s
    assert isinstance(box, Box) and box.size == (0.77, 0.39, 0.05)
    assert _pose(box)[:3, 3].tolist() == [0.4, 0.0, 0.025]
    assert isinstance(cyl, Cylinder) and (cyl.radius, cyl.length) == (0.02, 0.3)
    np.testing.assert_allclose(_pose(cyl)[:3, :3], _rot_z(90), atol=1e-15)  # qx qy qz qw
    assert isinstance(ball, Sphere) and ball.center == (0.3, -0.2, 0.4)


def test_moveit_new_layout_composes_object_and_shape_poses(tmp_path: Path) -> None:
    s = _load("new_format.scene", tmp_path)
    assert s.names == ("shelf#0", "shelf#1", "wedge")  # the subframe is read and dropped
    top, bottom, wedge = s
    # object at (0.5, 0.1, 0.2) turned 90 degrees about z; the boards 0.1 above and below
    for board, z in ((top, 0.3), (bottom, 0.1)):
        np.testing.assert_allclose(_pose(board)[:3, 3], [0.5, 0.1, z], atol=1e-15)
        np.testing.assert_allclose(_pose(board)[:3, :3], _rot_z(90), atol=1e-15)
    # the inline mesh became an OBJ file in mesh_dir, named by its content
    assert isinstance(wedge, Mesh) and Path(wedge.path).parent == (tmp_path / "meshes").resolve()
    assert Path(wedge.path).name.startswith("moveit-") and wedge.path.endswith(".obj")
    lo, hi = Scene([wedge]).bounds()
    np.testing.assert_allclose(lo, [-0.3, 0.2, 0.1], atol=1e-12)
    np.testing.assert_allclose(hi, [-0.2, 0.3, 0.2], atol=1e-12)
    again = _load("new_format.scene", tmp_path)  # the same content: the same file, reused
    assert again[2].path == wedge.path


def test_urdf_obstacles_are_at_the_zero_configuration(tmp_path: Path) -> None:
    import pinocchio as pin

    s = _load("obstacles.urdf", tmp_path)
    assert s.names == ("table_0", "table_1", "lamp_0", "lamp_1")  # collision only, not visual
    mount = pin.SE3(pin.rpy.rpyToMatrix(0.1, 0, 0), np.array([0, 0, 0.1]))
    table_box = mount * pin.SE3(pin.rpy.rpyToMatrix(0, 0, 0.3), np.array([0.5, 0, -0.01]))
    lamp = mount * pin.SE3(np.eye(3), np.array([0, 0, 0.2]))  # revolute joint at 0
    box, cyl, ball, mesh = s
    assert isinstance(box, Box) and box.size == pytest.approx((1.0, 0.6, 0.02), abs=1e-15)
    np.testing.assert_allclose(_pose(box), table_box.homogeneous, atol=1e-12)
    assert isinstance(cyl, Cylinder) and (cyl.radius, cyl.length) == pytest.approx((0.03, 0.5))
    np.testing.assert_allclose(
        _pose(cyl), (mount * pin.SE3(np.eye(3), np.array([0.5, 0, -0.3]))).homogeneous, atol=1e-12
    )
    assert isinstance(ball, Sphere)
    np.testing.assert_allclose(ball.center, lamp.act(np.array([0.1, 0.2, 0.3])), atol=1e-12)
    assert isinstance(mesh, Mesh) and mesh.path == str((DATA / "block.obj").resolve())
    assert mesh.scale == (1.0, 2.0, 1.0)
    np.testing.assert_allclose(_pose(mesh), lamp.homogeneous, atol=1e-12)


def test_format_told_by_content_without_a_known_extension(tmp_path: Path) -> None:
    for name in FIXTURES:
        copy = tmp_path / (Path(name).stem + ".txt")
        copy.write_text((DATA / name).read_text().replace("block.obj", str(DATA / "block.obj")))
        assert Scene.load(copy, mesh_dir=tmp_path / "meshes") == _load(name, tmp_path), name
    (tmp_path / "x.txt").write_text("hello: world\n")
    with pytest.raises(InvalidArgumentError, match="cannot tell the scene format.*json"):
        Scene.load(tmp_path / "x.txt")


# ----------------------------------------------------------------- an obstacle set in use
def test_a_loaded_scene_is_an_obstacle_set(tmp_path: Path) -> None:
    """coal distances from probes to a loaded cuRobo world, and the robot's exact check
    against it (through ``as_scene``, which reads any format)."""
    import coal
    from conftest import robot

    from swarm_ik.goals import AvoidCollisions

    assert AvoidCollisions(str(DATA / "world.yml")).scene == Scene.load(DATA / "world.yml")
    scene = as_scene(str(DATA / "world.yml"))
    objs = dict(scene.coal_objects())
    probe = coal.Sphere(1e-3)

    def dist(name: str, p) -> float:
        req, res = coal.DistanceRequest(), coal.DistanceResult()
        tf = coal.Transform3s(np.eye(3), np.asarray(p, dtype=float))
        obj = objs[name]
        return coal.distance(obj.collisionGeometry(), obj.getTransform(), probe, tf, req, res)

    assert dist("table", (0.5, 0.0, 0.289)) + 1e-3 == pytest.approx(0.29, abs=1e-6)
    assert dist("post", (0.2, 0.3, 0.8)) + 1e-3 == pytest.approx(0.06, abs=1e-6)  # tip at 0.7
    assert dist("rail", (0.3, -0.3, 0.6)) + 1e-3 == pytest.approx(0.08, abs=1e-6)  # along x

    rc = robot("panda").collision_model()
    q_home = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.785])
    table_only = Scene([o for o in scene if o.name == "table"])
    assert rc.check(q_home, table_only, self_collision=False).collision_free
    low = Scene([Box((1.0, 1.0, 0.2), (0.0, 0.0, 0.5), name="slab")])  # through the arm
    slab = tmp_path / "slab.yml"
    low.save(slab)
    rep = rc.check(q_home, as_scene(slab), self_collision=False)
    assert not rep.collision_free
    assert any("slab" in pair for pair in rep.pairs_in_contact)


# -------------------------------------------------------------------------- refusals
def _refused(path: Path, exc: type[Exception], words: list[str], **kw) -> str:
    with pytest.raises(exc) as info:
        Scene.load(path, **kw)
    msg = str(info.value)
    assert isinstance(info.value, SwarmIKError), type(info.value)
    assert "\n" not in msg, msg
    for w in words:
        assert w in msg, (w, msg)
    return msg


J = InvalidArgumentError
JSON_BAD = [
    ('{"obstacles": [{"type": "Box", "size": [1, 1, 1], "colour": 1}]}', J,
     ["obstacle 0 (Box)", "unknown field(s) ['colour']", "valid fields: size, pose, name"]),
    ('{"obstacles": [], "units": "m"}', J, ["unknown field(s) ['units']", "obstacles, format"]),
    ('{"obstacles": [{"type": "Cone", "radius": 1}]}', UnknownNameError,
     ["'Cone'", "Box, Capsule, Cylinder, Mesh, Sphere"]),
    ('{"obstacles": [{"type": ["Box"], "size": [1, 1, 1]}]}', J, ["type must be a string"]),
    ('{"obstacles": [{"type": "Box", "size": [1, 1, 1], "name": ["a"]}]}', J,
     ["name must be a non-empty string", "['a']"]),
    ('{"obstacles": [{"type": "Sphere", "radius": "0.1"}]}', J, ["radius", "'0.1'"]),
    ('{"obstacles": [{"type": "Sphere", "radius": true}]}', J, ["radius", "True"]),
    ('{"obstacles": [{"type": "Sphere", "radius": 0.1, "center": [0, false, 0]}]}', J,
     ["center must be 3 finite numbers"]),
    ('{"obstacles": [{"type": "Box", "size": [1, 0, 1]}]}', J, ["size", "positive"]),
    ('{"obstacles": [{"type": "Box", "size": [1, -2, 1]}]}', J, ["size", "positive"]),
    ('{"obstacles": [{"type": "Sphere", "radius": NaN}]}', J, ["non-finite number NaN"]),
    ('{"obstacles": [{"type": "Sphere", "radius": 1e999}]}', J, ["radius", "inf"]),
    ('{"obstacles": [{"type": "Sphere"}]}', J, ["missing field(s) ['radius']"]),
    ('{"obstacles": [{"type": "Box", "size": [1, 1, 1], "pose": {"position": [0, 0, 0], '
     '"quaternion": [0, 0, 0, 0]}}]}', J, ["zero norm"]),
    ('{"obstacles": [{"type": "Box", "size": [1, 1, 1], "pose": {"position": [0, 0, 0]}}]}', J,
     ["position, quaternion"]),
    ('{"obstacles": [{"type": "Mesh", "path": ["a.stl"]}]}', J, ["path must be a string"]),
    ('{"obstacles": [{"type": "Mesh", "path": "gone.stl"}]}', SceneFileNotFoundError,
     ["gone.stl"]),
    ('{"format": "other", "obstacles": []}', J, ["format is 'other'"]),
    ('{"version": true, "obstacles": []}', J, ["version is True"]),
    ('{"obstacles": {"a": 1}}', J, ["obstacles must be a list"]),
    ('{"obstacles": [], "obstacles": []}', J, ["'obstacles' given twice"]),
    ('{"obstacles": [{"type": "Sphere", "radius": 1, "name": "a"}, '
     '{"type": "Sphere", "radius": 1, "name": "a"}]}', J, ["['a'] used more than once"]),
    # (review 92: a name that is also an unnamed obstacle's default, said so)
    ('[{"type": "Box", "name": "box1", "size": [0.1, 0.1, 0.1]}, '
     '{"type": "Box", "size": [0.1, 0.1, 0.1]}]', J,
     ["['box1'] used more than once", "default name of an unnamed obstacle"]),
    ('{"obstacles": [', J, ["not a JSON file"]),
    ('{"obstacles": [{"type": "Sphere", "radius": ' + "1" * 5000 + "}]}", J, ["radius", "inf"]),
    ("[" * 40 + "]" * 40, J, ["nested more than 32 levels"]),
    ("[" * 200_000 + "]" * 200_000, J, ["nested more than 32 levels"]),
]  # fmt: skip


@pytest.mark.parametrize("text, exc, words", JSON_BAD)
def test_bad_json_is_refused_with_one_line(tmp_path: Path, text: str, exc, words) -> None:
    (tmp_path / "s.json").write_text(text)
    _refused(tmp_path / "s.json", exc, [str(tmp_path / "s.json"), *words])


YAML_BAD = [
    ("cuboid:\n  t: {dims: [1, 1, 1], pose: [0, 0, 0, 1, 0, 0, 0], mass: 2}\n", J,
     ["cuboid 't'", "unknown field(s) ['mass']", "valid fields: dims, pose, color"]),
    ("cube:\n  t: {dims: [1, 1, 1]}\n", UnknownNameError,
     ["unknown section 'cube'", "cuboid, sphere, capsule"]),
    ("voxel:\n  v: {dims: [1, 1, 1]}\n", J, ["'voxel'", "not supported"]),
    ("cuboid:\n  t: {dims: [1, 1, 1]}\n", J, ["missing field(s) ['pose']"]),
    ("cuboid:\n  t: {dims: [1, 0, 1], pose: [0, 0, 0, 1, 0, 0, 0]}\n", J, ["size", "positive"]),
    ("cuboid:\n  t: {dims: [1, .nan, 1], pose: [0, 0, 0, 1, 0, 0, 0]}\n", J, ["size", "finite"]),
    ("cuboid:\n  t: {dims: [1, 1, 1], pose: [0, 0, 0, 0, 0, 0, 0]}\n", J, ["zero norm"]),
    ("cuboid:\n  t: {dims: [1, 1, 1], pose: [0, 0, 0, 1, 0, 0]}\n", J, ["7 finite numbers"]),
    ("cuboid:\n  t: {dims: [1, 1, 1], pose: [0, 0, .inf, 1, 0, 0, 0]}\n", J, ["7 finite"]),
    ("sphere:\n  s: {radius: -0.1, position: [0, 0, 0]}\n", J, ["sphere 's'", "radius"]),
    ("sphere:\n  s: {radius: yes, position: [0, 0, 0]}\n", J, ["radius", "True"]),
    ("sphere:\n  s: {radius: '0.1', position: [0, 0, 0]}\n", J, ["radius", "'0.1'"]),
    ("sphere:\n  s: {radius: 0.1}\n", J, ["a pose or a position"]),
    ("sphere:\n  s: {radius: 0.1, position: [0, 0, 0], pose: [1, 0, 0, 1, 0, 0, 0]}\n", J,
     ["differ"]),
    ("capsule:\n  c: {radius: 0.1, base: [0, 0, 0], tip: [0, 0, 0], "
     "pose: [0, 0, 0, 1, 0, 0, 0]}\n", J, ["same point"]),
    ("mesh:\n  m: {file_path: gone.obj, pose: [0, 0, 0, 1, 0, 0, 0]}\n",
     SceneFileNotFoundError, ["gone.obj", "absolute"]),
    ("mesh:\n  m: {vertices: [[0, 0, 0]], faces: [0], pose: [0, 0, 0, 1, 0, 0, 0]}\n", J,
     ["inline vertices/faces"]),
    ("cuboid:\n  1: {dims: [1, 1, 1], pose: [0, 0, 0, 1, 0, 0, 0]}\n", J,
     ["name must be a non-empty string", "got 1"]),
    ("cuboid:\n  [a]: {dims: [1, 1, 1], pose: [0, 0, 0, 1, 0, 0, 0]}\n", J,
     ["not a YAML file", "unhashable key"]),
    ("cuboid: [1, 2]\n", J, ["cuboid must map obstacle names"]),
    ("", J, ["holds no cuRobo world"]),  # (an empty world would switch collisions off)
    ("# only a comment\n", J, ["holds no cuRobo world", "cuboid, sphere"]),
    ("- 1\n- 2\n", J, ["a mapping of sections"]),
    ("cuboid:\n  t: {dims: [1, 1, 1], pose: [0, 0, 0, 1, 0, 0, 0]}\n"
     "  t: {dims: [1, 1, 1], pose: [0, 0, 0, 1, 0, 0, 0]}\n", J, ["'t' given twice"]),
    ("cuboid:\n  t: {dims: [1, 1, 1]\n", J, ["not a YAML file"]),
    ("sphere:\n  s: {radius: " + "1" * 5000 + ", position: [0, 0, 0]}\n", J, ["not a YAML"]),
    ("cuboid:\n  t: {dims: [1, 1, 1], pose: [0, 0, 0, 1, 0, 0, 0], color: 2001-13-45}\n", J,
     ["not a YAML file", "month"]),
    ("cuboid:\n  t:\n" + "".join("  " * (k + 2) + f"k{k}:\n" for k in range(40)) + "  " * 42
     + "x: 1\n", J, ["nested more than 32 levels"]),
    ("a: &a [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]\n"
     + "".join(f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n"
               for p, c in zip("abcdefgh", "bcdefghi", strict=True)), J,
     ["more than 5000000 values"]),
]  # fmt: skip


@pytest.mark.parametrize("text, exc, words", YAML_BAD)
def test_bad_curobo_yaml_is_refused_with_one_line(tmp_path: Path, text: str, exc, words) -> None:
    (tmp_path / "w.yml").write_text(text)
    _refused(tmp_path / "w.yml", exc, [str(tmp_path / "w.yml"), *words])


GOOD_OBJECT = "* a\n1\nbox\n1 1 1\n0 0 0\n0 0 0 1\n0 0 0 0\n"
MOVEIT_BAD = [
    ("s\n* a\n1\ncone\n0.1 0.2\n0 0 0\n0 0 0 1\n0 0 0 0\n.\n", J,
     ["line 4", "object 'a'", "no cone primitive", "box, cylinder, mesh, sphere"]),
    ("s\n* a\n1\nplane\n0 0 1 0\n0 0 0\n0 0 0 1\n0 0 0 0\n.\n", J, ["infinite plane"]),
    ("s\n* a\n1\ntorus\n1\n0 0 0\n0 0 0 1\n0 0 0 0\n.\n", UnknownNameError,
     ["'torus'", "box, cylinder, mesh, sphere"]),
    ("s\n" + GOOD_OBJECT, J, ["file ends", "truncated"]),
    ("", J, ["the file is empty"]),
    ("s\n* a\n1\nbox\n1 1\n", J, ["file ends", "truncated"]),
    ("s\n* a\n1\nbox\n1 1 1\n0 0 0\n0 0 0 1\n", J, ["colour", "truncated"]),
    ("s\n* a\n1\nbox\n1 -1 1\n0 0 0\n0 0 0 1\n0 0 0 0\n.\n", J,
     ["line 4", "object 'a'", "size", "positive"]),
    ("s\n* a\n1\nbox\n1 nan 1\n0 0 0\n0 0 0 1\n0 0 0 0\n.\n", J, ["must be a number", "'nan'"]),
    ("s\n* a\n1\nbox\n1 1e999 1\n0 0 0\n0 0 0 1\n0 0 0 0\n.\n", J, ["finite", "1e999"]),
    ("s\n* a\n1\nbox\n1 1 1\n0 0 0\n0 0 0 0\n0 0 0 0\n.\n", J, ["zero norm"]),
    ("s\n* a\n-1\n.\n", J, ["number of shapes", "'-1'"]),
    ("s\n* a\n" + "9" * 5000 + "\n.\n", J, ["number of shapes", "whole number"]),
    ("s\n* a\n1\nbox\n1 x 1\n0 0 0\n0 0 0 1\n0 0 0 0\n.\n", J, ["box size y", "'x'"]),
    ("s\n" + GOOD_OBJECT + "?\n", J, ["unknown marker '?'"]),
    ("s\n*\n1\n.\n", J, ["without a name"]),
    ("s\n* a\n1\nmesh\n3 1\n0 0 0\n1 0 0\n0 1 0\n0 1 5\n0 0 0\n0 0 0 1\n0 0 0 0\n.\n", J,
     ["names a vertex beyond the 3 given"]),
    ("s\n* a\n1\nmesh\n3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 0\n0 0 0 1\n0 0 0 0\n.\n", J,
     ["no triangles"]),
    ("s\n" + GOOD_OBJECT + GOOD_OBJECT + ".\n", J, ["['a'] used more than once"]),
    ("only a name line", J, ["ends after its name line"]),
    # a pose or colour line of the wrong length (reading token by token would take the next
    # line's numbers: a 5-number quaternion, or a 4-number position before a 3-number one)
    ("s\n* a\n1\nbox\n1 1 1\n0 0 0\n0 0 0 1 0\n0 0 0 0\n.\n", J,
     ["line 7", "quaternion must be 4 numbers on one line", "more follow: '0'"]),
    ("s\n* a\n1\nbox\n1 1 1\n0.5 0 0 0.3\n0 0 1\n0 0 0 0\n.\n", J,
     ["line 6", "position must be 3 numbers on one line", "more follow: '0.3'"]),
    ("s\n* a\n1\nbox\n1 1 1\n0 0 0\n0 0 1\n0 0 0 0\n.\n", J,
     ["line 7", "quaternion must be 4 numbers on one line", "it has 3"]),
    ("s\n* a\n1\nbox\n1 1 1\n0 0 0\n0 0 0 1\n0 0 0\n.\n", J,
     ["line 8", "colour must be 4 numbers on one line", "it has 3"]),
    # a mesh with no surface (its every triangle of zero area), refused where it is written
    ("s\n* a\n1\nmesh\n3 1\n0 0 0\n1 0 0\n2 0 0\n0 1 2\n0 0 0\n0 0 0 1\n0 0 0 0\n.\n", J,
     ["line 4", "zero area"]),
]  # fmt: skip


@pytest.mark.parametrize("text, exc, words", MOVEIT_BAD)
def test_bad_moveit_scene_is_refused_with_one_line(tmp_path: Path, text, exc, words) -> None:
    (tmp_path / "m.scene").write_text(text)
    _refused(tmp_path / "m.scene", exc, [str(tmp_path / "m.scene"), *words], mesh_dir=tmp_path)


def _urdf(body: str) -> str:
    return f'<?xml version="1.0"?><robot name="r"><link name="base"/>{body}</robot>'


def _moving(joint: str, kind: str, lower: float, upper: float) -> str:
    """A box on a moving joint of the given limits."""
    return _urdf(
        '<link name="c"><collision><geometry><box size="1 1 1"/></geometry></collision></link>'
        f'<joint name="{joint}" type="{kind}"><parent link="base"/><child link="c"/>'
        f'<axis xyz="0 0 1"/><limit lower="{lower}" upper="{upper}" effort="1" velocity="1"/>'
        "</joint>"
    )


URDF_BAD = [
    ("<robot", J, ["not a valid XML file"]),
    ("<world/>", J, ["root element is <world>", "expected <robot>"]),
    (_urdf('<link name="c"><collision><geometry><cylinder radius="abc" length="1"/></geometry>'
           '</collision></link><joint name="j" type="fixed"><parent link="base"/>'
           '<child link="c"/></joint>'), J, ["link 'c'", "radius='abc'", "1 finite number"]),
    (_urdf('<link name="c"><collision><origin xyz="0 0 nan"/><geometry><sphere radius="1"/>'
           '</geometry></collision></link><joint name="j" type="fixed"><parent link="base"/>'
           '<child link="c"/></joint>'), J, ["link 'c'", "xyz='0 0 nan'", "3 finite numbers"]),
    (_urdf('<link name="c"/><joint name="j" type="fixed"><parent link="base"/>'
           '<child link="c"/></joint><joint name="k" type="fixed"><parent link="c"/>'
           '<child link="base"/></joint>'), J, ["a loop"]),
    (_urdf('<link name="c"><collision><geometry><capsule radius="1" length="1"/></geometry>'
           '</collision></link><joint name="j" type="fixed"><parent link="base"/>'
           '<child link="c"/></joint>'), UnknownNameError,
     ["link 'c'", "box, cylinder, mesh, sphere", "['capsule']"]),
    (_moving("door", "revolute", 0.5, 1), J, ["joint 'door'", "[0.5, 1]", "leave out 0",
                                              "make it a fixed joint"]),
    (_moving("rail", "prismatic", 0.3, 0.3), J, ["joint 'rail'", "[0.3, 0.3]", "leave out 0"]),
    (_urdf('<link name="c"><collision><geometry><mesh filename="gone.stl"/></geometry>'
           '</collision></link><joint name="j" type="fixed"><parent link="base"/>'
           '<child link="c"/></joint>'), SceneFileNotFoundError, ["gone.stl"]),
    (_urdf('<link name="c"><collision><geometry><box size="1 0 1"/></geometry>'
           '</collision></link><joint name="j" type="fixed"><parent link="base"/>'
           '<child link="c"/></joint>'), J, ["c_0", "size", "positive"]),
]  # fmt: skip


@pytest.mark.parametrize("text, exc, words", URDF_BAD)
def test_bad_urdf_is_refused_with_one_line(tmp_path: Path, text, exc, words) -> None:
    (tmp_path / "o.urdf").write_text(text)
    _refused(tmp_path / "o.urdf", exc, [str(tmp_path / "o.urdf"), *words])


def test_missing_large_and_binary_files_are_refused(tmp_path: Path) -> None:
    for ext in (".json", ".yml", ".scene", ".urdf"):
        _refused(tmp_path / f"gone{ext}", SceneFileNotFoundError, ["not found", f"gone{ext}"])
    _refused(tmp_path, SceneFileNotFoundError, ["is not a file"])
    big = tmp_path / "big.json"
    with big.open("wb") as f:
        f.truncate(S.MAX_FILE_BYTES + 1)  # sparse: no disk used, refused before reading
    _refused(big, InvalidArgumentError, ["64 MiB limit", str(S.MAX_FILE_BYTES + 1)])
    (tmp_path / "bin.yml").write_bytes(b"\xff\xfe\x00cuboid")
    _refused(tmp_path / "bin.yml", InvalidArgumentError, ["not a UTF-8 text file"])


def test_save_refuses_other_extensions(tmp_path: Path) -> None:
    with pytest.raises(InvalidArgumentError, match=r"\.json .*\.yml/\.yaml.*'\.scene'"):
        Scene([Sphere(0.1)]).save(tmp_path / "x.scene")


def test_shape_constructors_refuse_wrong_types() -> None:
    import pinocchio as pin

    se3 = pin.SE3(pin.rpy.rpyToMatrix(0.1, 0.2, 0.3), np.array([1.0, 2.0, 3.0]))
    np.testing.assert_array_equal(_pose(Box((1, 1, 1), se3)), se3.homogeneous)  # still taken
    assert Sphere(np.float32(0.5), np.arange(3)).center == (0.0, 1.0, 2.0)
    for make, words in [
        (lambda: Sphere(True), ["radius", "True"]),
        (lambda: Sphere("0.1"), ["radius", "'0.1'"]),
        (lambda: Box((1, True, 1)), ["size", "3 finite numbers"]),
        (lambda: Box((1, 1, 1), name=["b"]), ["name", "['b']"]),
        (lambda: Box((1, 1, 1), name=""), ["name", "non-empty"]),
        (lambda: Mesh(["a.stl"]), ["path must be a file path"]),
        (lambda: Cylinder(10**400, 1.0), ["radius", "inf"]),
        (lambda: Capsule(0.1, 1.0, np.eye(4, dtype=bool)), ["pose"]),
    ]:
        with pytest.raises(InvalidArgumentError) as info:
            make()
        msg = str(info.value)
        assert "\n" not in msg and all(w in msg for w in words), (words, msg)


def test_yaml_without_pyyaml_names_the_package_and_the_file(tmp_path: Path, monkeypatch) -> None:
    S._yaml_loader.cache_clear()
    monkeypatch.setitem(sys.modules, "yaml", None)  # import yaml -> ImportError
    try:
        with pytest.raises(SceneDependencyError, match=r"world\.yml: .*PyYAML: pip install pyyaml"):
            Scene.load(DATA / "world.yml")
        with pytest.raises(SceneDependencyError, match=r"w\.yml: .*PyYAML"):
            Scene([Sphere(0.1)]).save(tmp_path / "w.yml")
        assert not (tmp_path / "w.yml").exists()
        assert Scene.load(DATA / "table.json")  # the other formats do not need it
    finally:
        S._yaml_loader.cache_clear()


def test_curobo_sections_are_written_in_the_documented_order(tmp_path: Path) -> None:
    shapes = [
        Mesh(str(DATA / "block.obj"), name="m"),
        Cylinder(0.1, 0.2, name="cy"),
        Capsule(0.1, 0.2, name="ca"),
        Sphere(0.1, name="s"),
        Box((0.1, 0.1, 0.1), name="b"),
    ]
    path = Scene(shapes).save(tmp_path / "w.yml")
    sections = re.findall(r"^(\w+):", path.read_text(), flags=re.M)
    assert sections == ["cuboid", "sphere", "capsule", "cylinder", "mesh"]


def test_scene_paths_and_values_of_the_wrong_kind_are_refused(tmp_path: Path) -> None:
    scene = Scene([Sphere(0.1)])
    for make, words in [
        (lambda: Scene.load(None), ["scene file must be a path", "None"]),
        (lambda: Scene.from_json(3), ["scene file must be a path", "3"]),
        (lambda: scene.save(tmp_path / "no" / "such" / "w.json"), ["cannot write", "w.json"]),
        (lambda: scene.save(tmp_path / "no" / "such" / "w.yml"), ["cannot write", "w.yml"]),
        (lambda: as_scene(42), ["scene must be a Scene", "int"]),
        (lambda: AvoidCollisions(scene=42), ["scene must be a Scene", "int"]),
    ]:
        with pytest.raises(InvalidArgumentError) as info:
            make()
        msg = str(info.value)
        assert "\n" not in msg and all(w in msg for w in words), (words, msg)


# ---------------------------------------------------------------------------- the docs
def test_the_docs_snippets_run_as_written(tmp_path: Path, monkeypatch, capsys) -> None:
    """Every ```python block of docs/scenes.md runs in an empty folder and prints."""
    blocks = re.findall(r"```python\n(.*?)```", DOCS.read_text(), flags=re.S)
    assert len(blocks) >= 4
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SWARM_IK_CACHE_DIR", str(tmp_path / "cache"))
    for k, code in enumerate(blocks):
        exec(compile(code, f"{DOCS}:block{k}", "exec"), {"__name__": f"doc{k}"})
        assert capsys.readouterr().out.strip(), f"block {k} printed nothing"


def test_mangled_files_never_escape_as_bare_python_errors(tmp_path: Path) -> None:
    """Seeded random edits of every fixture (junk tokens, deletions, truncation): each file
    loads or is refused with a one-line swarm_ik error."""
    rng = random.Random(20240611)
    junk = ["", "-1", "0", "nan", "1e999", "true", "[1, 2]", "{}", "null", '"x"', "*", ".",
            "box", "cone", "[[[", "}", "\n", ":", "- a", "<", "/>", "&a", "*a", "1 2 3", "'1'",
            "é", "1" * 5000, "2001-13-45", "99999999999999999999"]  # fmt: skip
    (tmp_path / "block.obj").write_text((DATA / "block.obj").read_text())
    for name in FIXTURES:
        tokens = re.split(r"(\s+|[\[\]{},:\"<>=/])", (DATA / name).read_text())
        for _ in range(40):
            t = list(tokens)
            for _ in range(rng.randint(1, 3)):
                i = rng.randrange(len(t))
                op = rng.random()
                if op < 0.6:
                    t[i] = rng.choice(junk)
                elif op < 0.8:
                    del t[i]
                else:
                    t.insert(i, rng.choice(junk))
            text = "".join(t)
            if rng.random() < 0.2:
                text = text[: rng.randrange(len(text) + 1)]
            (tmp_path / name).write_text(text)
            try:
                Scene.load(tmp_path / name, mesh_dir=tmp_path / "meshes")
            except SwarmIKError as exc:
                assert "\n" not in str(exc), (name, text, str(exc))


def test_home_folder_paths_that_name_no_user_are_refused(tmp_path: Path) -> None:
    """``~nosuchuser/…`` (pathlib cannot expand it) is refused in one line, as a scene path, a
    JSON mesh path and a cuRobo mesh path."""
    _refused(Path("~nosuchuser_swarm_ik/x.json"), J, ["starts with '~'", "no home folder"])
    (tmp_path / "m.json").write_text(
        json.dumps([{"type": "mesh", "path": "~nosuchuser_swarm_ik/m.obj"}])
    )
    _refused(tmp_path / "m.json", J, ["obstacle 0", "~nosuchuser_swarm_ik/m.obj", "no home"])
    (tmp_path / "m.yml").write_text(
        "mesh:\n  m: {file_path: ~nosuchuser_swarm_ik/m.obj, pose: [0, 0, 0, 1, 0, 0, 0]}\n"
    )
    _refused(tmp_path / "m.yml", J, ["~nosuchuser_swarm_ik/m.obj", "no home"])


def test_a_mesh_dir_that_cannot_hold_the_meshes_is_refused(tmp_path: Path) -> None:
    """A MoveIt scene's inline mesh is written into ``mesh_dir``: a file there, or a value
    that is no path, is refused in one line."""
    text = "s\n* a\n1\nmesh\n3 1\n0 0 0\n1 0 0\n0 1 0\n0 1 2\n0 0 0\n0 0 0 1\n0 0 0 0\n.\n"
    (tmp_path / "m.scene").write_text(text)
    (tmp_path / "afile").write_text("x")
    _refused(tmp_path / "m.scene", J, ["cannot write", "afile", "writable"],
             mesh_dir=tmp_path / "afile")  # fmt: skip
    _refused(tmp_path / "m.scene", J, ["mesh_dir must be a path", "got 5"], mesh_dir=5)
    assert Scene.load(tmp_path / "m.scene", mesh_dir=tmp_path / "ok").names == ("a",)


def test_an_xml_urdf_in_another_encoding_is_read(tmp_path: Path) -> None:
    """A ``.xml`` holding a ``<robot>`` is told by its bytes, so an XML that declares another
    encoding reads as it does under ``.urdf``."""
    body = (
        '<?xml version="1.0" encoding="ISO-8859-1"?><robot name="r\xe9"><link name="a">'
        '<collision><geometry><box size="1 1 1"/></geometry></collision></link></robot>'
    )
    for ext in (".urdf", ".xml"):
        (tmp_path / f"o{ext}").write_bytes(body.encode("latin-1"))
        assert Scene.load(tmp_path / f"o{ext}").names == ("a_0",)


def test_moveit_shape_names_never_take_another_objects_id(tmp_path: Path) -> None:
    """An object of two shapes names them ``shelf#0``, ``shelf#1``; where another object is
    itself called ``shelf#0`` the generated name takes a further suffix (the file was
    refused: "obstacle name(s) ['shelf#0'] used more than once")."""
    board = "box\n1 1 0.02\n0 0 0\n0 0 0 1\n0 0 0 0\n"
    text = f"s\n* shelf\n2\n{board}{board}* shelf#0\n1\n{board}.\n"
    (tmp_path / "s.scene").write_text(text)
    assert Scene.load(tmp_path / "s.scene").names == ("shelf#0.1", "shelf#1", "shelf#0")
    (tmp_path / "d.scene").write_text(f"s\n* a\n1\n{board}* a\n1\n{board}.\n")
    _refused(tmp_path / "d.scene", J, ["['a'] used more than once"])  # (two objects 'a')


def test_a_curobo_mesh_urdf_path_is_accepted_and_ignored(tmp_path: Path) -> None:
    (tmp_path / "w.yml").write_text(
        f"mesh:\n  m: {{file_path: {DATA / 'block.obj'}, pose: [0, 0, 0, 1, 0, 0, 0], "
        "urdf_path: cell.urdf}\n"
    )
    (mesh,) = Scene.load(tmp_path / "w.yml")
    assert isinstance(mesh, Mesh) and mesh.path == str((DATA / "block.obj").resolve())
