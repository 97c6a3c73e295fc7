"""Obstacles around the robot: spheres, boxes, capsules, cylinders and meshes, in the world
frame (the robot's root frame), read from and written to JSON.

>>> from swarm_ik.scene import Box, Scene, Sphere
>>> table = Box(size=(1.0, 0.6, 0.02), pose=(0.5, 0.0, -0.011))
>>> scene = Scene([table, Sphere(0.05, (0.4, 0.0, 0.3))])
>>> [o.kind for o in scene], scene.names
(['box', 'sphere'], ('box0', 'sphere1'))

Poses are 4x4 homogeneous transforms (a 3-vector is taken as a pure translation).  Capsules
and cylinders run along their local z axis, centred on the pose origin, as in URDF and coal;
``length`` is the length of the straight part [m].  A box ``size`` is its full edge lengths
[m] (URDF convention).  Every shape is a frozen dataclass validated on construction; bad
values raise :class:`~swarm_ik.errors.InvalidArgumentError` (or
:class:`SceneFileNotFoundError` for a mesh file that does not exist), one line naming the
value.

JSON layout (``Scene.to_json`` / ``Scene.from_json``)::

    {"format": "swarm_ik.scene", "version": 1,
     "obstacles": [{"type": "box", "size": [1, 0.6, 0.02], "pose": [[1,0,0,0.5], ...]},
                   {"type": "sphere", "radius": 0.05, "center": [0.4, 0, 0.3]},
                   {"type": "mesh", "path": "shelf.stl", "pose": ..., "scale": [1, 1, 1]}]}

A relative mesh path in a JSON file is read relative to the file's folder.
"""

from __future__ import annotations

import json
import math
import os
import reprlib
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from swarm_ik.errors import InvalidArgumentError, SwarmIKError, unknown

FloatArray = NDArray[np.float64]
Matrix4 = tuple[tuple[float, ...], ...]
"""A 4x4 rigid transform as 4 rows of 4 numbers."""

FORMAT = "swarm_ik.scene"
VERSION = 1


class SceneFileNotFoundError(SwarmIKError, FileNotFoundError):
    """A scene file, or a mesh file named by a scene, that does not exist."""


# --------------------------------------------------------------------------- validation
def _positive(kind: str, what: str, value: Any) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InvalidArgumentError(
            f"{kind}: {what} must be a positive number [m], got {reprlib.repr(value)}"
        ) from None
    if not (math.isfinite(v) and v > 0.0):
        raise InvalidArgumentError(f"{kind}: {what} must be a positive number [m], got {v}")
    return v


def _vector(kind: str, what: str, value: Any, positive: bool = False) -> tuple[float, ...]:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        arr = np.array([])
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise InvalidArgumentError(
            f"{kind}: {what} must be 3 finite numbers, got {reprlib.repr(value)}"
        )
    if positive and not np.all(arr > 0.0):
        raise InvalidArgumentError(
            f"{kind}: {what} must be 3 positive numbers [m], got {arr.tolist()}"
        )
    return tuple(float(v) for v in arr)


def _pose(kind: str, value: Any) -> Matrix4:
    """A rigid transform as a tuple of 4 rows; ``None`` is the identity, a 3-vector a
    translation."""
    if value is None:
        value = np.eye(4)
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        arr = np.array([])
    if arr.shape == (3,):
        t = np.eye(4)
        t[:3, 3] = arr
        arr = t
    if arr.shape != (4, 4) or not np.all(np.isfinite(arr)):
        raise InvalidArgumentError(
            f"{kind}: pose must be a 4x4 homogeneous transform or a 3-vector translation, "
            f"got {reprlib.repr(value)}"
        )
    rot = arr[:3, :3]
    if (
        not np.allclose(rot.T @ rot, np.eye(3), atol=1e-6)
        or np.linalg.det(rot) < 0.0
        or not np.allclose(arr[3], [0.0, 0.0, 0.0, 1.0])
    ):
        raise InvalidArgumentError(
            f"{kind}: pose is not a rigid transform (its 3x3 block must be a rotation and its "
            f"last row [0, 0, 0, 1]), got {arr.tolist()}"
        )
    return tuple(tuple(float(v) for v in row) for row in arr)


# ------------------------------------------------------------------------------ shapes
@dataclass(frozen=True)
class Sphere:
    """A sphere of ``radius`` [m] centred at ``center`` (world frame, [m])."""

    radius: float
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    name: str | None = None
    kind: ClassVar[str] = "sphere"

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _positive("sphere", "radius", self.radius))
        object.__setattr__(self, "center", _vector("sphere", "center", self.center))

    @property
    def pose(self) -> FloatArray:
        """4x4 transform of the centre (identity rotation)."""
        t = np.eye(4)
        t[:3, 3] = self.center
        return t


@dataclass(frozen=True)
class Box:
    """A box with full edge lengths ``size`` (3,) [m], centred on ``pose`` (4x4)."""

    size: tuple[float, float, float]
    pose: Matrix4 = None  # type: ignore[assignment]  # validated in __post_init__
    name: str | None = None
    kind: ClassVar[str] = "box"

    def __post_init__(self) -> None:
        object.__setattr__(self, "size", _vector("box", "size", self.size, positive=True))
        object.__setattr__(self, "pose", _pose("box", self.pose))


@dataclass(frozen=True)
class _Rod:
    """The fields and checks of :class:`Capsule` and :class:`Cylinder`: a ``radius`` and a
    ``length`` [m] along the local z axis of ``pose``, centred on its origin (the messages
    name the subclass's ``kind``)."""

    radius: float
    length: float
    pose: Matrix4 = None  # type: ignore[assignment]  # validated in __post_init__
    name: str | None = None
    kind: ClassVar[str]

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _positive(self.kind, "radius", self.radius))
        object.__setattr__(self, "length", _positive(self.kind, "length", self.length))
        object.__setattr__(self, "pose", _pose(self.kind, self.pose))


@dataclass(frozen=True)
class Capsule(_Rod):
    """A capsule: the points within ``radius`` [m] of a segment of ``length`` [m] along the
    local z axis of ``pose``, centred on its origin."""

    kind: ClassVar[str] = "capsule"


@dataclass(frozen=True)
class Cylinder(_Rod):
    """A solid cylinder of ``radius`` and ``length`` [m] along the local z axis of ``pose``,
    centred on its origin."""

    kind: ClassVar[str] = "cylinder"


@dataclass(frozen=True)
class Mesh:
    """A triangle mesh file (STL, OBJ, DAE, … anything coal's assimp loader reads), scaled by
    ``scale`` (a number or 3 numbers) and placed at ``pose``.  The path is stored absolute."""

    path: str
    pose: Matrix4 = None  # type: ignore[assignment]  # validated in __post_init__
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    name: str | None = None
    kind: ClassVar[str] = "mesh"

    def __post_init__(self) -> None:
        p = Path(os.fspath(self.path)).expanduser()
        if not p.is_file():
            raise SceneFileNotFoundError(f"mesh: file not found: {str(p)!r}")
        object.__setattr__(self, "path", str(p.resolve()))
        scale = self.scale
        if isinstance(scale, (int, float)):
            scale = (scale, scale, scale)
        object.__setattr__(self, "scale", _vector("mesh", "scale", scale, positive=True))
        object.__setattr__(self, "pose", _pose("mesh", self.pose))


Shape = Sphere | Box | Capsule | Cylinder | Mesh
SHAPES: dict[str, type] = {c.kind: c for c in (Sphere, Box, Capsule, Cylinder, Mesh)}
"""Shape classes by their JSON ``type``."""


def shape_pose(shape: Shape) -> FloatArray:
    """The 4x4 world pose of a shape (for a sphere: its centre, identity rotation)."""
    return np.array(shape.pose, dtype=float)


# ------------------------------------------------------------------------------- scene
class Scene:
    """An immutable collection of obstacles.

    Args:
        obstacles: Shapes of :mod:`swarm_ik.scene` (``Sphere``, ``Box``, ``Capsule``,
            ``Cylinder``, ``Mesh``).  Unnamed shapes are named ``<kind><index>``.

    Raises:
        InvalidArgumentError: an item is not a shape, or two shapes have the same name.
    """

    def __init__(self, obstacles: Iterable[Shape] = ()) -> None:
        items = tuple(obstacles)
        names: list[str] = []
        for i, o in enumerate(items):
            if not isinstance(o, tuple(SHAPES.values())):
                raise InvalidArgumentError(
                    f"scene item {i} is a {type(o).__name__} ({reprlib.repr(o)}); expected one of "
                    + ", ".join(c.__name__ for c in SHAPES.values())
                )
            names.append(o.name if o.name else f"{o.kind}{i}")
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise InvalidArgumentError(f"scene: obstacle name(s) {dup} used more than once")
        self._obstacles: tuple[Shape, ...] = items
        self._names: tuple[str, ...] = tuple(names)
        self._coal: list[tuple[str, Any]] | None = None

    @property
    def obstacles(self) -> tuple[Shape, ...]:
        """The shapes, in order."""
        return self._obstacles

    @property
    def names(self) -> tuple[str, ...]:
        """One name per obstacle (its ``name``, or ``<kind><index>``)."""
        return self._names

    def __iter__(self) -> Iterator[Shape]:
        return iter(self._obstacles)

    def __len__(self) -> int:
        return len(self._obstacles)

    def __getitem__(self, i: int) -> Shape:
        return self._obstacles[i]

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Scene) and other._obstacles == self._obstacles

    def __hash__(self) -> int:
        return hash(self._obstacles)

    def __repr__(self) -> str:
        return f"Scene({list(self._obstacles)!r})"

    # ------------------------------------------------------------------------ JSON
    def to_dict(self) -> dict[str, Any]:
        """The JSON-ready description (see the module docstring)."""
        out = []
        for o in self._obstacles:
            d: dict[str, Any] = {"type": o.kind}
            if o.name:
                d["name"] = o.name
            if isinstance(o, Sphere):
                d.update(radius=o.radius, center=list(o.center))
            elif isinstance(o, Box):
                d.update(size=list(o.size), pose=[list(r) for r in o.pose])
            elif isinstance(o, (Capsule, Cylinder)):
                d.update(radius=o.radius, length=o.length, pose=[list(r) for r in o.pose])
            else:
                d.update(path=o.path, pose=[list(r) for r in o.pose], scale=list(o.scale))
            out.append(d)
        return {"format": FORMAT, "version": VERSION, "obstacles": out}

    @classmethod
    def from_dict(cls, data: Any, base_dir: str | os.PathLike[str] | None = None) -> Scene:
        """Build a scene from :meth:`to_dict`'s layout.

        Args:
            data: The parsed JSON.
            base_dir: Folder against which relative mesh paths are resolved (default: the
                working directory).

        Raises:
            InvalidArgumentError: wrong layout, a missing or unexpected field, a bad value.
            UnknownNameError: an unknown shape ``type`` (the valid ones listed).
            SceneFileNotFoundError: a mesh file that does not exist.
        """
        if isinstance(data, list):
            items = data
        elif isinstance(data, dict) and isinstance(data.get("obstacles"), list):
            fmt = data.get("format", FORMAT)
            if fmt != FORMAT:
                raise InvalidArgumentError(f"scene: format is {fmt!r}, expected {FORMAT!r}")
            items = data["obstacles"]
        else:
            raise InvalidArgumentError(
                'scene: expected {"obstacles": [...]} (or a list of obstacles), got '
                f"{reprlib.repr(data)}"
            )
        shapes: list[Shape] = []
        for i, item in enumerate(items):
            if not isinstance(item, dict) or "type" not in item:
                raise InvalidArgumentError(
                    f"scene: obstacle {i} must be an object with a 'type', got {reprlib.repr(item)}"
                )
            kind = item["type"]
            if kind not in SHAPES:
                raise unknown("shape type", kind, SHAPES)
            fields = {k: v for k, v in item.items() if k != "type"}
            if kind == "mesh" and "path" in fields and base_dir is not None:
                p = Path(str(fields["path"])).expanduser()
                if not p.is_absolute():
                    fields["path"] = str(Path(base_dir) / p)
            try:
                shapes.append(SHAPES[kind](**fields))
            except TypeError as exc:
                raise InvalidArgumentError(f"scene: obstacle {i} ({kind}): {exc}") from None
        return cls(shapes)

    def to_json(self, path: str | os.PathLike[str]) -> Path:
        """Write the scene to a JSON file; returns its path."""
        p = Path(path)
        p.write_text(json.dumps(self.to_dict(), indent=1) + "\n")
        return p

    @classmethod
    def from_json(cls, path: str | os.PathLike[str]) -> Scene:
        """Read a scene written by :meth:`to_json` (or by hand).

        Raises:
            SceneFileNotFoundError: the file (or a mesh it names) does not exist.
            InvalidArgumentError: not JSON, or a bad obstacle (see :meth:`from_dict`).
        """
        p = Path(path)
        if not p.is_file():
            raise SceneFileNotFoundError(f"scene file not found: {str(p)!r}")
        try:
            data = json.loads(p.read_text())
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise InvalidArgumentError(f"{p}: not a JSON file ({exc})") from None
        return cls.from_dict(data, base_dir=p.resolve().parent)

    # ------------------------------------------------------------------------ coal
    def coal_objects(self) -> list[tuple[str, Any]]:
        """The obstacles as coal collision objects (geometry + world transform), for the exact
        check; built once per scene.

        Returns:
            ``[(name, coal.CollisionObject), ...]`` in obstacle order.
        """
        if self._coal is None:
            self._coal = [
                (n, coal_object(o)) for n, o in zip(self._names, self._obstacles, strict=True)
            ]
        return self._coal

    def bounds(self) -> FloatArray:
        """Axis-aligned bounds of all obstacles ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``
        [m] (from coal's AABBs); ``(2, 3)`` of NaN for an empty scene."""
        if not self._obstacles:
            return np.full((2, 3), np.nan)
        lo, hi = [], []
        for _, obj in self.coal_objects():
            obj.computeAABB()
            box = obj.getAABB()
            lo.append(np.array(box.min_))
            hi.append(np.array(box.max_))
        return np.array([np.min(lo, axis=0), np.max(hi, axis=0)])


def coal_geometry(shape: Shape) -> Any:
    """The coal geometry of one shape, in its own frame."""
    import coal

    if isinstance(shape, Sphere):
        return coal.Sphere(shape.radius)
    if isinstance(shape, Box):
        return coal.Box(*shape.size)
    if isinstance(shape, Capsule):
        return coal.Capsule(shape.radius, shape.length)
    if isinstance(shape, Cylinder):
        return coal.Cylinder(shape.radius, shape.length)
    loader = coal.MeshLoader()
    mesh = loader.load(shape.path, np.array(shape.scale))
    return mesh


def coal_object(shape: Shape) -> Any:
    """A ``coal.CollisionObject`` of one shape at its world pose."""
    import coal

    pose = shape_pose(shape)
    tf = coal.Transform3s(pose[:3, :3].copy(), pose[:3, 3].copy())
    return coal.CollisionObject(coal_geometry(shape), tf)


def as_scene(scene: Scene | Sequence[Shape] | str | os.PathLike[str] | None) -> Scene:
    """A :class:`Scene` from a scene, a list of shapes, a JSON path, or ``None`` (empty)."""
    if scene is None:
        return Scene()
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, (str, os.PathLike)):
        return Scene.from_json(scene)
    return Scene(scene)
