"""Scene shapes: validation, JSON round trip, coal objects."""

from __future__ import annotations

import json

import numpy as np
import pytest

from swarm_ik.errors import InvalidArgumentError, SwarmIKError, UnknownNameError
from swarm_ik.scene import (
    Box,
    Capsule,
    Cylinder,
    Mesh,
    Scene,
    SceneFileNotFoundError,
    Sphere,
    as_scene,
)


def _rot_z(a: float, t=(0.0, 0.0, 0.0)) -> np.ndarray:
    m = np.eye(4)
    m[:2, :2] = [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]
    m[:3, 3] = t
    return m


@pytest.fixture()
def stl(tmp_path):
    import trimesh

    path = tmp_path / "block.stl"
    trimesh.creation.box(extents=(0.2, 0.1, 0.05)).export(path)
    return path


def _all_shapes(stl) -> list:
    return [
        Sphere(0.05, (0.4, 0.0, 0.3)),
        Box((1.0, 0.6, 0.02), _rot_z(0.3, (0.5, 0.0, -0.011)), name="table"),
        Capsule(0.04, 0.3, _rot_z(-1.0, (0.2, 0.3, 0.5))),
        Cylinder(0.03, 0.5, (0.0, -0.4, 0.25)),
        Mesh(stl, _rot_z(0.7, (0.3, 0.3, 0.1)), scale=(1.0, 2.0, 1.0)),
    ]


def test_json_round_trip(tmp_path, stl) -> None:
    scene = Scene(_all_shapes(stl))
    path = scene.to_json(tmp_path / "scene.json")
    back = Scene.from_json(path)
    assert back == scene
    assert back.names == ("sphere0", "table", "capsule2", "cylinder3", "mesh4")
    assert [o.kind for o in back] == ["sphere", "box", "capsule", "cylinder", "mesh"]
    np.testing.assert_array_equal(np.array(back[1].pose), _rot_z(0.3, (0.5, 0.0, -0.011)))


def test_relative_mesh_path_is_read_from_the_json_folder(tmp_path, stl) -> None:
    data = {"obstacles": [{"type": "mesh", "path": stl.name, "scale": 2.0}]}
    (tmp_path / "s.json").write_text(json.dumps(data))
    scene = Scene.from_json(tmp_path / "s.json")
    assert scene[0].path == str(stl.resolve())
    assert scene[0].scale == (2.0, 2.0, 2.0)


@pytest.mark.parametrize(
    "make, words",
    [
        (lambda: Sphere(-0.1), ["sphere", "radius", "-0.1"]),
        (lambda: Sphere(0.0), ["sphere", "radius", "0.0"]),
        (lambda: Capsule(0.1, -1.0), ["capsule", "length"]),
        (lambda: Cylinder(float("nan"), 1.0), ["cylinder", "radius"]),
        (lambda: Box((1.0, 0.0, 1.0)), ["box", "size", "positive"]),
        (lambda: Box((1.0, 1.0)), ["box", "size", "3"]),
        (lambda: Box((1, 1, 1), np.diag([1.0, 1.0, -1.0, 1.0])), ["box", "rigid"]),
        (lambda: Sphere(0.1, "abc"), ["sphere", "center"]),
        (lambda: Scene([Sphere(0.1), "a box"]), ["scene item 1", "str", "Sphere"]),
        (lambda: Scene([Sphere(0.1, name="a"), Sphere(0.2, name="a")]), ["'a'", "more than once"]),
    ],
)
def test_bad_shapes_are_refused_with_one_line(make, words) -> None:
    with pytest.raises(InvalidArgumentError) as exc:
        make()
    msg = str(exc.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, (w, msg)


def test_unknown_shape_type_lists_the_valid_ones() -> None:
    with pytest.raises(UnknownNameError) as exc:
        Scene.from_dict({"obstacles": [{"type": "cone", "radius": 1.0}]})
    msg = str(exc.value)
    assert "'cone'" in msg and "Box" in msg and "Cylinder" in msg and "\n" not in msg
    assert isinstance(exc.value, SwarmIKError)


def test_missing_mesh_file_is_refused(tmp_path) -> None:
    with pytest.raises(SceneFileNotFoundError) as exc:
        Mesh(tmp_path / "nope.stl")
    assert "nope.stl" in str(exc.value) and isinstance(exc.value, SwarmIKError)
    (tmp_path / "s.json").write_text('{"obstacles": [{"type": "mesh", "path": "gone.obj"}]}')
    with pytest.raises(SceneFileNotFoundError, match="gone.obj"):
        Scene.from_json(tmp_path / "s.json")


def test_bad_json_fields_are_refused(tmp_path) -> None:
    with pytest.raises(InvalidArgumentError, match="sphere.*radius"):
        Scene.from_dict([{"type": "sphere", "radius": -2}])
    with pytest.raises(InvalidArgumentError, match="obstacle 0 .*box"):
        Scene.from_dict([{"type": "box", "size": [1, 1, 1], "colour": "red"}])
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(InvalidArgumentError, match="not a JSON file"):
        Scene.from_json(tmp_path / "bad.json")
    with pytest.raises(SceneFileNotFoundError):
        Scene.from_json(tmp_path / "missing.json")
    with pytest.raises(InvalidArgumentError):
        Scene.from_dict({"shapes": []})


def test_coal_objects_match_the_shapes(stl) -> None:
    """coal distances from a probe sphere equal the analytic ones (poses and sizes right)."""
    import coal

    scene = as_scene(_all_shapes(stl))
    objs = dict(scene.coal_objects())
    assert list(objs) == list(scene.names)
    probe = coal.Sphere(1e-3)

    def dist(name: str, p) -> float:
        obj = objs[name]
        req, res = coal.DistanceRequest(), coal.DistanceResult()
        tf = coal.Transform3s(np.eye(3), np.asarray(p, dtype=float))
        return (
            coal.distance(obj.collisionGeometry(), obj.getTransform(), probe, tf, req, res) + 1e-3
        )

    assert dist("sphere0", (0.4, 0.0, 0.5)) == pytest.approx(0.15, abs=1e-6)
    # table: 2 cm thick, top at z = -0.001; a point 0.3 m above its centre
    assert dist("table", (0.5, 0.0, 0.289)) == pytest.approx(0.29, abs=1e-6)
    # capsule axis along z through (0.2, 0.3), half length 0.15, radius 0.04
    assert dist("capsule2", (0.2, 0.3, 0.5 + 0.15 + 0.1)) == pytest.approx(0.06, abs=1e-6)
    assert dist("cylinder3", (0.2, -0.4, 0.25)) == pytest.approx(0.17, abs=1e-6)
    # mesh: 0.2 x 0.1 (x2 scale in y -> 0.2) x 0.05 block; 0.5 m above its centre
    assert dist("mesh4", (0.3, 0.3, 0.6)) == pytest.approx(0.5 - 0.025, abs=1e-6)
    lo, hi = scene.bounds()
    assert lo[2] == pytest.approx(-0.021, abs=1e-6) and hi[2] >= 0.6


def test_scene_pickles_after_use() -> None:
    """A scene used in a check holds coal objects; it still pickles (they are made again)."""
    import pickle

    import numpy as np

    import swarm_ik
    from swarm_ik.scene import Box

    robot = swarm_ik.load_robot("panda")
    pose = np.eye(4)
    pose[:3, 3] = [0.6, 0.0, 0.2]
    scene = swarm_ik.Scene([Box(size=(0.2, 0.2, 0.2), pose=pose)])
    before = robot.collision_model().check(robot.mid_q(), scene, 0.0, False).collision_free
    again = pickle.loads(pickle.dumps(scene))
    assert again.names == scene.names
    assert robot.collision_model().check(robot.mid_q(), again, 0.0, False).collision_free == before


def test_mesh_edges_refused_with_one_message(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """A corrupt mesh file (exit 3 before), a scale of 1e300 (the sphere fit never
    returned) and a mesh too large for its sphere cover are refused naming the problem."""
    from pathlib import Path

    import numpy as np

    import swarm_ik
    from swarm_ik.errors import InvalidArgumentError
    from swarm_ik.goals import AvoidCollisions
    from swarm_ik.scene import Mesh, Scene

    block = Path(__file__).parent / "data" / "scenes" / "block.obj"
    bad = tmp_path / "bad.stl"
    bad.write_text("solid x\n garbage\nendsolid\n")
    robot = swarm_ik.load_robot("panda")
    target = robot.fk(robot.mid_q())
    with pytest.raises(InvalidArgumentError, match="coal cannot read it"):
        swarm_ik.solve(
            swarm_ik.IKProblem(robot, target, goals=[AvoidCollisions(Scene([Mesh(str(bad))]))])
        )
    for scale in (1e300, 1e-300):
        with pytest.raises(InvalidArgumentError, match="MESH_SCALE"):
            Mesh(str(block), scale=scale)
    with pytest.raises(InvalidArgumentError, match="MAX_LENGTH"):  # (vertices 100 km out)
        Mesh(str(block), scale=1e6, pose=np.eye(4))
    huge = Scene([Mesh(str(block), scale=1e4, pose=np.eye(4))])
    with pytest.raises(InvalidArgumentError, match="MAX_FIT_TRIANGLES"):
        swarm_ik.IKProblem(robot, target, goals=[AvoidCollisions(huge)])


def _box_obj(path, lo, hi) -> None:  # type: ignore[no-untyped-def]
    """A closed box ``lo``–``hi`` [m] written as an OBJ file."""
    v = [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    f = [(1, 3, 2), (2, 3, 4), (5, 6, 7), (6, 8, 7), (1, 2, 5), (2, 6, 5),
         (3, 7, 4), (4, 7, 8), (1, 5, 3), (3, 5, 7), (2, 4, 6), (4, 8, 6)]  # fmt: skip
    lines = [f"v {x:g} {y:g} {z:g}" for x, y, z in v] + [f"f {a} {b} {c}" for a, b, c in f]
    path.write_text("\n".join(lines) + "\n")


def test_a_mesh_file_rewritten_in_place_is_a_new_obstacle(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """Two meshes of one path are equal only while the file's bytes are: a file rewritten
    between two scenes was judged by the collision model cached for its old content (40 of
    99 batch successes in contact with the new block)."""
    import swarm_ik
    from swarm_ik.goals import AvoidCollisions

    path = tmp_path / "m.obj"
    robot = swarm_ik.load_robot("panda")
    targets = robot.fk(robot.random_q(np.random.default_rng(2), 40))
    _box_obj(path, [5, 5, 5], [5.1, 5.1, 5.1])  # far away
    far = Scene([Mesh(str(path), name="m")])
    swarm_ik.solve_batch(robot, targets, goals=[AvoidCollisions(far)])
    _box_obj(path, [0.2, -0.6, 0.0], [0.8, 0.6, 0.5])  # a block in the workspace
    near = Scene([Mesh(str(path), name="m")])
    assert near != far
    res = swarm_ik.solve_batch(robot, targets, goals=[AvoidCollisions(near)])
    model = robot.collision_model()
    hits = [model.collides(q, near, 0.0, True) for q in res.q[res.success]]
    assert res.success.any() and not any(hits)
