"""Sphere approximation of the collision geometry and its compiled penetration residual.

**Fitting** (:func:`fit_spheres`).  Every collision body is covered by spheres, so that the
spheres being apart implies the bodies being apart (conservative):

* a sphere is itself;
* a capsule gets ``n + 1`` spheres centred on its segment (ends included), ``n`` chosen so
  that the radius ``sqrt(r² + (L/2n)²)`` exceeds ``r`` by at most the tolerance;
* meshes, boxes and cylinders (as a 64-sided prism, the radii then grown by the sagitta
  ``r(1 - cos(π/64))``) go through a greedy cover: the surface is subdivided to edges of at
  most half the tolerance; candidate centres are grid points inside the mesh (generalised
  winding number > 1/2) and the surface points themselves; a candidate ``c`` at distance
  ``ρ(c)`` from the surface covers the surface points within ``ρ(c) + tolerance``; candidates
  are taken greedily (most uncovered points first) until every point is covered.  Each
  subdivided triangle is then given to the sphere that needs the least growth to contain its
  three vertices and every radius is set to its farthest assigned vertex; a sphere containing
  the three vertices of a triangle contains the triangle, so **the whole surface is covered**
  (the check coal does on meshes is a surface check too).  A sphere sticks out of the body by
  about the tolerance at most.

Fitted spheres are cached per URDF (a hash of every body's geometry and the tolerance) in
:func:`swarm_ik.paths.cache_dir`.

**Obstacles** keep their exact shape in compiled code: signed distance functions of a sphere,
box, capsule and cylinder (exact Euclidean distances, so a robot sphere of radius ``r`` is
clear of an obstacle iff the SDF at its centre is ``>= r``).  A mesh obstacle is covered by
spheres as above.

**Residual** (:func:`penetration`): one row ``max(0, margin + r_i + r_j − |c_i − c_j|)`` per
active sphere pair of an enabled body pair and ``max(0, margin + r_i − sdf_k(c_i))`` per
active sphere–obstacle pair (spheres of the bodies that ``q`` moves; a body fixed to the
world is left out, as the exact check leaves it), with its Jacobian.  Body pairs (and
body–obstacle pairs) are culled first with each body's bounding sphere.  The centre
``c = R c_local + p`` of a sphere moves with the body Jacobian ``J`` (LOCAL_WORLD_ALIGNED at
the body origin, rows ``[v; ω]``) as ``J_c = J_v − [R c_local]× J_ω``.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import sys
from dataclasses import dataclass
from typing import Any

import numpy as np

from swarm_ik._signals import sigint_deferred
from swarm_ik._types import FloatArray, IntArray
from swarm_ik.errors import InvalidArgumentError
from swarm_ik.kernels.mesh import triangle_owners, winding_numbers
from swarm_ik.kernels.spheres import (
    BOX,
    CAPSULE,
    CYLINDER,
    SPHERE,
    SphereArrays,
    penetration,
    sphere_centres,
)

TOLERANCE = 0.02
"""Default fitting tolerance [m]: how far a sphere may stick out of its body (about)."""

COARSE_SAMPLES = 500
"""Random configurations of the coarse-pair rule of :meth:`SphereModel.from_collision`."""

_CYL_SECTIONS = 64
_FIT_VERSION = 1


# ============================================================================ fitting
WINDING_PAIRS = 2e7
"""Most point–triangle pairs of the inside test of a fit (about 0.5 s compiled): a mesh of more
than 10,000 triangles gets a coarser grid of interior candidate centres (the surface points
remain candidates, so the cover stays complete; a 327,680-triangle ball took 250 s)."""

MAX_FIT_TRIANGLES = 5e6
"""Most triangles a mesh is subdivided into for its sphere cover (about 1 GB of work arrays;
a mesh scaled a million times at a 2 cm tolerance needs 10¹⁸)."""


def _import_trimesh() -> Any:
    """``trimesh``, a Ctrl-C during its first import kept: trimesh guards its optional
    imports with ``except BaseException``, which took the ``KeyboardInterrupt`` of a Ctrl-C
    arriving meanwhile (a first collision solve then printed its whole answer); the signal is
    recorded during the import and raised after it."""
    if "trimesh" in sys.modules:
        import trimesh

        return trimesh
    with sigint_deferred():
        import trimesh
    return trimesh


def fit_mesh(
    vertices: FloatArray, faces: IntArray, tolerance: float
) -> tuple[FloatArray, FloatArray]:
    """Spheres covering the surface of a triangle mesh (greedy cover, see the module docs).

    Args:
        vertices: Mesh vertices [m], shape ``(nv, 3)``.
        faces: Triangles (vertex indices), shape ``(nf, 3)``.
        tolerance: How far a sphere may stick out of the surface [m] (about).

    Returns:
        Centres ``(k, 3)`` [m] and radii ``(k,)`` [m] in the mesh frame.
    """
    import scipy.sparse as sp
    from scipy.spatial import cKDTree

    trimesh = _import_trimesh()

    V = np.asarray(vertices, dtype=float)
    F = np.asarray(faces, dtype=np.int64)
    tri = V[F]
    area = 0.5 * float(
        np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum()
    )
    pieces = 4.0 * area / (0.5 * tolerance) ** 2  # (triangles of the subdivision, about)
    if not np.isfinite(pieces) or pieces > MAX_FIT_TRIANGLES:
        raise InvalidArgumentError(
            f"a mesh of {area:.3g} m² needs about {pieces:.3g} triangles to be covered by "
            f"spheres at a tolerance of {tolerance:g} m; at most {MAX_FIT_TRIANGLES:.0e} "
            "(swarm_ik.spheres.MAX_FIT_TRIANGLES): a coarser tolerance, or a smaller mesh"
        )
    V2, F2 = trimesh.remesh.subdivide_to_size(V, F, max_edge=0.5 * tolerance, max_iter=30)
    V2 = np.asarray(V2, dtype=float)
    F2 = np.asarray(F2, dtype=np.int64)
    dense = cKDTree(np.vstack([V2, V2[F2].mean(axis=1)]))  # for distances to the surface
    pts = _voxel_subsample(np.vstack([V, V2]), 0.5 * tolerance)  # points the greedy covers
    lo, hi = V.min(axis=0), V.max(axis=0)
    ext = np.maximum(hi - lo, 1e-9)
    n_grid = min(2000.0, max(8.0, WINDING_PAIRS / len(F)))  # (interior candidates, about)
    pitch = max(0.5 * tolerance, float(np.prod(ext) / n_grid) ** (1.0 / 3.0))
    axes = [np.arange(lo[i] + 0.5 * pitch, hi[i], pitch) for i in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    if len(grid):
        inside = np.empty(len(grid))
        winding_numbers(V, np.ascontiguousarray(F), np.ascontiguousarray(grid), inside)
        grid = grid[inside > 0.5]
    cand = np.vstack([grid, pts]) if len(grid) else pts.copy()
    rho = dense.query(cand)[0]
    reach = rho + tolerance
    lists = cKDTree(pts).query_ball_point(cand, reach)
    lens = np.array([len(x) for x in lists])
    rows = np.repeat(np.arange(len(cand)), lens)
    cols = np.concatenate([np.asarray(x, dtype=np.int64) for x in lists])
    cover = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(cand), len(pts)))
    by_point = cover.T.tocsr()
    gain = lens.astype(np.int64)
    uncovered = np.ones(len(pts), dtype=bool)
    chosen: list[int] = []
    while uncovered.any():  # greedy set cover with incremental gains
        best = int(np.argmax(gain))
        if gain[best] <= 0:  # cannot happen: every point is a candidate covering itself
            raise RuntimeError("sphere cover did not progress")
        chosen.append(best)
        row = cover.indices[cover.indptr[best] : cover.indptr[best + 1]]
        new = row[uncovered[row]]
        uncovered[new] = False
        hit = np.concatenate(
            [by_point.indices[by_point.indptr[p] : by_point.indptr[p + 1]] for p in new]
        )
        gain -= np.bincount(hit, minlength=len(cand))
    centres = cand[chosen]
    nominal = reach[chosen]
    owner = np.empty(len(F2), dtype=np.int64)
    need_own = np.empty(len(F2))
    triangle_owners(np.ascontiguousarray(V2[F2]), centres, nominal, owner, need_own)
    radii = np.zeros(len(centres))
    np.maximum.at(radii, owner, need_own)
    keep = np.isin(np.arange(len(centres)), owner)
    return centres[keep], radii[keep]


def _voxel_subsample(points: FloatArray, pitch: float) -> FloatArray:
    """One point per voxel of edge ``pitch`` (the first one)."""
    keys = np.floor(points / pitch).astype(np.int64)
    _, idx = np.unique(keys, axis=0, return_index=True)
    return points[np.sort(idx)]


def fit_spheres(geometry: Any, tolerance: float = TOLERANCE) -> tuple[FloatArray, FloatArray]:
    """Spheres covering one coal collision geometry, in its own frame.

    Args:
        geometry: A coal ``Sphere``, ``Capsule``, ``Box``, ``Cylinder`` or BVH mesh.
        tolerance: How far a sphere may stick out of the body [m] (about).

    Returns:
        Centres ``(k, 3)`` [m] and radii ``(k,)`` [m].

    Raises:
        RobotModelError: another geometry type (the supported ones listed).
    """
    import coal

    from swarm_ik.errors import RobotModelError

    trimesh = _import_trimesh()

    if isinstance(geometry, coal.Sphere):
        return np.zeros((1, 3)), np.array([float(geometry.radius)])
    if isinstance(geometry, coal.Capsule):
        r, hl = float(geometry.radius), float(geometry.halfLength)
        step = 2.0 * math.sqrt((r + tolerance) ** 2 - r**2)
        n = max(1, math.ceil(2.0 * hl / step))
        z = np.linspace(-hl, hl, n + 1)
        centres = np.column_stack([np.zeros(n + 1), np.zeros(n + 1), z])
        return centres, np.full(n + 1, math.hypot(r, hl / n))
    if isinstance(geometry, coal.Box):
        mesh = trimesh.creation.box(extents=2.0 * np.asarray(geometry.halfSide))
        return fit_mesh(mesh.vertices, mesh.faces, tolerance)
    if isinstance(geometry, coal.Cylinder):
        r, hl = float(geometry.radius), float(geometry.halfLength)
        mesh = trimesh.creation.cylinder(radius=r, height=2.0 * hl, sections=_CYL_SECTIONS)
        c, rad = fit_mesh(mesh.vertices, mesh.faces, tolerance)
        return c, rad + r * (1.0 - math.cos(math.pi / _CYL_SECTIONS))
    if isinstance(geometry, coal.BVHModelBase):
        v, f = mesh_arrays(geometry)
        return fit_mesh(v, f, tolerance)
    raise RobotModelError(
        f"cannot fit spheres to a coal {type(geometry).__name__}; supported: Sphere, Capsule, "
        "Box, Cylinder, BVH mesh"
    )


def mesh_arrays(bvh: Any) -> tuple[FloatArray, IntArray]:
    """Vertices ``(nv, 3)`` and triangles ``(nt, 3)`` of a coal BVH mesh."""
    v = np.array(bvh.vertices(), dtype=float).reshape(-1, 3)
    f = np.array(
        [[t[0], t[1], t[2]] for t in (bvh.tri_indices(i) for i in range(bvh.num_tris))],
        dtype=np.int64,
    ).reshape(-1, 3)
    return v, f


def _geometry_key(geometry: Any) -> bytes:
    import coal

    h = hashlib.sha256(type(geometry).__name__.encode())
    if isinstance(geometry, coal.BVHModelBase):
        v, f = mesh_arrays(geometry)
        h.update(np.round(v, 12).tobytes())
        h.update(f.tobytes())
    else:
        for attr in ("radius", "halfLength", "halfSide"):
            if hasattr(geometry, attr):
                h.update(np.round(np.atleast_1d(getattr(geometry, attr)), 12).tobytes())
    return h.digest()


def fit_bodies(
    geometries: list[Any], tolerance: float = TOLERANCE, use_cache: bool = True
) -> list[tuple[FloatArray, FloatArray]]:
    """:func:`fit_spheres` of every geometry, cached on disk by a hash of all of them."""
    from swarm_ik.paths import cache_dir

    h = hashlib.sha256(json.dumps([_FIT_VERSION, round(tolerance, 12)]).encode())
    for g in geometries:
        h.update(_geometry_key(g))
    path = cache_dir() / f"spheres-{h.hexdigest()[:20]}.npz"
    if use_cache and path.is_file():
        # a damaged or foreign file (truncated: BadZipFile, EOFError; not an .npz: an array
        # without a context manager) is a cache miss, fitted again and overwritten
        try:
            with np.load(path) as z:
                body, centres, radii = z["body"], z["centres"], z["radii"]
            fits = [(centres[body == k], radii[body == k]) for k in range(len(geometries))]
            if (
                centres.shape == (len(body), 3)
                and radii.shape == body.shape
                and all(len(r) for _, r in fits)
            ):
                return fits
        except Exception:
            pass
    fits = [fit_spheres(g, tolerance) for g in geometries]
    if use_cache:  # a failed write (a full disk, a folder turned read-only) is skipped
        tmp = path.with_name(path.stem + f".tmp{id(fits)}.npz")
        try:
            np.savez(
                tmp,
                body=np.concatenate([np.full(len(r), k) for k, (_, r) in enumerate(fits)]),
                centres=np.vstack([c for c, _ in fits]),
                radii=np.concatenate([r for _, r in fits]),
            )
            tmp.replace(path)
        except OSError:
            with contextlib.suppress(OSError):
                tmp.unlink()
    return fits


_NO_ROWS = (np.empty((0, 6, 0)), np.empty(0), np.empty((0, 0)), np.empty((0, 2), dtype=np.int64))


def penetration_cost(
    rot: FloatArray, pos: FloatArray, arrays: SphereArrays, margin: float, scratch: FloatArray
) -> tuple[float, float]:
    """Sum of squared residuals [m²] over every active pair and the largest residual [m]
    (0 when clear): :func:`~swarm_ik.kernels.spheres.penetration` without its rows (the
    swarm's fitness term)."""
    jac, res, rows_jac, pair = _NO_ROWS
    _, total, worst = penetration(
        rot, pos, jac, arrays, float(margin), scratch, False, res, rows_jac, pair
    )
    return float(total), float(worst)


def _drop_coarse_pairs(
    rc: Any,
    pairs: IntArray,
    spheres: tuple[IntArray, FloatArray, FloatArray, IntArray, FloatArray, FloatArray],
    samples: int,
) -> tuple[IntArray, list[tuple[str, str]]]:
    """Split off the self body pairs whose spheres overlap in >= 95 % of ``samples`` random
    configurations (seed 0) while coal finds the two bodies in contact in none (``spheres``:
    the first six fields of :class:`SphereArrays`)."""
    import pinocchio as pin

    robot = rc.robot
    gm = pin.GeometryModel()
    for g in rc.geom_model.geometryObjects:
        gm.addGeometryObject(pin.GeometryObject(g))
    for a, b in pairs:
        gm.addCollisionPair(pin.CollisionPair(int(a), int(b)))
    gd = pin.GeometryData(gm)
    data = robot.model.createData()
    npair = len(pairs)
    overlap = np.zeros(npair, dtype=np.int64)
    touch = np.zeros(npair, dtype=np.int64)
    sph_body, body_start = spheres[0], spheres[3]
    scratch = np.empty((len(spheres[2]), 6))
    no_bodies = np.zeros(0, np.int64)
    no_obs = (np.zeros(0, np.int64), np.zeros((0, 3, 3)), np.zeros((0, 3)), np.zeros((0, 3)))
    model = SphereArrays(*spheres, np.ascontiguousarray(pairs), no_bodies, *no_obs)
    # one call per sample: a row per overlapping sphere pair (room for every pair of every
    # body pair), the body pairs read from its spheres (a call per body pair: 0.2-0.3 s)
    sizes = np.diff(body_start)
    room = max(int(sum(int(sizes[a]) * int(sizes[b]) for a, b in pairs)), 1)
    res, pair = np.zeros(room), np.zeros((room, 2), dtype=np.int64)
    no_jac, no_rows = np.zeros((len(sizes), 6, 0)), np.zeros((room, 0))
    index = {(int(a), int(b)): k for k, (a, b) in enumerate(pairs)}
    rng = np.random.default_rng(0)
    for q in robot.random_q(rng, samples):
        q_pin = robot.to_pinocchio(q)
        pin.computeCollisions(robot.model, data, gm, gd, q_pin, False)
        rot = np.array([np.array(m.rotation) for m in gd.oMg])
        pos = np.array([np.array(m.translation) for m in gd.oMg])
        for k in range(npair):
            touch[k] += gd.collisionResults[k].isCollision()
        rows, _, _ = penetration(rot, pos, no_jac, model, 0.0, scratch, True, res, no_rows, pair)
        hit = {(int(sph_body[i]), int(sph_body[j])) for i, j in pair[:rows].tolist()}
        for body_pair in hit:
            overlap[index[body_pair]] += 1
    coarse = (overlap >= 0.95 * samples) & (touch == 0)
    names = [(rc.body_links[int(a)], rc.body_links[int(b)]) for a, b in pairs[coarse]]
    return pairs[~coarse], sorted(set(names))


# ====================================================================== the wrapper
@dataclass(eq=False)
class SphereModel:
    """Arrays of the sphere approximation of a robot (and of a scene's obstacles).

    Build it with :meth:`from_collision`.  Body ``b`` is body ``b`` of the
    :class:`~swarm_ik.collision.RobotCollision` (a Pinocchio geometry object); its world pose
    is ``oMi[body_joint[b]] * (body_frame_rot[b], body_frame_pos[b])``.

    Attributes:
        body_joint: Reduced-model joint of each body (0: the world), ``(nb,)``; the kernels'
            tree joint index is ``body_joint - 1`` (``-1``: the root).
        body_frame_rot: Body placement in its joint frame, ``(nb, 3, 3)``.
        body_frame_pos: Its translation [m], ``(nb, 3)``.
        arrays: The arrays of :func:`penetration` (:class:`SphereArrays`; ``obs_bodies``: the
            bodies not fixed to the world).
        obs_names: Scene obstacle each obstacle entry comes from (a mesh gives several).
        tolerance: Fitting tolerance [m].
        coarse_pairs: Enabled self pairs (link names) left out of the residual because their
            spheres overlap in nearly every configuration while the bodies never touch; the
            exact check still tests them.
    """

    collision: Any
    body_joint: IntArray
    body_frame_rot: FloatArray
    body_frame_pos: FloatArray
    arrays: SphereArrays
    obs_names: tuple[str, ...]
    tolerance: float
    coarse_pairs: tuple[tuple[str, str], ...] = ()

    @classmethod
    def from_collision(
        cls,
        robot_collision: Any,
        scene: Any = None,
        tolerance: float = TOLERANCE,
        self_collision: bool = True,
    ) -> SphereModel:
        """Fit spheres to every body of ``robot_collision`` (read from and written to the
        cache folder) and convert ``scene``.

        A self pair whose spheres overlap in at least 95 % of :data:`COARSE_SAMPLES` random
        configurations while the exact geometry touches in none is left to the exact check
        alone (listed in ``coarse_pairs``); e.g. UR5's ``ee_link`` box, always a few
        millimetres from ``wrist_2_link``.

        Args:
            robot_collision: A :class:`~swarm_ik.collision.RobotCollision`.
            scene: A :class:`~swarm_ik.scene.Scene` (or shapes, a JSON path, ``None``).
            tolerance: Fitting tolerance [m].
            self_collision: Keep the enabled self-collision body pairs (else none).
        """
        import coal

        from swarm_ik.scene import Box, Capsule, Cylinder, Mesh, Sphere, as_scene

        tolerance = float(tolerance)
        if not (np.isfinite(tolerance) and tolerance > 0.0):
            raise InvalidArgumentError(f"tolerance must be a positive number [m], got {tolerance}")
        rc = robot_collision
        objs = list(rc.geom_model.geometryObjects)
        fits = fit_bodies([g.geometry for g in objs], tolerance)
        counts = [len(r) for _, r in fits]
        body_start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        sph_local = np.vstack([c for c, _ in fits])
        sph_radius = np.concatenate([r for _, r in fits])
        sph_body = np.concatenate([np.full(n, k) for k, n in enumerate(counts)]).astype(np.int64)
        bound_local = np.zeros((len(objs), 3))
        bound_radius = np.zeros(len(objs))
        for k, (c, r) in enumerate(fits):
            mid = 0.5 * (c.min(axis=0) + c.max(axis=0))
            bound_local[k] = mid
            bound_radius[k] = float(np.max(np.linalg.norm(c - mid, axis=1) + r))
        pairs = np.array(rc.self_pairs if self_collision else [], dtype=np.int64).reshape(-1, 2)
        spheres = (sph_body, sph_local, sph_radius, body_start, bound_local, bound_radius)
        coarse: list[tuple[str, str]] = []
        if len(pairs):  # (the robot's own: made once per robot)
            if tolerance not in rc.coarse_rule:
                rc.coarse_rule[tolerance] = _drop_coarse_pairs(rc, pairs, spheres, COARSE_SAMPLES)
            pairs, coarse = rc.coarse_rule[tolerance]
        kinds, rots, poss, dims, names = [], [], [], [], []
        sc = as_scene(scene)
        for k, (name, o) in enumerate(zip(sc.names, sc.obstacles, strict=True)):
            pose = np.array(o.pose, dtype=float)
            if isinstance(o, Sphere):
                kinds.append(SPHERE)
                dims.append([o.radius, 0.0, 0.0])
            elif isinstance(o, Box):
                kinds.append(BOX)
                dims.append([0.5 * v for v in o.size])
            elif isinstance(o, (Capsule, Cylinder)):
                kinds.append(CAPSULE if isinstance(o, Capsule) else CYLINDER)
                dims.append([o.radius, 0.5 * o.length, 0.0])
            else:
                assert isinstance(o, Mesh)
                geo = sc.coal_objects()[k][1].collisionGeometry()  # (loaded once per scene)
                assert isinstance(geo, coal.BVHModelBase)
                ((c, r),) = fit_bodies([geo], tolerance)
                for ck, rk in zip(c, r, strict=True):
                    kinds.append(SPHERE)
                    dims.append([rk, 0.0, 0.0])
                    rots.append(np.eye(3))
                    poss.append(pose[:3, :3] @ ck + pose[:3, 3])
                    names.append(name)
                continue
            rots.append(pose[:3, :3])
            poss.append(pose[:3, 3])
            names.append(name)
        return cls(
            collision=rc,
            body_joint=np.array(rc.body_joint, dtype=np.int64),
            body_frame_rot=np.array([np.array(g.placement.rotation) for g in objs]).reshape(
                -1, 3, 3
            ),
            body_frame_pos=np.array([np.array(g.placement.translation) for g in objs]).reshape(
                -1, 3
            ),
            arrays=SphereArrays(
                *spheres,
                pairs,
                np.flatnonzero(np.array(rc.body_joint) != 0).astype(np.int64),
                np.array(kinds, dtype=np.int64),
                np.array(rots, dtype=float).reshape(-1, 3, 3),
                np.array(poss, dtype=float).reshape(-1, 3),
                np.array(dims, dtype=float).reshape(-1, 3),
            ),
            obs_names=tuple(names),
            tolerance=tolerance,
            coarse_pairs=tuple(coarse),
        )

    @property
    def ns(self) -> int:
        """Number of robot spheres."""
        return int(self.arrays.sph_radius.shape[0])

    @property
    def nb(self) -> int:
        """Number of collision bodies."""
        return int(self.body_joint.shape[0])

    def scratch(self) -> FloatArray:
        """A work array for :func:`penetration`, ``(ns, 6)``."""
        return np.empty((self.ns, 6))

    def body_kinematics(self, q: Any) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Body world poses and Jacobians at chain configuration ``q`` (through Pinocchio;
        the reference the compiled FK is tested against).

        Returns:
            ``body_rot (nb, 3, 3)``, ``body_pos (nb, 3)`` [m], ``body_jac (nb, 6, nq)``
            (LOCAL_WORLD_ALIGNED at the body origin, rows ``[v; ω]``).
        """
        import pinocchio as pin

        robot = self.collision.robot
        model = robot.model
        data = model.createData()
        pin.computeJointJacobians(model, data, robot.to_pinocchio(robot.check_q(q)))
        nb, nv = self.nb, model.nv
        rot = np.empty((nb, 3, 3))
        pos = np.empty((nb, 3))
        jac = np.zeros((nb, 6, nv))
        for b in range(nb):
            j = int(self.body_joint[b])
            o = data.oMi[j]
            rot[b] = np.array(o.rotation) @ self.body_frame_rot[b]
            pos[b] = np.array(o.rotation) @ self.body_frame_pos[b] + np.array(o.translation)
            if j == 0:
                continue
            jj = np.array(
                pin.getJointJacobian(model, data, j, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
            ).reshape(6, nv)
            r = pos[b] - np.array(o.translation)
            skew = np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
            jac[b, :3] = jj[:3] - skew @ jj[3:]
            jac[b, 3:] = jj[3:]
        return rot, pos, jac

    def evaluate(
        self, q: Any, margin: float = 0.0, max_rows: int = 256
    ) -> tuple[FloatArray, FloatArray, IntArray]:
        """Penetration rows at ``q`` through Pinocchio's kinematics (reference / tests).

        Returns:
            Residuals ``(rows,)`` [m], Jacobian ``(rows, nq)``, pairs ``(rows, 2)``.
        """
        rot, pos, jac = self.body_kinematics(q)
        nq = jac.shape[2]
        out_res = np.zeros(max_rows)
        out_jac = np.zeros((max_rows, nq))
        out_pair = np.zeros((max_rows, 2), dtype=np.int64)
        n, _, _ = penetration(
            rot, pos, jac, self.arrays, float(margin), self.scratch(), True, out_res, out_jac,
            out_pair,
        )  # fmt: skip
        return out_res[:n].copy(), out_jac[:n].copy(), out_pair[:n].copy()

    def cost(self, q: Any, margin: float = 0.0) -> tuple[float, float]:
        """:func:`penetration_cost` at ``q`` (Pinocchio kinematics)."""
        rot, pos, _ = self.body_kinematics(q)
        return penetration_cost(rot, pos, self.arrays, margin, self.scratch())

    def world_spheres(self, q: Any) -> tuple[FloatArray, FloatArray]:
        """World sphere centres ``(ns, 3)`` [m] and radii ``(ns,)`` at ``q`` (for drawing)."""
        rot, pos, _ = self.body_kinematics(q)
        s = self.scratch()
        sphere_centres(rot, pos, self.arrays.sph_body, self.arrays.sph_local, s)
        return s[:, :3].copy(), self.arrays.sph_radius.copy()
