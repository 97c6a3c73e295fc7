"""Robot collision geometry, self-collision pairs and the exact collision check (coal).

The geometry is the URDF's ``<collision>`` elements, loaded by Pinocchio's
``buildGeomFromUrdf`` (meshes and primitives become coal objects) on the full model and
reduced with ``buildReducedModel`` to the solved chain, so every body follows the joint it
is attached to after the off-chain joints are locked at ``robot.q_locked``.  A mimic joint
driven by a solved joint stays in that model wherever it is (``robot.model``, off the chain
too), so the bodies it carries (a counterweight) move with their driver in the exact check
and in the sphere model alike.

Self-collision pairs are the pairs of links with collision geometry, minus

* **adjacent** links: a link and its nearest ancestor link that has collision geometry
  (links joined by a joint, skipping links without geometry, as MoveIt does);
* **rigid** pairs: links attached to the same joint of the reduced model (or both to the
  world); their relative pose never changes, so a contact there would be a property of the
  model, not of ``q``;
* the pairs an SRDF disables (``<disable_collisions link1=… link2=…/>``).  The SRDF is given
  or found next to the URDF (``<pkg>/srdf/<name>.srdf``; see :func:`find_srdf`), which covers
  every arm of ``example-robot-data``;
* without an SRDF, the pairs that collide in no sample or in at least 95 % of ``N = 2000``
  configurations drawn uniformly within the limits (the rule of MoveIt's setup assistant,
  "never in collision" / "always in collision"); the result is cached per URDF content in
  :func:`cache_dir`.

The exact check (:meth:`RobotCollision.check`) runs coal's ``collide`` (with the margin as
security margin) and ``distance`` on every enabled pair: self pairs and every robot body that
a joint moves against every obstacle of a :class:`~swarm_ik.scene.Scene` (the obstacles in
coal's dynamic AABB tree, its broad phase, so thousands of obstacles cost little).  A body
fixed to the world (a base link) is paired with no obstacle: its contacts do not depend on
``q`` (the rigid pairs' reason), and a base standing on the table of its scene (cuRobo's
``collision_table.yml`` under a Panda, whose base mesh dips 3e-5 m below its origin) made
every solve fail; one warning per scene names such a body in contact.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import threading
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from itertools import combinations
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from swarm_ik._types import FloatArray
from swarm_ik._validate import user_stacklevel
from swarm_ik.errors import (
    InvalidArgumentError,
    RobotFileNotFoundError,
    RobotModelError,
    RobotModelWarning,
)
from swarm_ik.kernels.mesh import enclosed_points
from swarm_ik.paths import cache_dir, package_dirs
from swarm_ik.pose import is_finite_nonneg
from swarm_ik.scene import Scene, as_scene

SAMPLES = 2000
"""Random configurations of the no-SRDF rule (MoveIt's setup assistant uses 10,000 by
default; 2000 already separates 'never' and 'always' pairs on the arms tested)."""

ALWAYS_FRACTION = 0.95
"""A pair colliding in at least this fraction of the samples is disabled ('always')."""

_RULE_VERSION = 1

SMALL_SCENE = 128
"""Scenes of at most this many obstacles join the robot's bodies in one Pinocchio geometry
model for a verdict without margin: one C++ call then places the bodies and runs the broad
and narrow phases (Panda: 23 µs among 10 boxes, 33 µs among 40, against 70–80 µs placing
coal's objects from Python); a larger scene keeps coal's tree of obstacles (a Pinocchio
model's pairs grow with bodies × obstacles: at 600 obstacles the one call took 177 µs)."""


# ------------------------------------------------------------------------------ SRDF
def _robot_name(path: Path) -> str | None:
    try:
        return ET.parse(path).getroot().get("name")
    except (ET.ParseError, OSError):
        return None


def find_srdf(urdf_path: str | os.PathLike[str]) -> Path | None:
    """The SRDF shipped next to a URDF, or ``None``.

    Looks in ``<urdf folder>/../srdf`` and the URDF's own folder for, in order:
    ``<stem>.srdf``; ``<stem without "_robot">.srdf``; ``<robot name>.srdf``; the only
    ``.srdf`` there whose ``<robot name>`` equals the URDF's.  (``ur5_robot.urdf`` →
    ``ur5.srdf``; ``baxter.urdf`` → ``baxter_manipulation.srdf``.)
    """
    urdf = Path(urdf_path).resolve()
    name = _robot_name(urdf)
    folders = [d for d in (urdf.parent.parent / "srdf", urdf.parent) if d.is_dir()]
    stems = [urdf.stem]
    if urdf.stem.endswith("_robot"):
        stems.append(urdf.stem[: -len("_robot")])
    if name:
        stems.append(name)
    for d in folders:
        for s in stems:
            if (d / f"{s}.srdf").is_file():
                return d / f"{s}.srdf"
    for d in folders:
        same = [p for p in sorted(d.glob("*.srdf")) if name and _robot_name(p) == name]
        if len(same) == 1:
            return same[0]
    return None


def parse_srdf(path: str | os.PathLike[str]) -> list[tuple[str, str, str]]:
    """The ``<disable_collisions>`` entries of an SRDF: ``(link1, link2, reason)``.

    Raises:
        RobotFileNotFoundError: the file does not exist.
        RobotModelError: not XML, or an entry without both links.
    """
    p = Path(path)
    if not p.is_file():
        raise RobotFileNotFoundError(f"SRDF file not found: {str(p)!r}")
    try:
        root = ET.parse(p).getroot()
    except ET.ParseError as exc:
        raise RobotModelError(f"{p}: not a valid XML file ({exc})") from None
    out = []
    for el in root.iter("disable_collisions"):
        a, b = el.get("link1"), el.get("link2")
        if not a or not b:
            raise RobotModelError(
                f"{p}: <disable_collisions> needs link1 and link2, got {el.attrib}"
            )
        out.append((a, b, el.get("reason", "")))
    return out


def _link_parents(urdf_path: Path) -> dict[str, str]:
    """child link -> parent link, from the URDF's joints."""
    root = ET.parse(urdf_path).getroot()
    out = {}
    for j in root.findall("joint"):
        parent, child = j.find("parent"), j.find("child")
        if parent is not None and child is not None:
            out[str(child.get("link"))] = str(parent.get("link"))
    return out


def _key(a: str, b: str) -> tuple[str, str]:
    return (a, b) if a <= b else (b, a)


# ------------------------------------------------------------------------- the report
@dataclass(frozen=True)
class CollisionReport:
    """Outcome of the exact check at one configuration.

    Attributes:
        collision_free: No pair closer than the margin (and none intersecting).
        clearance: Smallest distance over the checked pairs [m]; ``<= 0`` for a contact
            (intersecting meshes report 0, intersecting primitives minus the penetration
            depth); ``inf`` when no pair is checked.
        pairs_in_contact: Pairs ``(body, body)`` closer than the margin, by link name for the
            robot and obstacle name for the scene, sorted.
        closest_pair: The pair realising ``clearance`` (``None`` when no pair is checked).
    """

    collision_free: bool
    clearance: float
    pairs_in_contact: list[tuple[str, str]]
    closest_pair: tuple[str, str] | None = None


class DeferredReport:
    """A :class:`CollisionReport` of a configuration found collision-free, its distances
    computed on first use: the verdict of a solve costs the collision tests alone (about
    0.1 ms among 40 boxes), the clearance (about 0.5–1 ms) only when read.

    Attributes:
        collision_free: True (known from the check that made it).
    """

    collision_free = True

    def __init__(
        self, rc: RobotCollision, q: Any, scene: Scene | None, margin: float, self_col: bool
    ) -> None:
        self._args = (rc, np.array(q, dtype=float), scene, float(margin), bool(self_col))
        self._report: CollisionReport | None = None

    def _full(self) -> CollisionReport:
        if self._report is None:
            rc, q, scene, margin, self_col = self._args
            self._report = rc.check(q, scene, margin, self_col)
        return self._report

    @property
    def clearance(self) -> float:
        """As :attr:`CollisionReport.clearance` [m] (computed on first use)."""
        return self._full().clearance

    @property
    def pairs_in_contact(self) -> list[tuple[str, str]]:
        """As :attr:`CollisionReport.pairs_in_contact` (empty: the configuration is free)."""
        return self._full().pairs_in_contact

    @property
    def closest_pair(self) -> tuple[str, str] | None:
        """As :attr:`CollisionReport.closest_pair` (computed on first use)."""
        return self._full().closest_pair

    def __repr__(self) -> str:
        return repr(self._full())

    def __eq__(self, other: object) -> bool:
        """Equal to a report (deferred or not) of the same numbers (computing them)."""
        if isinstance(other, DeferredReport):
            other = other._full()
        if not isinstance(other, CollisionReport):
            return NotImplemented
        return self._full() == other

    __hash__ = None  # type: ignore[assignment]  # (as CollisionReport's: its list of pairs)


# ---------------------------------------------------------------------------- geometry
@dataclass(eq=False)
class RobotCollision:
    """Collision geometry of a robot's chain model and its enabled self-collision pairs.

    Build it with :meth:`from_robot`.

    Attributes:
        robot: The :class:`~swarm_ik.robot.RobotModel`.
        geom_model: Pinocchio ``GeometryModel`` of the reduced (chain) model; body ``k`` is
            ``geom_model.geometryObjects[k]``.
        body_names: Geometry object names, shape ``(nb,)``.
        body_links: Link of each body, shape ``(nb,)``.
        body_joint: Reduced-model joint each body is attached to (0: the world), ``(nb,)``.
        self_pairs: Enabled self-collision pairs of body indices ``(i, j)``, ``i < j``.
        srdf_path: The SRDF used, or ``None``.
        pair_rule: How the pairs were chosen (``"srdf"`` or ``"sampled"``).
        disabled: Disabled link pairs by reason: ``"adjacent"``, ``"rigid"``, ``"srdf"``,
            ``"never"``, ``"always"``.
        coarse_rule: The sphere models' coarse-pair rule, made once per robot
            (:meth:`swarm_ik.spheres.SphereModel.from_collision`), by fitting tolerance.
    """

    robot: Any
    geom_model: Any
    body_names: tuple[str, ...]
    body_links: tuple[str, ...]
    body_joint: tuple[int, ...]
    self_pairs: list[tuple[int, int]]
    srdf_path: Path | None
    pair_rule: str
    disabled: dict[str, list[tuple[str, str]]]
    coarse_rule: dict[float, Any] = field(default_factory=dict, repr=False)
    _local: threading.local = field(default_factory=threading.local, repr=False)
    _solids: Any = field(default=None, repr=False)

    @classmethod
    def from_robot(
        cls,
        robot: Any,
        srdf: str | os.PathLike[str] | bool | None = None,
        *,
        samples: int = SAMPLES,
        seed: int = 0,
        use_cache: bool = True,
    ) -> RobotCollision:
        """Load the collision geometry of ``robot`` and choose its self-collision pairs.

        Args:
            robot: A :class:`~swarm_ik.robot.RobotModel`.
            srdf: An SRDF path; ``None`` finds one next to the URDF (:func:`find_srdf`);
                ``False`` uses none (the sampling rule decides).
            samples: Random configurations of the no-SRDF rule.
            seed: Seed of those samples (part of the cache key).
            use_cache: Read and write the sampled pairs in :func:`cache_dir`.

        Raises:
            RobotModelError: a mesh cannot be found, or the model has no collision geometry.
            RobotFileNotFoundError: ``srdf`` does not exist.
        """
        urdf = Path(robot.urdf_path)
        dirs = package_dirs(urdf)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                full_geom = pin.buildGeomFromUrdf(
                    robot.full_model, str(urdf), pin.GeometryType.COLLISION, package_dirs=dirs
                )
            except ValueError as exc:
                raise RobotModelError(
                    f"{urdf}: cannot load the collision geometry ({exc}); searched {dirs} (add "
                    "the package folder to ROS_PACKAGE_PATH)"
                ) from None
        if full_geom.ngeoms == 0:
            raise RobotModelError(f"{urdf}: the URDF has no <collision> elements")
        locked = [robot.full_model.getJointId(n) for n in robot.locked_joints]
        if locked:
            model, geom = pin.buildReducedModel(robot.full_model, full_geom, locked, robot.q_locked)
            if list(model.names) != list(robot.model.names):
                raise RobotModelError(f"{urdf}: reduced geometry model does not match the chain")
        else:
            geom = full_geom
        objs = list(geom.geometryObjects)
        names = tuple(g.name for g in objs)
        links = tuple(robot.model.frames[g.parentFrame].name for g in objs)
        joints = tuple(int(g.parentJoint) for g in objs)

        link_joint: dict[str, int] = dict(zip(links, joints, strict=True))
        link_set = sorted(link_joint)
        disabled: dict[str, set[tuple[str, str]]] = {
            k: set() for k in ("adjacent", "rigid", "srdf", "never", "always")
        }
        parents = _link_parents(urdf)
        for link in link_set:
            up = parents.get(link)
            while up is not None and up not in link_joint:
                up = parents.get(up)
            if up is not None:
                disabled["adjacent"].add(_key(link, up))
        for a, b in combinations(link_set, 2):
            if link_joint[a] == link_joint[b] and _key(a, b) not in disabled["adjacent"]:
                disabled["rigid"].add(_key(a, b))
        srdf_path: Path | None
        if srdf is None or srdf is True:
            srdf_path = find_srdf(urdf)
        elif srdf is False:
            srdf_path = None
        else:
            srdf_path = Path(os.fspath(srdf))
        if srdf_path is not None:
            srdf_pairs = parse_srdf(srdf_path)
            for a, b, _ in srdf_pairs:
                if a in link_joint and b in link_joint and a != b:
                    disabled["srdf"].add(_key(a, b))
            known = {f.name for f in robot.full_model.frames}
            unknown = sorted({n for a, b, _ in srdf_pairs for n in (a, b)} - known)
            if unknown:  # (another robot's SRDF: its pairs disable nothing of this one)
                warnings.warn(
                    f"SRDF {str(srdf_path)!r} names {len(unknown)} link(s) that robot "
                    f"{robot.name!r} does not have ({', '.join(unknown[:3])}"
                    f"{', …' if len(unknown) > 3 else ''}): is it another robot's? Its pairs "
                    "with them disable nothing",
                    RobotModelWarning,
                    stacklevel=user_stacklevel(),
                )
        off = set().union(*disabled.values())
        candidates = [p for p in combinations(link_set, 2) if _key(*p) not in off]
        rule = "srdf" if srdf_path is not None else "sampled"
        if srdf_path is None and candidates:
            never, always = _sampled_rule(
                robot, geom, links, candidates, samples, seed, urdf, use_cache
            )
            disabled["never"] = set(never)
            disabled["always"] = set(always)
            off = set().union(*disabled.values())
        pairs = [
            (i, j)
            for i, j in combinations(range(len(objs)), 2)
            if links[i] != links[j] and _key(links[i], links[j]) not in off
        ]
        return cls(
            robot=robot,
            geom_model=geom,
            body_names=names,
            body_links=links,
            body_joint=joints,
            self_pairs=pairs,
            srdf_path=srdf_path,
            pair_rule=rule,
            disabled={k: sorted(v) for k, v in disabled.items()},
        )

    @property
    def nb(self) -> int:
        """Number of collision bodies."""
        return len(self.body_names)

    @property
    def self_link_pairs(self) -> list[tuple[str, str]]:
        """Enabled self-collision pairs by link name, sorted."""
        return sorted({_key(self.body_links[i], self.body_links[j]) for i, j in self.self_pairs})

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        state.pop("_local", None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._local = threading.local()

    # -------------------------------------------------------------------- checking
    def _checker(self, scene: Scene, self_collision: bool) -> _Checker:
        """The pair set of a scene, with per-thread Pinocchio data (built once)."""
        cache = getattr(self._local, "checkers", None)
        if cache is None:
            cache = self._local.checkers = {}
        key = (scene, self_collision)
        hit = cache.get(key)
        if hit is None:
            if len(cache) >= 32:  # many scenes in one thread: keep memory bounded
                cache.clear()
            hit = cache[key] = _Checker(self, scene, self_collision)
        return hit

    def check(
        self,
        q: Any,
        scene: Scene | None = None,
        margin: float = 0.0,
        self_collision: bool = True,
    ) -> CollisionReport:
        """Exact check of configuration ``q`` with coal on the URDF collision geometry.

        Contact is decided by coal's ``collide`` on every pair, with ``margin`` as security
        margin.  The clearance is the exact smallest distance: coal's ``distance`` on the
        pairs in contact, else on the pairs in order of a lower bound (the distance between
        the convex hulls of the meshes, GJK), until the bound exceeds the best distance.

        Args:
            q: Chain joint vector (rad / m), shape ``(nq,)``.
            scene: Obstacles (default: none).
            margin: Bodies closer than this [m] count as in contact (``>= 0``).
            self_collision: Check the enabled self-collision pairs too.

        Returns:
            The :class:`CollisionReport`.

        Raises:
            InvalidArgumentError: a bad ``q`` or ``margin``.
        """
        margin = _margin(margin)
        q = self.robot.check_q(q)
        return self._checker(as_scene(scene), bool(self_collision)).run(
            self.robot.to_pinocchio(q), margin
        )

    def solids(self) -> Solids:
        """The robot's mesh bodies as solids (:class:`Solids`), read once per robot."""
        if self._solids is None:  # (two threads at once would each make the same)
            self._solids = Solids.of(self.geom_model)
        return self._solids  # type: ignore[no-any-return]

    def collides(
        self, q: Any, scene: Scene | None = None, margin: float = 0.0, self_collision: bool = True
    ) -> bool:
        """Fast exact test: whether any pair is closer than ``margin`` [m] at ``q`` (coal's
        ``collide`` only, no distance; same answer as ``not check(...).collision_free``).

        Raises:
            InvalidArgumentError: a bad ``q`` or ``margin``.
        """
        m = _margin(margin)
        q = self.robot.check_q(q)
        ck = self._checker(as_scene(scene), bool(self_collision))
        return ck.collide(self.robot.to_pinocchio(q), m)

    def pairs_always_in_contact(
        self, scene: Scene | None = None, margin: float = 0.0, self_collision: bool = True
    ) -> list[tuple[str, str]]:
        """Pairs closer than ``margin`` [m] at each of :data:`ALWAYS_SAMPLES` configurations
        drawn uniformly within the limits (seed 0), sorted: a collision goal they are part
        of may have no answer (a UR5's ``ee_link`` and ``wrist_2_link`` are 0.0198 m apart
        whatever the joints: a margin of 0.02 m failed every solve, silently).  Empty as soon
        as one sample is free of contact (the common case: one :meth:`collides_many`)."""
        qs = self.robot.random_q(np.random.default_rng(0), ALWAYS_SAMPLES)
        if not self.collides_many(qs, scene, margin, self_collision).all():
            return []
        common: set[tuple[str, str]] | None = None
        for q in qs:
            pairs = set(self.check(q, scene, margin, self_collision).pairs_in_contact)
            common = pairs if common is None else common & pairs
            if not common:
                return []
        return sorted(common or ())

    def collides_many(
        self, qs: Any, scene: Scene | None = None, margin: float = 0.0, self_collision: bool = True
    ) -> NDArray[np.bool_]:
        """:meth:`collides` of each row of ``qs`` ``(n, nq)`` → ``(n,)`` (checked once).

        Raises:
            InvalidArgumentError: bad ``qs`` or ``margin``.
        """
        m = _margin(margin)
        arr = np.asarray(qs, dtype=float)
        if arr.ndim != 2 or arr.shape[1] != self.robot.nq or not np.isfinite(arr).all():
            raise InvalidArgumentError(
                f"qs must be finite joint vectors of shape (n, {self.robot.nq}), got shape "
                f"{arr.shape}"
            )
        ck = self._checker(as_scene(scene), bool(self_collision))
        to_pin = self.robot.to_pinocchio
        return np.array([ck.collide(to_pin(q, copy=False), m) for q in arr], dtype=bool)

    def body_placements(self, q: Any) -> tuple[FloatArray, FloatArray]:
        """World poses of the collision bodies at ``q`` (Pinocchio):
        rotations ``(nb, 3, 3)`` and positions ``(nb, 3)`` [m]."""
        q = self.robot.check_q(q)
        data = self.robot.model.createData()
        gd = pin.GeometryData(self.geom_model)
        pin.forwardKinematics(self.robot.model, data, self.robot.to_pinocchio(q))
        pin.updateGeometryPlacements(self.robot.model, data, self.geom_model, gd)
        rot = np.array([np.array(m.rotation) for m in gd.oMg])
        pos = np.array([np.array(m.translation) for m in gd.oMg])
        return rot, pos


def _margin(value: Any) -> float:
    """A security margin: a finite number ``>= 0`` [m], or :class:`InvalidArgumentError`
    (coal refuses a negative one deep inside Pinocchio; NaN would pass every pair)."""
    if not is_finite_nonneg(value):
        raise InvalidArgumentError(f"margin must be a finite number >= 0 [m], got {value!r}")
    return float(value)


def load_kernels() -> None:
    """Load the exact check's compiled kernel (numba's cache) before a clock starts: its first
    call in a process takes about 10 ms."""
    empty = np.zeros((0, 3))
    enclosed_points(
        np.zeros((0, 4, 4)), empty, empty, np.zeros(0), empty, np.zeros(0), empty,
        np.zeros((0, 3), dtype=np.int64), np.zeros(1, dtype=np.int64), True,
    )  # fmt: skip


@dataclass(frozen=True)
class Solids:
    """The robot's mesh bodies, taken as solids by the exact check (coal's meshes are
    surfaces), as :func:`swarm_ik.kernels.mesh.enclosed_points` reads them.

    Attributes:
        bodies: Index of each mesh body in the geometry model.
        box: Each one's box in its own frame [m], ``(ns, 2, 3)``: lowest and highest corner.
        reach: Each one's box diagonal [m], ``(ns,)``: no larger obstacle fits inside.
        mesh: ``(verts, tris, tri0)``: every mesh's vertices and triangles, concatenated
            (triangles indexing the whole), mesh ``s`` at triangles ``tri0[s]:tri0[s + 1]``.
    """

    bodies: list[int]
    box: FloatArray
    reach: FloatArray
    mesh: tuple[FloatArray, NDArray[np.int64], NDArray[np.int64]]

    @classmethod
    def of(cls, geom_model: Any) -> Solids:
        import coal

        meshes = [
            (b, _triangles(g.geometry))
            for b, g in enumerate(geom_model.geometryObjects)
            if isinstance(g.geometry, coal.BVHModelBase)
        ]
        verts = [v for _, (v, _) in meshes]
        box = np.array([[v.min(axis=0), v.max(axis=0)] for v in verts]).reshape(-1, 2, 3)
        start = np.cumsum([0] + [v.shape[0] for v in verts])
        tris = [t + start[k] for k, (_, (_, t)) in enumerate(meshes)]
        return cls(
            bodies=[b for b, _ in meshes],
            box=box,
            reach=np.linalg.norm(box[:, 1] - box[:, 0], axis=1),
            mesh=(
                np.concatenate(verts) if verts else np.zeros((0, 3)),
                np.concatenate(tris) if tris else np.zeros((0, 3), dtype=np.int64),
                np.cumsum([0] + [t.shape[0] for t in tris]).astype(np.int64),
            ),
        )


def _triangles(mesh: Any) -> tuple[FloatArray, NDArray[np.int64]]:
    """A coal mesh's vertices ``(nv, 3)`` and triangles ``(nt, 3)`` (indices)."""
    verts = np.array(mesh.vertices(), dtype=float).reshape(-1, 3)
    tris = [mesh.tri_indices(i) for i in range(mesh.num_tris)]
    return verts, np.array([[t[0], t[1], t[2]] for t in tris], dtype=np.int64).reshape(-1, 3)


def _inner_point(obj: Any) -> FloatArray:
    """A world point inside a coal obstacle: a primitive's centre, a mesh's first vertex (an
    obstacle wholly inside a body has all its points inside)."""
    tf = obj.getTransform()
    rot, pos = np.array(tf.getRotation()), np.array(tf.getTranslation())
    geom = obj.collisionGeometry()
    if hasattr(geom, "vertices") and int(getattr(geom, "num_vertices", 0) or 0) > 0:
        return np.asarray(rot @ np.array(geom.vertex(0), dtype=float) + pos)
    return np.asarray(pos)


class _Checker:
    """The exact check of one (scene, self_collision) set of pairs, with per-thread data.

    The robot's self pairs run in a Pinocchio geometry model of the robot's bodies alone
    (exact, and convex hulls of the meshes for distance bounds).  The obstacles stay coal
    objects in coal's dynamic AABB tree (its broad phase): building it is ``O(n log n)`` in
    obstacles (a Pinocchio geometry model holding them grew quadratically: 3,000 obstacles
    took 40 s), and a verdict asks it once, with a tree of the robot's bodies."""

    def __init__(self, rc: RobotCollision, scene: Scene, self_collision: bool) -> None:
        import coal

        self._coal = coal
        self.model = rc.robot.model
        self.data = rc.robot.model.createData()
        nb = rc.nb
        gm, hm = pin.GeometryModel(), pin.GeometryModel()
        is_mesh = []
        for g in rc.geom_model.geometryObjects:
            gm.addGeometryObject(pin.GeometryObject(g))
            h = pin.GeometryObject(g)
            mesh = isinstance(g.geometry, coal.BVHModelBase)
            if mesh:
                g.geometry.buildConvexHull(False, "Qt")  # qhull: the true hull
                h.geometry = g.geometry.convex
            is_mesh.append(mesh)
            hm.addGeometryObject(h)
        pair_map = np.zeros((nb, nb), dtype=bool)
        if self_collision:
            for i, j in rc.self_pairs:
                pair_map[min(i, j), max(i, j)] = True
        # every pair at once from a map (one call each is quadratic in Pinocchio); the pairs
        # come back in row order, the same in both models
        gm.setCollisionPairs(pair_map, True)
        hm.setCollisionPairs(pair_map, True)
        self.gm, self.hm = gm, hm
        self.gd, self.hd = pin.GeometryData(gm), pin.GeometryData(hm)
        # the self pairs of a verdict without margin through Pinocchio's broad phase (the
        # bodies' boxes first: 14 µs against 48 µs for the Panda's 44 pairs); it places the
        # bodies in data and gd as forwardKinematics and updateGeometryPlacements do
        self.self_broad: Any = None
        if len(gm.collisionPairs):
            self.self_broad = pin.BroadPhaseManager_DynamicAABBTreeCollisionManager(
                self.model, gm, self.gd
            )
        self.labels = [
            _key(rc.body_links[cp.first], rc.body_links[cp.second]) for cp in gm.collisionPairs
        ]
        self.exact_by_hull = np.array(
            [not (is_mesh[cp.first] or is_mesh[cp.second]) for cp in gm.collisionPairs], dtype=bool
        )
        self.margin = 0.0
        # the last verdict of collide, keyed by its configuration and margin: a solve checks
        # its answer before judging it, and the judge asks again (scenes are immutable)
        self._last: tuple[Any, bool] = (None, False)
        # the obstacles: coal objects (fixed in the world) in the broad phase's tree
        self.body_links = rc.body_links
        self.bodies = [coal.CollisionObject(g.geometry) for g in gm.geometryObjects]
        # bodies that no joint moves (fixed to the world) are left out of the obstacle pairs:
        # their contacts do not depend on q (a base standing on the table of its scene)
        self.moving = np.asarray(rc.body_joint) != 0
        self.obstacles = [obj for _, obj in scene.coal_objects()]
        self.obstacle_names = [name for name, _ in scene.coal_objects()]
        self.obs_lo, self.obs_hi = scene.boxes()  # (computes each object's box)
        self.manager: Any = None
        self.body_manager: Any = None
        self._scene_broad: Any = None  # (built on the first verdict without margin)
        # coal's meshes are surfaces: an obstacle wholly inside a body's mesh touches none of
        # its triangles.  The robot's mesh bodies as solids (enclosed_pairs), and the
        # obstacles small enough to fit in one (an obstacle's box's longest side is at most a
        # body's diameter, at most the diagonal of the body's box): a point of each, sorted
        # by x
        self.solids = rc.solids()
        self.solid_lo = np.ascontiguousarray(self.solids.box[:, 0])
        self.solid_hi = np.ascontiguousarray(self.solids.box[:, 1])
        # (a fixed body's solid holds no obstacle: its reach below any obstacle's size)
        self.solid_reach = np.where(self.moving[self.solids.bodies], self.solids.reach, -1.0)
        size = (self.obs_hi - self.obs_lo).max(axis=1) if self.obstacles else np.zeros(0)
        reach = float(self.solid_reach.max()) if len(self.solids.bodies) else -1.0
        small = np.flatnonzero(size <= reach)
        self.small = bool(small.size)
        if self.small:
            points = np.array([_inner_point(self.obstacles[o]) for o in small.tolist()])
            order = np.argsort(points[:, 0], kind="stable")
            self.small_points = np.ascontiguousarray(points[order])
            self.small_sizes = np.ascontiguousarray(size[small][order])
            self.small_obstacles = small[order]
        if self.obstacles:
            self.manager = coal.DynamicAABBTreeCollisionManager()
            for obj in self.obstacles:
                self.manager.registerObject(obj)
            self.manager.setup()
            # the bodies in a tree of their own: one query of tree against tree
            self.body_manager = coal.DynamicAABBTreeCollisionManager()
            for obj, moving in zip(self.bodies, self.moving.tolist(), strict=True):
                if moving:
                    self.body_manager.registerObject(obj)
            self.body_manager.setup()
            self._warn_fixed_contacts(rc, scene)

    def _set_margin(self, margin: float) -> None:
        if margin != self.margin:
            for req in self.gd.collisionRequests:
                req.security_margin = margin
            self.margin = margin

    def _place(self, q_pin: FloatArray, placed: bool = False) -> None:
        """The bodies at ``q_pin``: Pinocchio's placements (unless already ``placed``) and,
        with obstacles, the coal objects' (which only the obstacle queries read)."""
        if not placed:
            pin.forwardKinematics(self.model, self.data, q_pin)
            pin.updateGeometryPlacements(self.model, self.data, self.gm, self.gd)
        if self.manager is None:
            return
        for obj, placement in zip(self.bodies, self.gd.oMg, strict=True):
            obj.setTransform(placement)
            obj.computeAABB()

    def _scene_manager(self) -> Any:
        """Pinocchio's broad phase over one geometry model of the robot's bodies and the
        obstacles (the self pairs, and every body with every obstacle), for a scene of at
        most :data:`SMALL_SCENE` obstacles; None for a larger one."""
        if self._scene_broad is None and len(self.obstacles) <= SMALL_SCENE:
            gm = pin.GeometryModel()
            for g in self.gm.geometryObjects:
                gm.addGeometryObject(pin.GeometryObject(g))
            for name, obj in zip(self.obstacle_names, self.obstacles, strict=True):
                tf = obj.getTransform()
                placement = pin.SE3(np.array(tf.getRotation()), np.array(tf.getTranslation()))
                gm.addGeometryObject(
                    pin.GeometryObject(name, 0, placement, obj.collisionGeometry())
                )
            nb, n = len(self.gm.geometryObjects), len(gm.geometryObjects)
            pair_map = np.zeros((n, n), dtype=bool)
            for cp in self.gm.collisionPairs:
                pair_map[cp.first, cp.second] = True
            pair_map[np.flatnonzero(self.moving), nb:] = True
            gm.setCollisionPairs(pair_map, True)
            self._scene_data = self.model.createData()
            self._scene_gm, self._scene_gd = gm, pin.GeometryData(gm)  # (kept alive)
            self._scene_broad = pin.BroadPhaseManager_DynamicAABBTreeCollisionManager(
                self.model, gm, self._scene_gd
            )
        return self._scene_broad

    def collide(self, q_pin: FloatArray, margin: float) -> bool:
        """Whether any pair is in contact (stops at the first), an obstacle inside a body's
        mesh included (:meth:`enclosed_pairs`)."""
        key = (q_pin.tobytes(), margin)
        if self._last[0] == key:
            return self._last[1]
        out = self._touch(q_pin, margin) or (
            self.small and bool(self.enclosed_pairs(q_pin, True, self._placed))
        )
        self._last = (key, out)
        return out

    def enclosed_pairs(
        self, q_pin: FloatArray, first: bool = False, placed: Any = None
    ) -> list[tuple[int, int]]:
        """``(body, obstacle)`` pairs where an obstacle lies inside a body's mesh (so touches
        none of its triangles: coal's narrow phase finds no contact), at ``q_pin``: for each
        obstacle that fits in a body, its inner point's generalised winding number about the
        body's closed mesh is above a half (Jacobson et al. 2013: robust to small holes).
        ``first``: stop at the first; ``placed``: a geometry data whose first bodies are
        placed at ``q_pin`` already (else they are placed here)."""
        if placed is None:
            pin.forwardKinematics(self.model, self.data, q_pin)
            pin.updateGeometryPlacements(self.model, self.data, self.gm, self.gd)
            placed = self.gd
        oMg, sd = placed.oMg, self.solids
        pairs = enclosed_points(
            np.array([oMg[b].homogeneous for b in sd.bodies]), self.solid_lo, self.solid_hi,
            self.solid_reach, self.small_points, self.small_sizes, *sd.mesh, bool(first),
        )  # fmt: skip
        return [(sd.bodies[s], int(self.small_obstacles[i])) for s, i in pairs.tolist()]

    def _touch(self, q_pin: FloatArray, margin: float) -> bool:
        """Whether any pair's surfaces come within ``margin`` (stops at the first)."""
        self._placed: Any = None  # (the geometry data placed at q_pin: enclosed_pairs)
        if not self.labels and self.manager is None:
            return False
        self._set_margin(margin)
        if margin == 0.0 and self.manager is not None:  # a small scene: one C++ call
            broad = self._scene_manager()
            if broad is not None:  # (its bodies come first, placed by the call)
                self._placed = self._scene_gd
                return bool(pin.computeCollisions(self.model, self._scene_data, broad, q_pin, True))
        self._placed = self.gd  # (each way below places the bodies in self.gd)
        if margin == 0.0 and self.self_broad is not None:  # (its boxes ignore a margin)
            if pin.computeCollisions(self.model, self.data, self.self_broad, q_pin, True):
                return True
            if self.manager is None:
                return False
            self._place(q_pin, placed=True)
        else:
            self._place(q_pin)
            if self.labels and pin.computeCollisions(self.gm, self.gd, True):
                return True
            if self.manager is None:
                return False
        coal = self._coal
        self.body_manager.update()  # (the bodies' new boxes)
        if margin == 0.0:
            hit = coal.CollisionCallBackDefault()
            self.manager.collide(self.body_manager, hit)
            return bool(hit.data.result.isCollision())
        # (the trees' boxes ignore a security margin: the smallest distance instead)
        near = coal.DistanceCallBackDefault()
        self.manager.distance(self.body_manager, near)
        return bool(near.data.result.min_distance < margin)

    def _gaps(self) -> FloatArray:
        """Lower bounds of the body–obstacle distances ``(nb, n_obstacles)`` [m]: the gaps
        between their axis-aligned boxes."""
        boxes = [obj.getAABB() for obj in self.bodies]
        lo = np.array([np.array(b.min_) for b in boxes])
        hi = np.array([np.array(b.max_) for b in boxes])
        gap = np.maximum(
            np.maximum(lo[:, None, :] - self.obs_hi[None], self.obs_lo[None] - hi[:, None, :]),
            0.0,
        )
        out = np.sqrt((gap * gap).sum(-1))
        out[~self.moving] = np.inf  # (bodies fixed to the world: no obstacle pairs)
        return np.asarray(out)

    def _warn_fixed_contacts(self, rc: RobotCollision, scene: Scene) -> None:
        """One warning naming the bodies fixed to the world that touch an obstacle (whatever
        the joints, so left out of the check like every pair of such a body)."""
        coal = self._coal
        self._place(rc.robot.to_pinocchio(rc.robot.mid_q()))  # (the bodies' coal objects)
        touching = []
        for b in np.flatnonzero(~self.moving).tolist():
            body = self.bodies[b]
            box = body.getAABB()
            lo, hi = np.array(box.min_), np.array(box.max_)
            near = np.all((self.obs_lo <= hi) & (self.obs_hi >= lo), axis=1)  # (boxes meet)
            for o in np.flatnonzero(near).tolist():
                obj = self.obstacles[o]
                if coal.collide(body, obj, coal.CollisionRequest(), coal.CollisionResult()):
                    touching.append(f"{rc.body_links[b]}–{self.obstacle_names[o]}")
        if touching:
            warnings.warn(
                f"{', '.join(sorted(set(touching)))}: fixed to the world, in contact whatever "
                "the joints; such pairs are left out of the collision check",
                stacklevel=user_stacklevel(),
            )

    def _obstacle_distance(self, b: int, o: int) -> float:
        coal = self._coal
        return float(
            coal.distance(
                self.bodies[b], self.obstacles[o], coal.DistanceRequest(), coal.DistanceResult()
            )
        )

    def run(self, q_pin: FloatArray, margin: float) -> CollisionReport:
        """Check Pinocchio configuration ``q_pin`` of the chain model."""
        gm, gd, hm, hd = self.gm, self.gd, self.hm, self.hd
        coal = self._coal
        n_self, n_obs = len(self.labels), len(self.obstacles)
        if n_self == 0 and n_obs == 0:
            return CollisionReport(True, float("inf"), [], None)
        self._set_margin(margin)
        self._place(q_pin)
        if n_self:
            pin.computeCollisions(gm, gd, False)
        self_hits = [k for k in range(n_self) if gd.collisionResults[k].isCollision()]
        gaps = self._gaps() if n_obs else np.zeros((len(self.bodies), 0))
        obs_hits = []
        request = coal.CollisionRequest()
        request.security_margin = margin
        for b, o in np.argwhere(gaps <= margin).tolist():  # (the narrow phase where boxes meet)
            if coal.collide(self.bodies[b], self.obstacles[o], request, coal.CollisionResult()):
                obs_hits.append((b, o))
        enclosed = self.enclosed_pairs(q_pin, placed=gd) if self.small else []
        obs_hits += [pair for pair in enclosed if pair not in obs_hits]
        best, best_label = float("inf"), None
        if self_hits or obs_hits:
            for k in self_hits:
                pin.computeDistance(gm, gd, k)
                d = float(gd.distanceResults[k].min_distance)
                if d < best:
                    best, best_label = d, self.labels[k]
            for b, o in obs_hits:
                d = self._obstacle_distance(b, o)
                if (b, o) in enclosed:  # (inside: the distance out to the surface, negated)
                    d = -abs(d)
                if d < best:
                    best, best_label = d, (self.body_links[b], self.obstacle_names[o])
            if margin == 0.0:
                best = min(best, 0.0)
            contact = {self.labels[k] for k in self_hits}
            contact |= {(self.body_links[b], self.obstacle_names[o]) for b, o in obs_hits}
            return CollisionReport(False, best, sorted(contact), best_label)
        # the clearance: exact distances in the order of their lower bounds (the convex hulls
        # of the self pairs, the boxes of the obstacle pairs) until a bound exceeds the best
        if n_self:
            pin.updateGeometryPlacements(self.model, self.data, hm, hd)
            pin.computeDistances(hm, hd)
        bound = np.concatenate(
            [[hd.distanceResults[k].min_distance for k in range(n_self)], gaps.ravel()]
        )
        for k in np.argsort(bound, kind="stable").tolist():
            if bound[k] >= best:
                break
            if k < n_self:
                if self.exact_by_hull[k]:
                    d = float(bound[k])
                else:
                    pin.computeDistance(gm, gd, k)
                    d = float(gd.distanceResults[k].min_distance)
                label = self.labels[k]
            else:
                b, o = divmod(k - n_self, n_obs)
                d = self._obstacle_distance(b, o)
                label = (self.body_links[b], self.obstacle_names[o])
            if d < best:
                best, best_label = d, label
        return CollisionReport(True, best, [], best_label)


ALWAYS_SAMPLES = 16
"""Random configurations :meth:`RobotCollision.pairs_always_in_contact` checks."""


# ---------------------------------------------------------------------- sampling rule
def _sampled_rule(
    robot: Any,
    geom: Any,
    links: tuple[str, ...],
    candidates: list[tuple[str, str]],
    samples: int,
    seed: int,
    urdf: Path,
    use_cache: bool,
) -> tuple[list[tuple[str, str]], list[tuple[str, str]]]:
    """MoveIt's rule on the candidate link pairs: (never, always) in ``samples`` random
    configurations, cached per URDF content, locked joints, samples and seed."""
    h = hashlib.sha256()
    h.update(urdf.read_bytes())
    h.update(
        json.dumps(
            [
                list(robot.locked_joints),
                np.asarray(robot.q_locked).round(12).tolist(),
                samples,
                seed,
                ALWAYS_FRACTION,
                _RULE_VERSION,
                sorted(candidates),
            ]
        ).encode()
    )
    path = cache_dir() / f"pairs-{h.hexdigest()[:20]}.json"
    if use_cache and path.is_file():
        try:  # a damaged file (unreadable, not UTF-8, not JSON, another shape) is a miss
            data = json.loads(path.read_text())
            return [tuple(p) for p in data["never"]], [tuple(p) for p in data["always"]]  # type: ignore[misc]
        except (OSError, ValueError, KeyError, TypeError):
            pass
    gm = pin.GeometryModel()
    for g in geom.geometryObjects:
        gm.addGeometryObject(pin.GeometryObject(g))
    want = {_key(*p) for p in candidates}
    pair_link: list[tuple[str, str]] = []
    for i, j in combinations(range(gm.ngeoms), 2):
        key = _key(links[i], links[j])
        if links[i] != links[j] and key in want:
            gm.addCollisionPair(pin.CollisionPair(i, j))
            pair_link.append(key)
    gd = pin.GeometryData(gm)
    data = robot.model.createData()
    rng = np.random.default_rng(seed)
    counts = dict.fromkeys(want, 0)
    for q in robot.random_q(rng, samples):
        pin.computeCollisions(robot.model, data, gm, gd, robot.to_pinocchio(q), False)
        hit = {pair_link[k] for k in range(len(pair_link)) if gd.collisionResults[k].isCollision()}
        for key in hit:
            counts[key] += 1
    never = sorted(k for k, c in counts.items() if c == 0)
    always = sorted(k for k, c in counts.items() if c >= ALWAYS_FRACTION * samples)
    if use_cache:  # a failed write (a full disk, a folder turned read-only) is skipped
        tmp = path.with_suffix(f".tmp{os.getpid()}")
        try:
            tmp.write_text(json.dumps({"never": never, "always": always, "samples": samples}))
            tmp.replace(path)
        except OSError:
            with contextlib.suppress(OSError):
                tmp.unlink()
    return never, always
