"""Obstacles of a :class:`swarm_ik.scene.Scene` and collision contacts drawn in the viewer.

:func:`show_collision` draws the robot at ``q``, every obstacle (grey, translucent) and, from
the exact check's :class:`swarm_ik.collision.CollisionReport`, the obstacles and the robot's
collision bodies in contact in red.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from swarm_ik._types import FloatArray
from swarm_ik.robot import RobotModel
from swarm_ik.viz.scene import Scene

OBSTACLE_RGBA = (0.55, 0.58, 0.62, 0.45)
"""Colour of an obstacle clear of the robot."""
CONTACT_RGBA = (0.9, 0.1, 0.1, 0.75)
"""Colour of an obstacle, or a robot collision body, in contact."""


def _material(rgba: Sequence[float]) -> Any:
    import meshcat.geometry as mg

    from swarm_ik.viz.geometry import rgb_int

    return mg.MeshPhongMaterial(
        color=rgb_int(rgba), opacity=float(rgba[3]), transparent=float(rgba[3]) < 1.0
    )


def _shape_object(shape: Any) -> tuple[list[tuple[Any, FloatArray]], FloatArray]:
    """meshcat geometries of one scene shape, each with its local transform, and the shape's
    world pose."""
    import meshcat.geometry as mg

    from swarm_ik.scene import shape_pose

    pose = np.asarray(shape_pose(shape), dtype=float)
    kind = type(shape).__name__
    x_to_y = np.eye(4)  # three.js cylinders run along y, ours along z
    x_to_y[:3, :3] = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]
    if kind == "Sphere":
        return [(mg.Sphere(float(shape.radius)), np.eye(4))], pose
    if kind == "Box":
        return [(mg.Box([float(v) for v in shape.size]), np.eye(4))], pose
    if kind == "Cylinder":
        return [(mg.Cylinder(float(shape.length), float(shape.radius)), x_to_y)], pose
    if kind == "Capsule":
        r, h = float(shape.radius), float(shape.length)
        parts: list[tuple[Any, FloatArray]] = [(mg.Cylinder(h, r), x_to_y)]
        for z in (-h / 2, h / 2):
            t = np.eye(4)
            t[2, 3] = z
            parts.append((mg.Sphere(r), t))
        return parts, pose
    scale = np.diag([*np.broadcast_to(np.asarray(shape.scale, dtype=float), (3,)), 1.0])
    path = str(shape.path)
    loader = mg.StlMeshGeometry if path.lower().endswith(".stl") else mg.ObjMeshGeometry
    if path.lower().endswith(".dae"):
        loader = mg.DaeMeshGeometry
    return [(loader.from_file(path), scale)], pose


def add_obstacles(scene: Scene, obstacles: Any, in_contact: Sequence[str] = ()) -> None:
    """Draw every obstacle of ``obstacles`` (a :class:`swarm_ik.scene.Scene`); those named in
    ``in_contact`` in red."""
    from swarm_ik.scene import as_scene

    obs = as_scene(obstacles)
    for name, shape in zip(obs.names, obs, strict=True):
        rgba = CONTACT_RGBA if name in in_contact else OBSTACLE_RGBA
        parts, pose = _shape_object(shape)
        node = scene.node(f"obstacles/{name}")
        node.set_transform(pose)
        for k, (geometry, local) in enumerate(parts):
            sub = node[f"part{k}"]
            sub.set_object(geometry, _material(rgba))
            sub.set_transform(local)


def add_contact_bodies(scene: Scene, robot: RobotModel, q: Any, links: Sequence[str]) -> None:
    """Overlay, in red, the collision bodies of ``robot`` at ``q`` whose link is in ``links``
    (meshes and primitives of the URDF's ``<collision>`` elements)."""
    import coal
    import meshcat.geometry as mg

    rc = robot.collision_model()
    rot, pos = rc.body_placements(q)
    for k, (gobj, link) in enumerate(
        zip(rc.geom_model.geometryObjects, rc.body_links, strict=True)
    ):
        if link not in links:
            continue
        t = np.eye(4)
        t[:3, :3], t[:3, 3] = rot[k], pos[k]
        g = gobj.geometry
        node = scene.node(f"contacts/{k}_{link}")
        if isinstance(g, coal.Sphere):
            obj: Any = mg.Sphere(float(g.radius))
        elif isinstance(g, coal.Box):
            obj = mg.Box([2.0 * float(v) for v in g.halfSide])
        elif isinstance(g, (coal.Cylinder, coal.Capsule)):
            obj = mg.Cylinder(2.0 * float(g.halfLength), float(g.radius))
            turn = np.eye(4)
            turn[:3, :3] = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]
            t = t @ turn
        else:
            path = str(gobj.meshPath)
            if (
                not path
                or path.startswith("BOX")
                or not path.lower().endswith((".stl", ".obj", ".dae"))
            ):
                continue
            kinds = {
                ".stl": mg.StlMeshGeometry,
                ".obj": mg.ObjMeshGeometry,
                ".dae": mg.DaeMeshGeometry,
            }
            obj = kinds[path.lower()[-4:]].from_file(path)
            t = t @ np.diag([*np.asarray(gobj.meshScale, dtype=float), 1.0])
        node.set_object(obj, _material(CONTACT_RGBA))
        node.set_transform(t)


def show_collision(
    robot: RobotModel,
    q: Any,
    obstacles: Any = None,
    report: Any = None,
    *,
    target: Any = None,
    lines: Sequence[str] = (),
    scene: Scene | None = None,
) -> Scene:
    """The robot at ``q`` among the obstacles, contacts in red.

    Args:
        robot: The robot.
        q: Joint vector (rad / m), ``(nq,)``.
        obstacles: A :class:`swarm_ik.scene.Scene` (or shapes, a JSON path, None).
        report: The exact check's :class:`swarm_ik.collision.CollisionReport` at ``q``
            (default: computed now); its pairs in contact are drawn red.
        target: Optional target pose (4x4) drawn as a triad.
        lines: Text of the sign.
        scene: Scene to draw into.

    Returns:
        The scene.
    """
    from swarm_ik.scene import as_scene
    from swarm_ik.viz.views import show_pose

    obs = as_scene(obstacles)
    if report is None:
        report = robot.collision_model().check(q, obs)
    named = {n for pair in report.pairs_in_contact for n in pair}
    scene = show_pose(robot, q, target=target, lines=lines, scene=scene)
    add_obstacles(scene, obs, [n for n in obs.names if n in named])
    add_contact_bodies(scene, robot, q, [n for n in named if n not in set(obs.names)])
    return scene
