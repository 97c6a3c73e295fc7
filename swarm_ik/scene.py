"""Obstacles around the robot: spheres, boxes, capsules, cylinders and meshes, in the world
frame (the robot's root frame), read from and written to files.

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
value; sizes and position coordinates are at most :data:`MAX_LENGTH` (10 km).

Files (:meth:`Scene.load` / :meth:`Scene.save`, the layouts in ``docs/scenes.md``):

* swarm_ik's JSON (``.json``)::

    {"format": "swarm_ik.scene", "version": 1,
     "obstacles": [{"type": "Box", "size": [1, 0.6, 0.02], "pose": [[1,0,0,0.5], ...]},
                   {"type": "Sphere", "radius": 0.05, "center": [0.4, 0, 0.3]},
                   {"type": "Mesh", "path": "shelf.stl", "pose": ..., "scale": [1, 1, 1]}]}

  ``type`` is the class name (the lowercase ``"box"``, ``"sphere"``, … of older files are
  read too); a relative mesh path is read relative to the file's folder.
* cuRobo's world YAML (``.yml``, ``.yaml``; read and written; needs PyYAML).
* MoveIt's ``.scene`` text (both layouts: with and without the object pose line; read only).
* a URDF of fixed obstacles (``.urdf``; every link's collision geometry at the zero
  configuration; read only).

A file with no obstacles is refused (a URDF without ``<collision>`` elements, a MoveIt scene
without shapes, an empty YAML file) unless it says so: the JSON ``{"obstacles": []}`` and the
YAML ``{}`` that :meth:`Scene.save` writes for an empty scene are read back.
"""

from __future__ import annotations

import collections
import functools
import hashlib
import json
import math
import os
import re
import reprlib
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from swarm_ik._types import FloatArray
from swarm_ik._validate import json_int, one_line
from swarm_ik.errors import InvalidArgumentError, SwarmIKError, UnknownNameError
from swarm_ik.paths import written_in_place_of
from swarm_ik.pose import unit, unit_quaternion_matrix

Matrix4 = tuple[tuple[float, ...], ...]
"""A 4x4 rigid transform as 4 rows of 4 numbers."""

FORMAT = "swarm_ik.scene"
VERSION = 1
MAX_FILE_BYTES = 64 * 2**20
"""Largest scene file read [bytes] (64 MiB): larger files are refused before reading."""
MAX_DEPTH = 32
"""Deepest nesting of lists and mappings in a JSON or YAML scene."""
MAX_NODES = 5_000_000
"""Most values in a parsed JSON or YAML scene (YAML aliases counted at every use)."""
MAX_LENGTH = 1e4
"""Largest size (a radius, a length, a box edge) and largest coordinate of a position [m] of
an obstacle: 10 km, in every format and in the shapes' constructors.  No robot's scene is that
large (a factory floor, a ground plane of a kilometre fit well within it), so a larger value is
a unit error or a stand-in for "infinite" (``1e308``), and such values break the collision
checks: a sphere of radius 1e308 m made each solve print Eigen's "too many iterations in
Jacobi transform" on stderr, a box 1e16 m away made coal's broadphase raise.  Within it,
float64 still resolves positions to about 2e-12 m.  (A mesh's size is its file's times
``scale``, bounded by :data:`MESH_SCALE`.)"""


class SceneFileNotFoundError(SwarmIKError, FileNotFoundError):
    """A scene file, or a mesh file named by a scene, that does not exist."""


class SceneDependencyError(SwarmIKError, ImportError):
    """A scene format whose reader needs a package that is not installed (PyYAML)."""


# --------------------------------------------------------------------------- validation
def _is_number(value: Any) -> bool:
    """A real number: int or float (numpy's too), never a bool nor a string."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
        value, (bool, np.bool_)
    )


def _as_float(value: Any) -> float:
    try:
        return float(value)
    except OverflowError:  # an int beyond the float range
        return math.inf if value > 0 else -math.inf


def _float_array(value: Any, shape: tuple[int, ...]) -> FloatArray | None:
    """``value`` as a float array of ``shape`` when it is nested lists/tuples (or a numeric
    array, or an object numpy converts such as ``pinocchio.SE3``) of real numbers; ``None``
    otherwise (strings, booleans, ragged or wrong sizes)."""
    if not isinstance(value, (np.ndarray, list, tuple)) and hasattr(value, "__array__"):
        try:
            value = np.asarray(value)
        except Exception:  # whatever a foreign __array__ raises: not numbers
            return None
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in "iuf" or value.shape != shape:
            return None
        return value.astype(float)
    if not shape:
        return np.array(_as_float(value)) if _is_number(value) else None
    if not isinstance(value, (list, tuple)) or len(value) != shape[0]:
        return None
    parts = [_float_array(v, shape[1:]) for v in value]
    if any(p is None for p in parts):
        return None
    return np.array(parts, dtype=float).reshape(shape)


def _too_large(
    kind: str, what: str, got: float | list[float], size: bool = True
) -> InvalidArgumentError:
    """The refusal of a size (``size``) or a position beyond :data:`MAX_LENGTH` (``got``: a
    number or 3)."""
    if size:
        bound = f"at most {MAX_LENGTH:g} m" + ("" if isinstance(got, float) else " each")
    else:
        bound = f"within ±{MAX_LENGTH:g} m in each coordinate"
    shown = f"{got:g}" if isinstance(got, float) else str(got)
    return InvalidArgumentError(
        f"{kind}: {what} must be {bound} (swarm_ik.scene.MAX_LENGTH: no robot's scene is that "
        f"large; a unit error?), got {shown}"
    )


def _positive(kind: str, what: str, value: Any) -> float:
    if not _is_number(value):
        raise InvalidArgumentError(
            f"{kind}: {what} must be a positive number [m], got {reprlib.repr(value)}"
        )
    v = _as_float(value)
    if not (math.isfinite(v) and v > 0.0):
        raise InvalidArgumentError(f"{kind}: {what} must be a positive number [m], got {v}")
    if v > MAX_LENGTH:
        raise _too_large(kind, what, v)
    return v


def _vector(
    kind: str, what: str, value: Any, positive: bool = False, bounded: bool = True
) -> tuple[float, ...]:
    """3 finite numbers (``positive``: each > 0; ``bounded``: each within ±:data:`MAX_LENGTH`,
    a size or a position in metres)."""
    arr = _float_array(value, (3,))
    if arr is None or not np.all(np.isfinite(arr)):
        raise InvalidArgumentError(
            f"{kind}: {what} must be 3 finite numbers, got {reprlib.repr(value)}"
        )
    if positive and not np.all(arr > 0.0):
        raise InvalidArgumentError(
            f"{kind}: {what} must be 3 positive numbers [m], got {arr.tolist()}"
        )
    if bounded and not np.all(np.abs(arr) <= MAX_LENGTH):
        raise _too_large(kind, what, arr.tolist(), size=positive)
    return tuple(float(v) for v in arr)


def _pose(kind: str, value: Any) -> Matrix4:
    """A rigid transform as a tuple of 4 rows; ``None`` is the identity, a 3-vector a
    translation."""
    if value is None:
        value = np.eye(4)
    arr = _float_array(value, (3,))
    if arr is not None:
        t = np.eye(4)
        t[:3, 3] = arr
        arr = t
    else:
        arr = _float_array(value, (4, 4))
    if arr is None or not np.all(np.isfinite(arr)):
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
        off = float(np.abs(rot.T @ rot - np.eye(3)).max())
        raise InvalidArgumentError(
            f"{kind}: pose is not a rigid transform (its 3x3 block must be a rotation, "
            f"orthonormal within 1e-6: it is off by {off:.1g}, determinant "
            f"{np.linalg.det(rot):.6g}; and its last row [0, 0, 0, 1]): give the rotation with "
            f"more digits, or the pose as a position and a quaternion, got {arr.tolist()}"
        )
    if not np.all(np.abs(arr[:3, 3]) <= MAX_LENGTH):
        raise _too_large(kind, "pose position", arr[:3, 3].tolist(), size=False)
    return tuple(tuple(float(v) for v in row) for row in arr)


def _name(kind: str, value: Any) -> str | None:
    if value is None:
        return None
    if not isinstance(value, str) or not value:
        raise InvalidArgumentError(
            f"{kind}: name must be a non-empty string (or None), got {reprlib.repr(value)}"
        )
    return value


def _quat_matrix(value: Any, order: str) -> FloatArray:
    """Rotation matrix of a quaternion given as 4 numbers in ``order`` (``"wxyz"`` or
    ``"xyzw"``), normalised; a zero (or non-finite) quaternion is refused."""
    q = _float_array(value, (4,))
    if q is None or not np.all(np.isfinite(q)):
        raise InvalidArgumentError(
            f"quaternion must be 4 finite numbers ({', '.join(order)}), got {reprlib.repr(value)}"
        )
    u = unit(q)
    if u is None:
        raise InvalidArgumentError(f"quaternion ({', '.join(order)}) has zero norm: {q.tolist()}")
    w, x, y, z = u if order == "wxyz" else u[[3, 0, 1, 2]]
    return unit_quaternion_matrix(x, y, z, w)


def _matrix_quat_wxyz(rot: Any) -> FloatArray:
    """Unit quaternion ``(w, x, y, z)`` with ``w >= 0`` of a rotation matrix (Shepperd)."""
    r = np.asarray(rot, dtype=float)
    tr = float(np.trace(r))
    if tr > 0.0:
        s = 2.0 * math.sqrt(tr + 1.0)
        q = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = [(r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s]
    elif r[1, 1] > r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = [(r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s]
    else:
        s = 2.0 * math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = [(r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s]
    out = np.array(q) / np.linalg.norm(q)
    return -out if out[0] < 0.0 else out


def _m4(a: Any) -> Matrix4:
    """A 4x4 array as the rows tuple the shapes hold (their constructors check it)."""
    return tuple(tuple(float(v) for v in row) for row in np.asarray(a, dtype=float))


def _v3(a: Any) -> tuple[float, float, float]:
    """3 numbers as the tuple the shapes hold (their constructors check them)."""
    x, y, z = (float(v) for v in np.asarray(a, dtype=float))
    return (x, y, z)


def _transform(rot: Any, pos: Any) -> FloatArray:
    t = np.eye(4)
    t[:3, :3] = rot
    t[:3, 3] = pos
    return t


def _z_to(d: FloatArray) -> FloatArray:
    """A rotation taking the z axis onto the unit vector ``d`` (identity for +z)."""
    flip = d[2] < 0.0  # rotate by pi about x first: Rodrigues stays far from its singularity
    f = np.diag([1.0, -1.0, -1.0])
    e = f @ d if flip else d
    v = np.array([-e[1], e[0], 0.0])  # z x e
    vx = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    r = np.eye(3) + vx + vx @ vx / (1.0 + e[2])
    return f @ r if flip else r


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
        object.__setattr__(self, "name", _name("sphere", self.name))

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
        object.__setattr__(self, "name", _name("box", self.name))


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
        object.__setattr__(self, "name", _name(self.kind, self.name))


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
    digest: str = field(default="", init=False, repr=False)
    """SHA-256 of the file's bytes when the mesh was made: two meshes of one path are equal
    only if the file did not change between them (a file rewritten in place was judged by
    the collision model cached for its old content)."""
    geometry: Any = field(default=None, init=False, repr=False, compare=False)
    """coal's model of the file as it was read when the mesh was made (scaled): every use of
    the mesh is of this content, whatever the file holds later (a file rewritten after the
    mesh was made, then read again at its first use, put other content under the digest of
    the first: an answer inside the obstacle was judged free).  Pickled without it: the file
    is read again where it is unpickled, and refused if its digest differs."""
    kind: ClassVar[str] = "mesh"

    def __getstate__(self) -> dict[str, Any]:
        return {k: v for k, v in self.__dict__.items() if k != "geometry"}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        geometry, digest = _read_mesh(Path(self.path), self.scale)
        if digest != self.digest:
            raise InvalidArgumentError(
                f"mesh {self.path!r}: the file changed since the mesh was made (its SHA-256 "
                "differs); load the scene again"
            )
        object.__setattr__(self, "geometry", geometry)

    def __post_init__(self) -> None:
        raw = self.path
        if not isinstance(raw, (str, os.PathLike)) or not os.fsdecode(raw):
            raise InvalidArgumentError(
                f"mesh: path must be a file path (a string), got {reprlib.repr(raw)}"
            )
        p = _expanded(os.fsdecode(raw), "mesh path")
        if p.is_dir():
            raise InvalidArgumentError(f"mesh: path {str(p)!r} is a folder, not a mesh file")
        if not p.is_file():
            raise SceneFileNotFoundError(f"mesh: file not found: {str(p)!r}")
        object.__setattr__(self, "path", str(p.resolve()))
        scale: Any = self.scale
        if _is_number(scale):
            scale = (scale, scale, scale)
        object.__setattr__(
            self, "scale", _vector("mesh", "scale", scale, positive=True, bounded=False)
        )
        if not all(MESH_SCALE[0] <= v <= MESH_SCALE[1] for v in self.scale):
            raise InvalidArgumentError(
                f"mesh: scale must be in [{MESH_SCALE[0]:g}, {MESH_SCALE[1]:g}] "
                f"(swarm_ik.scene.MESH_SCALE), got {list(self.scale)}"
            )
        object.__setattr__(self, "pose", _pose("mesh", self.pose))
        object.__setattr__(self, "name", _name("mesh", self.name))
        geometry, digest = _read_mesh(p, self.scale)
        object.__setattr__(self, "geometry", geometry)
        object.__setattr__(self, "digest", digest)
        # its vertices as coal reads them, scaled: finite and within MAX_LENGTH (a NaN vertex
        # printed Eigen's complaints on each solve and made every configuration "in contact")
        vertices = np.asarray(geometry.vertices(), dtype=float)
        if not np.isfinite(vertices).all():
            raise InvalidArgumentError(f"mesh {str(p)!r}: its vertices hold NaN or infinite values")
        if vertices.size and float(np.abs(vertices).max()) > MAX_LENGTH:
            raise InvalidArgumentError(
                f"mesh {str(p)!r}: a vertex lies {float(np.abs(vertices).max()):g} m from its "
                f"origin after scale {list(self.scale)}, beyond {MAX_LENGTH:g} m "
                "(swarm_ik.scene.MAX_LENGTH; a unit error?)"
            )


MESH_SCALE = (1e-6, 1e6)
"""Smallest and largest scale factor of a mesh (a scale of 1e300 overflowed the sphere fit,
which then never returned)."""

Shape = Sphere | Box | Capsule | Cylinder | Mesh
SHAPES: dict[str, type] = {c.kind: c for c in (Sphere, Box, Capsule, Cylinder, Mesh)}
"""Shape classes by their ``kind`` (the lowercase JSON ``type`` of older files)."""
SHAPE_TYPES: dict[str, type] = {c.__name__: c for c in SHAPES.values()}
"""Shape classes by their JSON ``type`` (the class name)."""
_TYPE_NAME = {k: c.__name__ for k, c in SHAPES.items()}
_JSON_FIELDS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "sphere": (("radius",), ("center", "name")),
    "box": (("size",), ("pose", "name")),
    "capsule": (("radius", "length"), ("pose", "name")),
    "cylinder": (("radius", "length"), ("pose", "name")),
    "mesh": (("path",), ("pose", "scale", "name")),
}
"""Per shape kind: its required and optional JSON fields (besides ``type``)."""


def shape_pose(shape: Shape) -> FloatArray:
    """The 4x4 world pose of a shape (for a sphere: its centre, identity rotation)."""
    return np.array(shape.pose, dtype=float)


@contextmanager
def _context(prefix: str) -> Iterator[None]:
    """Prefix the message of a swarm_ik error raised inside (same class, one line)."""
    try:
        yield
    except SwarmIKError as exc:
        raise type(exc)(one_line(f"{prefix}: {exc}")) from None


def _check_fields(where: str, given: Mapping[Any, Any], required: Sequence[str],
                  optional: Sequence[str]) -> None:  # fmt: skip
    """Refuse keys that are not strings, unknown keys (the valid ones listed) and missing
    required keys."""
    at = f"{where}: " if where else ""
    valid = [*required, *optional]
    bad = [k for k in given if not isinstance(k, str) or k not in valid]
    if bad:
        raise InvalidArgumentError(
            f"{at}unknown field(s) {sorted(map(str, bad))}; valid fields: {', '.join(valid)}"
        )
    missing = [k for k in required if k not in given]
    if missing:
        raise InvalidArgumentError(f"{at}missing field(s) {missing}")


def _check_tree(data: Any, where: str) -> None:
    """Refuse parsed JSON/YAML nested deeper than :data:`MAX_DEPTH` or holding more than
    :data:`MAX_NODES` values (counted at every use: a YAML alias bomb is caught without being
    walked more than once per distinct node)."""
    sizes: dict[int, int] = {}

    def size(node: Any, depth: int) -> int:
        if depth > MAX_DEPTH:
            raise InvalidArgumentError(
                f"{where}: nested more than {MAX_DEPTH} levels deep (a scene needs about 5)"
            )
        if not isinstance(node, (list, tuple, dict)):
            return 1
        key = id(node)
        if key in sizes:
            return sizes[key]
        children = list(node.values()) if isinstance(node, dict) else node
        n = 1 + sum(size(c, depth + 1) for c in children)
        if n > MAX_NODES:
            raise InvalidArgumentError(f"{where}: more than {MAX_NODES} values; too large a scene")
        sizes[key] = n
        return n

    size(data, 0)


def _json_pose(value: Any) -> Any:
    """A JSON pose: 4x4 rows, a 3-vector, or ``{"position": [x, y, z], "quaternion": [qx, qy,
    qz, qw]}`` as in the goals' JSON (the quaternion normalised)."""
    if not isinstance(value, Mapping):
        return value
    keys = set(value)
    if keys != {"position", "quaternion"}:
        raise InvalidArgumentError(
            "pose given as an object needs exactly the fields position, quaternion (x, y, z, w); "
            f"got {sorted(map(str, keys))}"
        )
    pos = _float_array(value["position"], (3,))
    if pos is None or not np.all(np.isfinite(pos)):
        raise InvalidArgumentError(
            f"pose position must be 3 finite numbers, got {reprlib.repr(value['position'])}"
        )
    return _transform(_quat_matrix(value["quaternion"], "xyzw"), pos)


# ------------------------------------------------------------------------------- scene
def _not_shapes(value: Any) -> str:
    """Why ``value`` is no ``obstacles`` of :class:`Scene` (one line; where to turn instead)."""
    head = (
        "Scene takes a list of shapes ("
        + ", ".join(c.__name__ for c in SHAPES.values())
        + "), got "
    )
    if value is None:
        return head + "None (Scene() is the empty scene)"
    if isinstance(value, Mapping):
        return (
            f"{head}a {type(value).__name__}; read a scene's JSON dict with "
            "Scene.from_dict(data), a scene file with Scene.load(path)"
        )
    if isinstance(value, (str, bytes, os.PathLike)):
        return f"{head}{reprlib.repr(value)}; read a scene file with Scene.load(path)"
    return f"{head}{type(value).__name__} {reprlib.repr(value)}"


class Scene:
    """An immutable collection of obstacles.

    Args:
        obstacles: Shapes of :mod:`swarm_ik.scene` (``Sphere``, ``Box``, ``Capsule``,
            ``Cylinder``, ``Mesh``).  Unnamed shapes are named ``<kind><index>``.

    Raises:
        InvalidArgumentError: ``obstacles`` is not a list of shapes (a scene JSON dict:
            :meth:`from_dict`; a file: :meth:`load`), an item is not a shape, or two shapes
            have the same name.
    """

    def __init__(self, obstacles: Iterable[Shape] = ()) -> None:
        if (
            isinstance(obstacles, (Mapping, str, bytes, os.PathLike))
            or (isinstance(obstacles, np.ndarray) and obstacles.dtype != object)
            or not isinstance(obstacles, Iterable)
        ):  # (an array of numbers, even empty, holds no shapes)
            raise InvalidArgumentError(_not_shapes(obstacles))
        items = tuple(obstacles)
        names: list[str] = []
        for i, o in enumerate(items):
            if not isinstance(o, tuple(SHAPES.values())):
                raise InvalidArgumentError(
                    f"scene item {i} is a {type(o).__name__} ({reprlib.repr(o)}); expected one of "
                    + ", ".join(c.__name__ for c in SHAPES.values())
                )
            names.append(o.name if o.name else f"{o.kind}{i}")
        dup = sorted(n for n, k in collections.Counter(names).items() if k > 1)
        if dup:
            unnamed = sorted({names[i] for i, o in enumerate(items) if not o.name} & set(dup))
            why = (
                f" ({unnamed} also the default name of an unnamed obstacle: kind + its index "
                "in the scene; name that one)"
                if unnamed
                else ""
            )
            raise InvalidArgumentError(f"scene: obstacle name(s) {dup} used more than once{why}")
        self._obstacles: tuple[Shape, ...] = items
        self._names: tuple[str, ...] = tuple(names)
        self._coal: list[tuple[str, Any]] | None = None
        self._boxes: tuple[FloatArray, FloatArray] | None = None
        self._hash: int | None = None

    def __getstate__(self) -> dict[str, Any]:
        """Pickled without its coal objects (they cannot be pickled; made again on use)."""
        state = dict(self.__dict__)
        state["_coal"] = None
        state["_hash"] = None  # (a string's hash differs between processes)
        return state

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
        if self._hash is None:  # (a scene keys caches: thousands of obstacles hashed once)
            self._hash = hash(self._obstacles)
        return self._hash

    def __repr__(self) -> str:
        return f"Scene({list(self._obstacles)!r})"

    # ------------------------------------------------------------------------ files
    @classmethod
    def load(cls, path: str | os.PathLike[str], *, mesh_dir: str | os.PathLike[str] | None = None
             ) -> Scene:  # fmt: skip
        """Read a scene file, its format told by the extension (else by its content):

        * ``.json``: swarm_ik's JSON (:meth:`from_json`);
        * ``.yml`` / ``.yaml``: a cuRobo world (``cuboid``, ``sphere``, ``capsule``,
          ``cylinder``, ``mesh``; needs PyYAML);
        * ``.scene``: MoveIt's scene text, either layout (with or without object poses);
        * ``.urdf`` (or ``.xml`` holding a ``<robot>``): every link's collision geometry at
          the zero configuration.

        Args:
            path: The file.
            mesh_dir: Where the triangle meshes written inline in a MoveIt ``.scene`` are
                stored as OBJ files (named by their content's hash; default: the ``scene_meshes``
                folder of :func:`swarm_ik.paths.cache_dir`).

        Raises:
            SceneFileNotFoundError: the file, or a mesh it names, does not exist.
            InvalidArgumentError: a file over :data:`MAX_FILE_BYTES`, unreadable, or a bad
                obstacle (one line naming it and the problem); a file with no obstacles that
                does not say so (a URDF without ``<collision>`` elements, a MoveIt scene
                without shapes, an empty YAML file: an empty scene would turn collision
                avoidance off unnoticed; the JSON ``{"obstacles": []}`` and YAML ``{}`` that
                :meth:`save` writes for an empty scene are read).
            UnknownNameError: an unknown shape type (the valid ones listed).
            SceneDependencyError: a YAML file without PyYAML installed.
        """
        p = _path_arg(path, "scene file")
        suffix = p.suffix.lower()
        fmt = _SUFFIXES.get(suffix)
        text = _read_text(p, decode=fmt != "urdf")  # URDFs: any XML encoding
        if suffix == ".xml":  # (a URDF, told by its bytes: the XML names its own encoding)
            fmt = "urdf" if re.search(rb"<robot[\s>]", _read_bytes(p)) else None
        elif fmt is None:
            fmt = _sniff(text)
        if fmt is None:
            raise InvalidArgumentError(
                f"{p}: cannot tell the scene format; name the file with one of the "
                f"extensions {', '.join(_SUFFIXES)}"
            )
        if fmt == "json":
            return cls.from_dict(_parse_json(text, p), base_dir=p.resolve().parent, where=str(p))
        if fmt == "curobo":
            return _from_curobo(_parse_yaml(text, p), p.resolve().parent, str(p))
        if fmt == "moveit":
            out = None if mesh_dir is None else _path_arg(mesh_dir, "mesh_dir")
            shapes = _from_moveit(text, str(p), out)
        else:
            shapes = _from_urdf(p)
        with _context(str(p)):
            return Scene(shapes)

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the scene: swarm_ik JSON for ``.json``, a cuRobo world for ``.yml`` /
        ``.yaml`` (grouped by type: cuboid, sphere, capsule, cylinder, mesh; unnamed shapes take
        their :attr:`names`); returns the path.

        Raises:
            InvalidArgumentError: another extension.
            SceneDependencyError: YAML without PyYAML installed.
        """
        p = _path_arg(path, "scene file")
        ext = p.suffix.lower()
        if ext == ".json":
            return self.to_json(p)
        if ext not in (".yml", ".yaml"):
            raise InvalidArgumentError(
                f"{p}: scenes are written as .json (swarm_ik) or .yml/.yaml (cuRobo), "
                f"not {ext or 'a file without extension'!r}"
            )
        yaml = _yaml(str(p))
        _write_text(p, yaml.safe_dump(self.to_curobo(), sort_keys=False, default_flow_style=None))
        return p

    # ------------------------------------------------------------------------ JSON
    def to_dict(self) -> dict[str, Any]:
        """The JSON-ready description (see the module docstring)."""
        out = []
        for o in self._obstacles:
            d: dict[str, Any] = {"type": _TYPE_NAME[o.kind]}
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
    def from_dict(
        cls, data: Any, base_dir: str | os.PathLike[str] | None = None, *, where: str = "scene"
    ) -> Scene:
        """Build a scene from :meth:`to_dict`'s layout.

        Args:
            data: The parsed JSON: ``{"format": "swarm_ik.scene", "version": 1,
                "obstacles": [...]}`` (``format`` and ``version`` optional) or the list of
                obstacles alone.
            base_dir: Folder against which relative mesh paths are resolved (default: the
                working directory).
            where: What to name in messages (the file).

        Raises:
            InvalidArgumentError: wrong layout, a missing, unknown or mistyped field, a bad
                value.
            UnknownNameError: an unknown shape ``type`` (the valid ones listed).
            SceneFileNotFoundError: a mesh file that does not exist.
        """
        _check_tree(data, where)
        if isinstance(data, list):
            items = data
        elif isinstance(data, dict):
            _check_fields(where, data, ("obstacles",), ("format", "version"))
            fmt = data.get("format", FORMAT)
            if fmt != FORMAT:
                raise InvalidArgumentError(
                    f"{where}: format is {reprlib.repr(fmt)}, expected {FORMAT!r}"
                )
            version = data.get("version", VERSION)
            if type(version) is not int or version != VERSION:
                raise InvalidArgumentError(
                    f"{where}: version is {reprlib.repr(version)}, expected {VERSION} (the integer)"
                )
            items = data["obstacles"]
            if not isinstance(items, list):
                raise InvalidArgumentError(
                    f"{where}: obstacles must be a list, got {reprlib.repr(items)}"
                )
        else:
            raise InvalidArgumentError(
                f'{where}: expected {{"obstacles": [...]}} (or a list of obstacles), got '
                f"{reprlib.repr(data)}"
            )
        shapes: list[Shape] = []
        for i, item in enumerate(items):
            if not isinstance(item, dict) or "type" not in item:
                raise InvalidArgumentError(
                    f"{where}: obstacle {i} must be an object with a 'type', "
                    f"got {reprlib.repr(item)}"
                )
            given = item["type"]
            if not isinstance(given, str):
                raise InvalidArgumentError(
                    f"{where}: obstacle {i}: type must be a string (one of "
                    f"{', '.join(sorted(SHAPE_TYPES))}), got {reprlib.repr(given)}"
                )
            shape_cls = SHAPE_TYPES.get(given) or SHAPES.get(given)
            if shape_cls is None:
                raise UnknownNameError(
                    f"{where}: unknown shape type {given!r}; valid shape types: "
                    f"{', '.join(sorted(SHAPE_TYPES))} (or their lowercase names)"
                )
            kind: str = shape_cls.kind  # type: ignore[attr-defined]
            fields = {k: v for k, v in item.items() if k != "type"}
            with _context(f"{where}: obstacle {i} ({given})"):
                _check_fields("", fields, *_JSON_FIELDS[kind])
                if "pose" in fields:
                    fields["pose"] = _json_pose(fields["pose"])
                if kind == "mesh":
                    raw = fields["path"]
                    if not isinstance(raw, str):
                        raise InvalidArgumentError(
                            f"path must be a string, got {reprlib.repr(raw)}"
                        )
                    p = _expanded(raw, "mesh path")
                    if base_dir is not None and not p.is_absolute():
                        fields["path"] = str(Path(base_dir) / p)
                shapes.append(shape_cls(**fields))
        with _context(where):
            return cls(shapes)

    def to_json(self, path: str | os.PathLike[str]) -> Path:
        """Write the scene to a JSON file; returns its path."""
        p = _path_arg(path, "scene file")
        _write_text(p, json.dumps(self.to_dict(), indent=1, allow_nan=False) + "\n")
        return p

    @classmethod
    def from_json(cls, path: str | os.PathLike[str]) -> Scene:
        """Read a scene written by :meth:`to_json` (or by hand).

        Raises:
            SceneFileNotFoundError: the file (or a mesh it names) does not exist.
            InvalidArgumentError: not JSON, too large or deep, or a bad obstacle (see
                :meth:`from_dict`).
        """
        p = _path_arg(path, "scene file")
        data = _parse_json(_read_text(p), p)
        return cls.from_dict(data, base_dir=p.resolve().parent, where=str(p))

    # ------------------------------------------------------------------------ cuRobo
    def to_curobo(self) -> dict[str, dict[str, dict[str, Any]]]:
        """The scene as a cuRobo world dictionary (``WorldConfig.from_dict``'s layout: poses
        ``[x, y, z, qw, qx, qy, qz]``, capsules as ``base``/``tip`` on the local z axis, mesh
        paths absolute); unnamed shapes take their :attr:`names`."""
        out: dict[str, dict[str, dict[str, Any]]] = {}
        for name, o in zip(self._names, self._obstacles, strict=True):
            pose = shape_pose(o)
            seven = [*map(float, pose[:3, 3]), *map(float, _matrix_quat_wxyz(pose[:3, :3]))]
            if isinstance(o, Sphere):
                section, d = "sphere", {"radius": o.radius, "pose": seven}
            elif isinstance(o, Box):
                section, d = "cuboid", {"dims": list(o.size), "pose": seven}
            elif isinstance(o, Capsule):
                half = 0.5 * o.length
                d = {"radius": o.radius, "base": [0.0, 0.0, -half], "tip": [0.0, 0.0, half]}
                section, d["pose"] = "capsule", seven
            elif isinstance(o, Cylinder):
                section, d = "cylinder", {"radius": o.radius, "height": o.length, "pose": seven}
            else:
                section = "mesh"
                d = {"file_path": o.path, "scale": list(o.scale), "pose": seven}
            out.setdefault(section, {})[name] = d
        order = ("cuboid", "sphere", "capsule", "cylinder", "mesh")
        return {k: out[k] for k in order if k in out}

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

    def boxes(self) -> tuple[FloatArray, FloatArray]:
        """Each obstacle's axis-aligned box (coal's AABB of its world pose): ``(lo, hi)``,
        each ``(n, 3)`` [m]; computed once per scene."""
        if self._boxes is None:
            lo, hi = [], []
            for _, obj in self.coal_objects():
                obj.computeAABB()
                box = obj.getAABB()
                lo.append(np.array(box.min_))
                hi.append(np.array(box.max_))
            self._boxes = (np.array(lo).reshape(-1, 3), np.array(hi).reshape(-1, 3))
        return self._boxes

    def bounds(self) -> FloatArray:
        """Axis-aligned bounds of all obstacles ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``
        [m] (from coal's AABBs); ``(2, 3)`` of NaN for an empty scene."""
        if not self._obstacles:
            return np.full((2, 3), np.nan)
        lo, hi = self.boxes()
        return np.array([lo.min(axis=0), hi.max(axis=0)])


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
    return shape.geometry.clone()  # (the content read when the mesh was made)


def _read_mesh(path: Path, scale: tuple[float, float, float]) -> tuple[Any, str]:
    """coal's model of the mesh file at ``path``, scaled, and the SHA-256 of the bytes it was
    read from (the file hashed before and after coal reads it: a file rewritten meanwhile is
    refused, not half-read)."""
    import coal

    before = hashlib.sha256(path.read_bytes()).hexdigest()
    try:
        mesh = coal.MeshLoader().load(str(path), np.array(scale))
    except (ValueError, RuntimeError) as exc:  # coal's loader: a corrupt or unknown file
        said = re.search(r"message:\s*(.*?)(?:\s*Hint:|$)", str(exc), re.S)
        reason = " ".join((said.group(1) if said else str(exc)).split())[:200]
        raise InvalidArgumentError(f"mesh {str(path)!r}: coal cannot read it ({reason})") from None
    if hashlib.sha256(path.read_bytes()).hexdigest() != before:
        raise InvalidArgumentError(
            f"mesh {str(path)!r}: the file changed while it was read; load it again"
        )
    return mesh, before


def coal_object(shape: Shape) -> Any:
    """A ``coal.CollisionObject`` of one shape at its world pose."""
    import coal

    pose = shape_pose(shape)
    tf = coal.Transform3s(pose[:3, :3].copy(), pose[:3, 3].copy())
    return coal.CollisionObject(coal_geometry(shape), tf)


def as_scene(scene: Scene | Sequence[Shape] | str | os.PathLike[str] | None) -> Scene:
    """A :class:`Scene` from a scene, a list of shapes, a scene file (any format of
    :meth:`Scene.load`), or ``None`` (empty)."""
    if scene is None:
        return Scene()
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, (str, os.PathLike)):
        return Scene.load(scene)
    if not isinstance(scene, Iterable):
        raise InvalidArgumentError(
            f"scene must be a Scene, a list of shapes, a scene file's path or None, got "
            f"{type(scene).__name__} ({reprlib.repr(scene)})"
        )
    return Scene(scene)


# ------------------------------------------------------------------------- reading files
_SUFFIXES = {
    ".json": "json",
    ".yml": "curobo",
    ".yaml": "curobo",
    ".scene": "moveit",
    ".urdf": "urdf",
    ".xml": "urdf",
}


def _read_text(p: Path, decode: bool = True) -> str:
    """The text of a scene file: refused when missing, over :data:`MAX_FILE_BYTES` or not
    UTF-8 (a byte-order mark is dropped); ``""`` without ``decode`` (the checks only)."""
    if not p.exists():
        raise SceneFileNotFoundError(f"scene file not found: {str(p)!r}")
    if not p.is_file():
        raise SceneFileNotFoundError(f"scene file {str(p)!r} is not a file")
    size = p.stat().st_size
    if size > MAX_FILE_BYTES:
        raise InvalidArgumentError(
            f"{p}: {size} bytes, over the {MAX_FILE_BYTES // 2**20} MiB limit of scene files"
        )
    if not decode:
        return ""
    try:
        return _read_bytes(p).decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InvalidArgumentError(f"{p}: not a UTF-8 text file ({exc.reason} at byte "
                                   f"{exc.start})") from None  # fmt: skip


def _read_bytes(p: Path) -> bytes:
    """The bytes of a scene file, an unreadable one refused in one line."""
    try:
        return p.read_bytes()
    except OSError as exc:
        raise InvalidArgumentError(f"{p}: cannot be read ({exc.strerror})") from None


def _sniff(text: str) -> str | None:
    """The format of a scene file by its content: JSON, URDF, MoveIt (ends with a line
    ``.``) or cuRobo YAML (a mapping with cuRobo's sections); ``None`` when unsure."""
    head = text.lstrip()
    if head[:1] in ("{", "["):
        return "json"
    if head.startswith("<"):
        return "urdf" if re.search(r"<robot[\s>]", text) else None
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    if lines and lines[-1] == ".":
        return "moveit"
    if re.search(rf"^\s*({'|'.join(_CUROBO)})\s*:", text, flags=re.MULTILINE):
        return "curobo"
    return None


def _parse_json(text: str, p: Path) -> Any:
    def no_constants(name: str) -> Any:
        raise InvalidArgumentError(
            f"{p}: non-finite number {name} (every number in a scene must be finite)"
        )

    def no_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for k, v in pairs:
            if k in out:
                raise InvalidArgumentError(f"{p}: key {k!r} given twice in one object")
            out[k] = v
        return out

    return _parsed_tree(
        p,
        "JSON",
        5,
        (ValueError,),  # JSONDecodeError among them
        lambda: json.loads(
            text, parse_constant=no_constants, object_pairs_hook=no_duplicates, parse_int=json_int
        ),
    )


def _parsed_tree(
    p: Path,
    kind: str,
    levels: int,
    errors: tuple[type[Exception], ...],
    parse: Callable[[], Any],
) -> Any:
    """What ``parse()`` reads from scene file ``p``, checked by :func:`_check_tree`: the
    parser's own ``errors`` become one line "not a {kind} file", a nesting too deep for
    Python's recursion one line naming :data:`MAX_DEPTH` (a scene of this kind needs about
    ``levels``); an :class:`InvalidArgumentError` raised while parsing passes unchanged.
    """
    try:
        data = parse()
    except InvalidArgumentError:
        raise
    except errors as exc:
        raise InvalidArgumentError(f"{p}: not a {kind} file ({one_line(exc)})") from None
    except RecursionError:
        raise InvalidArgumentError(
            f"{p}: nested more than {MAX_DEPTH} levels deep (a scene needs about {levels})"
        ) from None
    _check_tree(data, str(p))
    return data


# ----------------------------------------------------------------------------- cuRobo
_CUROBO_VISUAL = ("color", "texture", "texture_id", "material")
"""cuRobo obstacle fields for rendering only: accepted and ignored."""
_CUROBO: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "cuboid": (("dims", "pose"), ()),
    "sphere": (("radius",), ("pose", "position")),
    "capsule": (("radius", "base", "tip", "pose"), ()),
    "cylinder": (("radius", "height", "pose"), ()),
    "mesh": (("file_path", "pose"), ("scale", "urdf_path")),
}
"""cuRobo world sections: required and optional fields of their obstacles (a mesh's
``urdf_path``, which cuRobo hands to its simulator, is accepted and ignored)."""


def _yaml(where: str | None = None) -> Any:
    """PyYAML, or a one-line refusal naming ``where`` (the file) when it is not installed."""
    try:
        import yaml
    except ImportError:
        head = f"{where}: " if where else ""
        raise SceneDependencyError(
            f"{head}cuRobo YAML scenes need PyYAML: pip install pyyaml (import name 'yaml')"
        ) from None
    return yaml


def _path_arg(path: Any, what: str) -> Path:
    """``path`` as a :class:`~pathlib.Path` (``~`` expanded), refused unless it is a string or
    a path."""
    if not isinstance(path, (str, os.PathLike)) or str(path) == "":
        raise InvalidArgumentError(
            f"the {what} must be a path (a string or a pathlib.Path), got {reprlib.repr(path)}"
        )
    return _expanded(path, what)


def _expanded(path: str | os.PathLike[str], what: str) -> Path:
    """``Path(path)`` with a leading ``~`` or ``~user`` expanded; one that names no home
    folder is refused in one line."""
    try:
        return Path(path).expanduser()
    except RuntimeError:  # (pathlib: "Could not determine home directory")
        raise InvalidArgumentError(
            f"the {what} {os.fsdecode(path)!r} starts with '~' but names no home folder"
        ) from None


def _write_text(p: Path, text: str) -> None:
    """Write ``text`` to ``p``, an unwritable place refused in one line."""
    try:
        with written_in_place_of(p) as part:  # (never a partial file)
            part.write_text(text)
    except OSError as exc:
        raise InvalidArgumentError(
            f"cannot write the scene to {str(p)!r}: {exc.strerror or exc}"
        ) from None


@functools.cache
def _yaml_loader() -> Any:
    """PyYAML's safe loader, refusing duplicate keys and reading ``1e-3`` as a number (YAML
    1.1 wants a dot in a float; PyYAML would give the string)."""
    yaml = _yaml()

    class Loader(yaml.SafeLoader):  # type: ignore[name-defined,misc]
        def construct_mapping(self, node: Any, deep: bool = False) -> Any:
            seen: set[str] = set()
            for key_node, _ in node.value:
                if isinstance(key_node, yaml.ScalarNode):
                    if key_node.value in seen:
                        raise yaml.constructor.ConstructorError(
                            None, None, f"key {key_node.value!r} given twice", key_node.start_mark
                        )
                    seen.add(key_node.value)
            return super().construct_mapping(node, deep)

    Loader.add_implicit_resolver(
        "tag:yaml.org,2002:float",
        re.compile(
            r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
            |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
            |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
            |[-+]?\.(?:inf|Inf|INF)
            |\.(?:nan|NaN|NAN))$""",
            re.X,
        ),
        list("-+0123456789."),
    )
    return Loader


def _parse_yaml(text: str, p: Path) -> Any:
    yaml = _yaml(str(p))
    return _parsed_tree(
        p,
        "YAML",
        4,
        # ValueError: a too-long integer, a date such as 2001-13-45 (the constructors raise it)
        (yaml.YAMLError, ValueError, TypeError, OverflowError),
        lambda: yaml.load(text, Loader=_yaml_loader()),  # a SafeLoader subclass
    )


def _curobo_pose(value: Any) -> FloatArray:
    """A cuRobo pose ``[x, y, z, qw, qx, qy, qz]`` as a 4x4 transform."""
    arr = _float_array(value, (7,))
    if arr is None or not np.all(np.isfinite(arr)):
        raise InvalidArgumentError(
            f"pose must be 7 finite numbers [x, y, z, qw, qx, qy, qz], got {reprlib.repr(value)}"
        )
    return _transform(_quat_matrix(arr[3:], "wxyz"), arr[:3])


def _curobo_point(what: str, value: Any) -> FloatArray:
    arr = _float_array(value, (3,))
    if arr is None or not np.all(np.isfinite(arr)):
        raise InvalidArgumentError(f"{what} must be 3 finite numbers, got {reprlib.repr(value)}")
    return arr


def _curobo_shape(section: str, name: str, d: Mapping[str, Any], base_dir: Path) -> Shape:
    """One obstacle of a cuRobo world section."""
    if section == "cuboid":
        return Box(d["dims"], _m4(_curobo_pose(d["pose"])), name=name)
    if section == "sphere":
        if "pose" not in d and "position" not in d:
            raise InvalidArgumentError("a sphere needs a pose or a position")
        center = None
        if "pose" in d:
            center = _curobo_pose(d["pose"])[:3, 3]
        if "position" in d:
            pos = _curobo_point("position", d["position"])
            if center is not None and not np.array_equal(pos, center):
                raise InvalidArgumentError(
                    f"position {pos.tolist()} and the pose's position {center.tolist()} differ"
                )
            center = pos
        return Sphere(d["radius"], _v3(center), name=name)
    if section == "capsule":
        base = _curobo_point("base", d["base"])
        tip = _curobo_point("tip", d["tip"])
        axis = tip - base
        length = float(np.linalg.norm(axis))
        if not length > 0.0:
            raise InvalidArgumentError(
                f"base and tip are the same point {base.tolist()} (length 0: write a sphere)"
            )
        local = _transform(_z_to(axis / length), 0.5 * (base + tip))
        return Capsule(d["radius"], length, _m4(_curobo_pose(d["pose"]) @ local), name=name)
    if section == "cylinder":
        return Cylinder(d["radius"], d["height"], _m4(_curobo_pose(d["pose"])), name=name)
    raw = d["file_path"]
    if not isinstance(raw, str) or not raw:
        raise InvalidArgumentError(f"file_path must be a file path, got {reprlib.repr(raw)}")
    path = _expanded(raw, "mesh file_path")
    if not path.is_absolute():
        path = base_dir / path
        if not path.is_file() and not path.is_dir():
            raise SceneFileNotFoundError(
                f"mesh file not found: {str(path)!r} (a relative file_path is read from the "
                "YAML's folder, not from cuRobo's assets folder: give an absolute path)"
            )
    scale = d.get("scale")
    pose = _curobo_pose(d["pose"])
    return Mesh(str(path), _m4(pose), scale=(1.0, 1.0, 1.0) if scale is None else scale, name=name)


def _from_curobo(data: Any, base_dir: Path, where: str) -> Scene:
    """A scene from a parsed cuRobo world (``WorldConfig.from_dict``'s layout)."""
    if data is None:  # (an empty world would turn collision avoidance off unnoticed)
        raise InvalidArgumentError(
            f"{where}: the file holds no cuRobo world (empty, or comments only); sections: "
            f"{', '.join(_CUROBO)}"
        )
    if not isinstance(data, dict):
        raise InvalidArgumentError(
            f"{where}: a cuRobo world is a mapping of sections ({', '.join(_CUROBO)}), "
            f"got {reprlib.repr(data)}"
        )
    shapes: list[Shape] = []
    for section, entries in data.items():
        if section in ("blox", "voxel"):
            raise InvalidArgumentError(
                f"{where}: cuRobo {section!r} worlds (nvblox maps, voxel grids) are not "
                f"supported; valid sections: {', '.join(_CUROBO)}"
            )
        if not isinstance(section, str) or section not in _CUROBO:
            raise UnknownNameError(
                f"{where}: unknown section {reprlib.repr(section)}; valid sections: "
                f"{', '.join(_CUROBO)}"
            )
        if entries is None:
            continue
        if not isinstance(entries, dict):
            raise InvalidArgumentError(
                f"{where}: {section} must map obstacle names to their fields, "
                f"got {reprlib.repr(entries)}"
            )
        required, optional = _CUROBO[section]
        for name, fields in entries.items():
            if not isinstance(name, str) or not name:
                raise InvalidArgumentError(
                    f"{where}: {section}: an obstacle name must be a non-empty string, "
                    f"got {reprlib.repr(name)}"
                )
            with _context(f"{where}: {section} {name!r}"):
                if not isinstance(fields, dict):
                    raise InvalidArgumentError(
                        f"expected a mapping of fields, got {reprlib.repr(fields)}"
                    )
                if section == "mesh" and ("vertices" in fields or "faces" in fields):
                    raise InvalidArgumentError(
                        "inline vertices/faces are not supported: give the mesh as file_path"
                    )
                _check_fields("", fields, required, optional + _CUROBO_VISUAL)
                shapes.append(_curobo_shape(section, name, fields, base_dir))
    with _context(where):
        return Scene(shapes)


# ----------------------------------------------------------------------------- MoveIt
_MOVEIT_SHAPES = ("box", "cylinder", "mesh", "sphere")
_MOVEIT_TYPES = (*_MOVEIT_SHAPES, "cone", "plane")
"""Every shape type line of MoveIt's format (cones and planes refused by name)."""
_MoveitObject = tuple[str, list[tuple[Callable[[FloatArray, str], Shape], FloatArray, int]]]
"""An object of a MoveIt scene as :func:`_from_moveit` reads it: its id and, per shape, the
shape's maker, world pose and line."""
_NUMBER = re.compile(r"[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?")
_TOKEN = re.compile(r"\s*(\S+)")


class _Stream:
    """Whitespace-separated tokens of a MoveIt ``.scene`` file, read as MoveIt's
    ``std::istream >>`` does, with the line of each for the messages."""

    def __init__(self, text: str, pos: int, where: str) -> None:
        self.text, self.pos, self.where = text, pos, where
        self.context = ""  # the object being read, for the messages

    def line(self) -> int:
        return self.text.count("\n", 0, self.pos) + 1

    def next_line(self) -> int:
        """The line of the next token."""
        m = _TOKEN.match(self.text, self.pos)
        return self.text.count("\n", 0, m.start(1) if m else self.pos) + 1

    def at(self, line: int | None = None) -> str:
        """``file: line N: object 'x': `` for a message."""
        return f"{self.where}: line {self.line() if line is None else line}: {self.context}"

    def fail(self, message: str, line: int | None = None) -> InvalidArgumentError:
        return InvalidArgumentError(one_line(f"{self.at(line)}{message}"))

    def token(self, what: str) -> str:
        m = _TOKEN.match(self.text, self.pos)
        if m is None:
            raise InvalidArgumentError(
                f"{self.where}: {self.context}the file ends where {what} was expected "
                "(truncated? a scene ends with a line '.')"
            )
        self.pos = m.end()
        return m.group(1)

    def peek(self) -> str | None:
        """The next token, not consumed (None at the end of the file)."""
        m = _TOKEN.match(self.text, self.pos)
        return None if m is None else m.group(1)

    def rest_of_line(self) -> str:
        end = self.text.find("\n", self.pos)
        end = len(self.text) if end < 0 else end
        out, self.pos = self.text[self.pos : end], min(end + 1, len(self.text))
        return out.strip()

    def number(self, what: str) -> float:
        tok = self.token(what)
        if not _NUMBER.fullmatch(tok):
            raise self.fail(f"{what} must be a number, got {tok!r}")
        v = float(tok)
        if not math.isfinite(v):
            raise self.fail(f"{what} must be a finite number, got {tok!r}")
        return v

    def count(self, what: str) -> int:
        tok = self.token(what)
        if not re.fullmatch(r"[0-9]{1,18}", tok):
            raise self.fail(f"{what} must be a whole number >= 0, got {reprlib.repr(tok)}")
        return int(tok)

    def row(self, what: str, labels: Sequence[str]) -> list[float]:
        """The numbers of one line, one per label (MoveIt writes a position, a quaternion and
        a colour each on a line of its own): a line with more or fewer is refused, where
        reading token by token would take the next line's numbers as these."""
        line = self.next_line()
        form = f"{what} must be {len(labels)} numbers on one line ({' '.join(labels)})"
        values: list[float] = []
        for c in labels:
            if self.next_line() != line:
                raise self.fail(f"{form}; it has {len(values)}", line)
            values.append(self.number(f"{what} {c}"))
        extra = self.rest_of_line()
        if extra:
            raise self.fail(f"{form}; more follow: {reprlib.repr(extra)}", line)
        return values

    def pose(self, what: str) -> FloatArray:
        """``x y z`` then ``qx qy qz qw`` (MoveIt's ``readPoseFromText``), normalised."""
        pos = self.row(f"{what} position", "xyz")
        quat = self.row(f"{what} quaternion", ("qx", "qy", "qz", "qw"))
        try:
            rot = _quat_matrix(quat, "xyzw")
        except InvalidArgumentError as exc:
            raise self.fail(f"{what}: {exc}") from None
        return _transform(rot, pos)


def _write_obj(vertices: FloatArray, triangles: Any, mesh_dir: Path | None) -> Path:
    """An OBJ file of a MoveIt inline mesh, named by its content's hash (written once)."""
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in vertices.tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in triangles]
    text = "\n".join(lines) + "\n"
    if mesh_dir is None:
        from swarm_ik.paths import cache_dir

        mesh_dir = cache_dir() / "scene_meshes"
    path = mesh_dir / f"moveit-{hashlib.sha256(text.encode()).hexdigest()[:24]}.obj"
    try:
        mesh_dir.mkdir(parents=True, exist_ok=True)
        if not path.is_file():
            tmp = path.with_suffix(f".{os.getpid()}.tmp")
            tmp.write_text(text)
            os.replace(tmp, path)
    except OSError as exc:
        raise InvalidArgumentError(
            f"cannot write the scene's inline mesh into {str(mesh_dir)!r} "
            f"({exc.strerror or type(exc).__name__}); give mesh_dir a writable folder"
        ) from None
    return path


def _moveit_shape(s: _Stream, mesh_dir: Path | None) -> Callable[[FloatArray, str], Shape]:
    """Read one shape's type line and dimensions; returns its builder from (pose, name)."""
    kind = s.token("a shape type")
    if kind == "box":
        size = s.row("box size", "xyz")  # (one line, as MoveIt writes it)
        return lambda pose, name: Box(_v3(size), _m4(pose), name=name)
    if kind == "sphere":
        (r,) = s.row("sphere", ("radius",))
        return lambda pose, name: Sphere(r, _v3(pose[:3, 3]), name=name)
    if kind == "cylinder":
        r, length = s.row("cylinder", ("radius", "length"))
        return lambda pose, name: Cylinder(r, length, _m4(pose), name=name)
    if kind == "mesh":
        line = s.line()
        nv, nt = s.count("mesh vertex count"), s.count("mesh triangle count")
        if nt == 0:
            raise s.fail("mesh with no triangles")
        verts = np.array([[s.number(f"mesh vertex {i} {c}") for c in "xyz"] for i in range(nv)])
        tris = []
        for i in range(nt):
            tri = [s.count(f"mesh triangle {i} index") for _ in range(3)]
            if max(tri) >= nv:
                raise s.fail(f"mesh triangle {i} {tri} names a vertex beyond the {nv} given")
            tris.append(tri)
        v = verts.reshape(nv, 3)
        t = np.array(tris, dtype=np.int64)
        area2 = np.linalg.norm(np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]), axis=1)
        if not np.any(area2 > 0.0):
            raise s.fail("mesh: its triangles all have zero area (no surface to collide with)",
                         line)  # fmt: skip
        path = _write_obj(v, tris, mesh_dir)
        return lambda pose, name: Mesh(str(path), _m4(pose), name=name)
    if kind == "cone":
        raise s.fail(
            f"cone: swarm_ik has no cone primitive (shapes: {', '.join(_MOVEIT_SHAPES)}); "
            "replace the cone by a mesh or a cylinder"
        )
    if kind == "plane":
        raise s.fail("plane: an infinite plane is not an obstacle swarm_ik checks; use a thin box")
    raise UnknownNameError(
        f"{s.at()}unknown shape type {kind!r}; valid shape types: {', '.join(_MOVEIT_SHAPES)}"
    )


def _from_moveit(text: str, where: str, mesh_dir: Path | None) -> list[Shape]:
    """The obstacles of a MoveIt ``.scene`` file (``PlanningScene::loadGeometryFromStream``:
    a name line; per object ``* id``, [its pose: ``x y z`` / ``qx qy qz qw``], the number of
    shapes and per shape its type and dimensions, pose and colour ``r g b a``, [the number of
    subframes and per subframe a name and pose]; a line ``.`` at the end).  The bracketed
    parts are the newer layout, told as MoveIt does by the line after the first ``*``: three
    numbers (a position) rather than one (a shape count)."""
    first = text.find("\n")
    if not text.strip():
        raise InvalidArgumentError(f"{where}: the file is empty (a MoveIt scene file was expected)")
    if first < 0:
        raise InvalidArgumentError(f"{where}: the file ends after its name line (truncated?)")
    lines = text[first + 1 :].split("\n")
    new_format = False
    for i, ln in enumerate(lines):
        if ln.startswith("*"):
            nxt = lines[i + 1].strip() if i + 1 < len(lines) else ""
            new_format = len(nxt.split()) > 1
            break
    s = _Stream(text, first + 1, where)
    # each object's shapes, built once every object id is known (an object of several shapes
    # names them <id>#k; one such name taken by another object's id gets a further suffix)
    pending: list[_MoveitObject] = []
    n_objects = 0
    while True:
        marker = s.token("an object ('* name') or the end line '.'")
        if marker == "." and not any(made for _, made in pending):  # (an empty scene would
            # turn collision avoidance off unnoticed: MoveIt writes one for an empty scene)
            held = (
                f"its {n_objects} object{'s have' if n_objects > 1 else ' has'} no shapes"
                if n_objects
                else "no object"
            )
            raise InvalidArgumentError(
                f"{where}: the scene holds no obstacles ({held} before the end line '.')"
            )
        if marker == ".":
            return _moveit_shapes(pending, s)
        if marker != "*":
            raise s.fail(f"unknown marker {marker!r}; expected '*' (an object) or '.' (the end)")
        s.context = ""
        object_id = s.rest_of_line()
        if not object_id:
            raise s.fail("an object ('*') without a name")
        s.context = f"object {object_id!r}: "
        n_objects += 1
        obj_pose = s.pose("object pose") if new_format else np.eye(4)
        count_line = s.next_line()
        n = s.count("number of shapes")
        declared = f"{n} shape{'s' * (n != 1)} declared (line {count_line})"
        made: list[tuple[Callable[[FloatArray, str], Shape], FloatArray, int]] = []
        for k in range(n):
            line = s.next_line()
            tok = s.peek()
            if (
                tok is None
                or (k and tok not in _MOVEIT_TYPES)
                or tok in ("*", ".")
                or _NUMBER.fullmatch(tok)
            ):  # (a shape count larger than the shapes given)
                follows = (
                    "the file ends (truncated?)" if tok is None else f"line {line} holds {tok!r}"
                )
                raise s.fail(
                    f"{declared} but {k} given: {follows} where shape {k}'s type "
                    f"({', '.join(_MOVEIT_SHAPES)}) was expected",
                    line,
                )
            build = _moveit_shape(s, mesh_dir)
            pose = obj_pose @ s.pose(f"shape {k} pose")
            s.row(f"shape {k} colour", "rgba")
            made.append((build, pose, line))
        after = s.peek()
        if after in _MOVEIT_TYPES:  # (where a subframe count or the next object was due)
            raise s.fail(f"{declared}, but another shape follows: {after!r}", s.next_line())
        if new_format:
            for k in range(s.count("number of subframes")):
                s.token(f"subframe {k} name")
                s.pose(f"subframe {k} pose")
        pending.append((object_id, made))


def _moveit_shapes(pending: list[_MoveitObject], s: _Stream) -> list[Shape]:
    """The shapes of :func:`_from_moveit`'s objects, named: an object of one shape by its id,
    of several ``<id>#k`` (``<id>#k.m`` where another object's id is ``<id>#k``)."""
    ids = {object_id for object_id, _ in pending}
    shapes: list[Shape] = []
    for object_id, made in pending:
        for k, (build, pose, line) in enumerate(made):
            name = object_id
            if len(made) != 1:
                name = f"{object_id}#{k}"
                m = 0
                while name in ids:
                    m += 1
                    name = f"{object_id}#{k}.{m}"
            with _context(s.at(line).rstrip(": ")):
                shapes.append(build(pose, name))
    return shapes


# ------------------------------------------------------------------------------- URDF
_URDF_GEOMETRY = ("box", "cylinder", "mesh", "sphere")


_URDF_ATTRS = {"box": (("size", 3),), "cylinder": (("radius", 1), ("length", 1)),
               "sphere": (("radius", 1),), "mesh": (("scale", 3),)}  # fmt: skip
"""Numeric attributes of the URDF geometries and their counts (checked before urdfdom, which
drops a whole link's collisions on a bad one)."""


def _urdf_numbers(where: str, el: Any, attr: str, n: int, required: bool) -> None:
    raw = el.get(attr)
    if raw is None:
        if required:
            raise InvalidArgumentError(f"{where}: <{el.tag}> needs the attribute {attr!r}")
        return
    vals = [v for v in raw.split() if _NUMBER.fullmatch(v)]
    if (
        len(vals) != len(raw.split())
        or len(vals) != n
        or not all(math.isfinite(float(v)) for v in vals)
    ):
        raise InvalidArgumentError(
            f"{where}: <{el.tag} {attr}={raw!r}> must be {n} finite number{'s' * (n > 1)}"
        )


def _check_urdf_collisions(root: Any, where: str) -> int:
    """Refuse collision elements urdfdom would drop (with their whole link) or Pinocchio
    would misread; returns their number."""
    count = 0
    for link in root.findall("link"):
        for col in link.findall("collision"):
            at = f"{where}: link {link.get('name')!r}"
            origin = col.find("origin")
            if origin is not None:
                for attr in ("xyz", "rpy"):
                    _urdf_numbers(at, origin, attr, 3, required=False)
            geo = col.find("geometry")
            kinds = [g.tag for g in geo] if geo is not None else []
            if len(kinds) != 1 or kinds[0] not in _URDF_GEOMETRY:
                unknown_shape = len(kinds) == 1  # (one geometry of a type URDF does not have)
                raise (UnknownNameError if unknown_shape else InvalidArgumentError)(
                    f"{at}: a collision geometry must be one of {', '.join(_URDF_GEOMETRY)} "
                    f"(URDF has no other), got {kinds}"
                )
            assert geo is not None
            shape = geo[0]
            for attr, n in _URDF_ATTRS[shape.tag]:
                _urdf_numbers(at, shape, attr, n, required=shape.tag != "mesh")
            if shape.tag == "mesh" and not shape.get("filename"):
                raise InvalidArgumentError(f"{at}: <mesh> needs a filename")
            count += 1
    return count


def _check_zero_within_limits(model: Any, p: Path) -> None:
    """A scene URDF's moving joints stand at 0 (:func:`_from_urdf`): one whose limits leave
    out 0 is refused, naming it (its obstacles were placed where the joint never is).

    Raises:
        InvalidArgumentError: such a joint.
    """
    import pinocchio as pin

    zero = pin.neutral(model)
    lo, hi = np.asarray(model.lowerPositionLimit), np.asarray(model.upperPositionLimit)
    for j in range(1, model.njoints):
        a, n = model.idx_qs[j], model.nqs[j]
        part_lo, part_hi, part = lo[a : a + n], hi[a : a + n], zero[a : a + n]
        limited = np.isfinite(part_lo) & np.isfinite(part_hi) & (part_lo <= part_hi)
        if np.any(limited & ((part < part_lo - 1e-12) | (part > part_hi + 1e-12))):
            raise InvalidArgumentError(
                f"{p}: joint {model.names[j]!r} has limits [{part_lo[0]:g}, {part_hi[0]:g}] "
                "that leave out 0, where a scene URDF places its moving joints (every joint "
                "at 0): make it a fixed joint with the origin where its obstacles stand"
            )


def _from_urdf(p: Path) -> list[Shape]:
    """Every link's collision geometry of a URDF at its placement for the zero configuration
    (Pinocchio's ``buildGeomFromUrdf`` + ``updateGeometryPlacements``), named as Pinocchio
    names it (``<link>_<k>``).  The file is checked as robots are
    (:func:`swarm_ik.urdf.load_urdf`: one root, no loops, well-formed joints)."""
    import xml.etree.ElementTree as ET

    import coal
    import pinocchio as pin

    from swarm_ik.errors import RobotModelError
    from swarm_ik.paths import package_dirs
    from swarm_ik.urdf import captured_stderr, load_urdf

    try:
        model, info = load_urdf(p)
    except RobotModelError as exc:
        raise InvalidArgumentError(one_line(exc)) from None
    _check_zero_within_limits(model, p)
    root = ET.fromstring(info.xml)
    n_collision = _check_urdf_collisions(root, str(p))
    if n_collision == 0:  # (an empty scene would turn collision avoidance off unnoticed)
        n_visual = sum(len(link.findall("visual")) for link in root.findall("link"))
        visuals = (
            f"; <visual> elements ({n_visual} here) are drawn, never collided with"
            if n_visual
            else ""
        )
        raise InvalidArgumentError(
            f"{p}: no link has a <collision> element, so the file holds no obstacles{visuals} "
            "(give each obstacle a <collision> geometry)"
        )
    error = None
    with captured_stderr() as said:
        try:
            geom = pin.buildGeomFromUrdfString(
                model, info.xml, pin.GeometryType.COLLISION, package_dirs=package_dirs(p)
            )
        except (ValueError, RuntimeError) as exc:
            error = one_line(exc)
    if error is not None:
        if "could not be found" in error:
            raise SceneFileNotFoundError(f"{p}: {error}")
        raise InvalidArgumentError(f"{p}: Pinocchio cannot read its collision geometry ({error})")
    if len(geom.geometryObjects) != n_collision:
        detail = "; ".join(ln for ln in said if not ln.startswith("at line"))[:300]
        raise InvalidArgumentError(
            f"{p}: Pinocchio read {len(geom.geometryObjects)} of its {n_collision} collision "
            f"geometries ({one_line(detail) or 'no message'})"
        )
    data, gdata = model.createData(), pin.GeometryData(geom)
    pin.forwardKinematics(model, data, pin.neutral(model))
    pin.updateGeometryPlacements(model, data, geom, gdata)
    shapes: list[Shape] = []
    for obj, placement in zip(geom.geometryObjects, gdata.oMg, strict=True):
        g, pose, name = obj.geometry, np.array(placement.homogeneous), str(obj.name)
        with _context(f"{p}: {name}"):
            if isinstance(g, coal.Box):
                shapes.append(Box(_v3(2.0 * np.array(g.halfSide)), _m4(pose), name=name))
            elif isinstance(g, coal.Sphere):
                shapes.append(Sphere(g.radius, _v3(pose[:3, 3]), name=name))
            elif isinstance(g, coal.Cylinder):
                shapes.append(Cylinder(g.radius, 2.0 * g.halfLength, _m4(pose), name=name))
            elif isinstance(g, coal.Capsule):
                shapes.append(Capsule(g.radius, 2.0 * g.halfLength, _m4(pose), name=name))
            elif isinstance(g, coal.BVHModelBase):
                scale = np.array(obj.meshScale, dtype=float)
                shapes.append(Mesh(str(obj.meshPath), _m4(pose), scale=_v3(scale), name=name))
            else:
                raise InvalidArgumentError(f"unsupported geometry {type(g).__name__}")
    return shapes
