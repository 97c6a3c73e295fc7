"""Robot geometry for the viewer: meshes found from ``package://`` paths, the full model's
configuration for a chain configuration, and Pinocchio's meshcat loader adapted to a scene.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from swarm_ik import paths
from swarm_ik._signals import sigint_deferred
from swarm_ik._types import FloatArray
from swarm_ik.errors import RobotModelError
from swarm_ik.robot import RobotModel


def package_dirs(robot: RobotModel) -> list[str]:
    """Folders searched for ``package://`` meshes of ``robot``'s URDF.

    The URDF's folder and its two parents (a ``<pkg>/urdf/robot.urdf`` layout), the
    ``example-robot-data`` folders when that package is installed, and ``$ROS_PACKAGE_PATH``
    (the same search as the collision geometry, :func:`swarm_ik.paths.package_dirs`).
    """
    return paths.package_dirs(robot.urdf_path)


def visual_model(robot: RobotModel) -> Any:
    """Pinocchio visual geometry model of the robot's full URDF model.

    Raises:
        RobotModelError: a mesh cannot be found (the message names it).
    """
    try:
        return pin.buildGeomFromUrdf(
            robot.full_model,
            str(robot.urdf_path),
            pin.GeometryType.VISUAL,
            package_dirs=package_dirs(robot),
        )
    except ValueError as exc:
        raise RobotModelError(
            f"{robot.urdf_path}: cannot load the visual geometry ({exc}); searched "
            f"{package_dirs(robot)} (add the package folder to ROS_PACKAGE_PATH)"
        ) from None


def full_configuration(robot: RobotModel, q: Any) -> FloatArray:
    """Configuration of ``robot.full_model`` for ``q``: :meth:`RobotModel.full_configuration`."""
    return robot.full_configuration(q)


def reach_length(robot: RobotModel) -> float:
    """A length scale of the robot [m]: the sum of its joint offsets (at least 0.2)."""
    return max(0.2, robot.reach_radius(base=False))


def rgb_int(rgb: Any) -> int:
    """``0xRRGGBB`` of an RGB(A) colour in ``[0, 1]``."""
    r, g, b = (int(round(255 * min(1.0, max(0.0, float(c))))) for c in rgb[:3])
    return r * 65536 + g * 256 + b


@functools.lru_cache(maxsize=1)
def shape_loader() -> type:
    """Pinocchio's meshcat loader, each shape one node below the node that gets placed.

    meshcat's ``set_transform`` replaces the matrix of the object at a path, and Pinocchio
    puts primitive shapes (cylinders along z where three.js has y) there with a built-in
    rotation: placing the parent node instead keeps that rotation.
    """
    with sigint_deferred():  # (pinocchio.visualize's imports guard one with a bare except,
        # which took a Ctrl-C arriving meanwhile: the command ran on and exited 0)
        from pinocchio.visualize import MeshcatVisualizer

    class ShapeLoader(MeshcatVisualizer):  # type: ignore[misc]
        def node_of(self, geometry_object: Any) -> str:
            return str(super().getViewerNodeName(geometry_object, pin.GeometryType.VISUAL))

        def getViewerNodeName(self, geometry_object: Any, geometry_type: Any) -> str:  # noqa: N802
            return str(super().getViewerNodeName(geometry_object, geometry_type)) + "/shape"

        def updatePlacements(self, geometry_type: Any) -> None:  # noqa: N802
            """Placements are set by :class:`RobotDrawing` (on the parent nodes)."""

        def loadViewerGeometryObject(  # noqa: N802
            self, geometry_object: Any, geometry_type: Any, color: Any = None
        ) -> None:
            """Pinocchio's loader, except that a colour override also recolours mesh files
            (Pinocchio drops the material of a Collada file): the mesh is sent as plain
            geometry with the override's material."""
            import meshcat.geometry as mg

            ext = Path(geometry_object.meshPath).suffix.lower()
            kinds = {
                ".dae": mg.DaeMeshGeometry,
                ".stl": mg.StlMeshGeometry,
                ".obj": mg.ObjMeshGeometry,
            }
            if color is None or ext not in kinds or not Path(geometry_object.meshPath).is_file():
                super().loadViewerGeometryObject(geometry_object, geometry_type, color)
                return
            rgba = np.asarray(color, dtype=float)
            material = mg.MeshPhongMaterial(
                color=rgb_int(rgba), opacity=float(rgba[3]), transparent=float(rgba[3]) < 1.0
            )
            shape = kinds[ext].from_file(geometry_object.meshPath)
            self.viewer[self.getViewerNodeName(geometry_object, geometry_type)].set_object(
                shape, material
            )

    return ShapeLoader
