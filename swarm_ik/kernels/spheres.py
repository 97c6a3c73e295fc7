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
:func:`swarm_ik.collision.cache_dir`.

**Obstacles** keep their exact shape in compiled code: signed distance functions of a sphere,
box, capsule and cylinder (exact Euclidean distances, so a robot sphere of radius ``r`` is
clear of an obstacle iff the SDF at its centre is ``>= r``).  A mesh obstacle is covered by
spheres as above.

**Residual** (:func:`penetration`): one row ``max(0, margin + r_i + r_j − |c_i − c_j|)`` per
active sphere pair of an enabled body pair and ``max(0, margin + r_i − sdf_k(c_i))`` per
active sphere–obstacle pair (spheres of the bodies that ``q`` moves; a body fixed to the
world is left to the exact check), with its Jacobian.  Body pairs (and body–obstacle pairs) are
culled first with each body's bounding sphere.  The centre ``c = R c_local + p`` of a sphere
moves with the body Jacobian ``J`` (LOCAL_WORLD_ALIGNED at the body origin, rows ``[v; ω]``)
as ``J_c = J_v − [R c_local]× J_ω``.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numba
import numpy as np

from swarm_ik._types import FloatArray, IntArray
from swarm_ik.kernels import leaf

SPHERE = 0
BOX = 1
CAPSULE = 2
CYLINDER = 3
OBSTACLE_KINDS = ("sphere", "box", "capsule", "cylinder")

TOLERANCE = 0.02
"""Default fitting tolerance [m]: how far a sphere may stick out of its body (about)."""

COARSE_SAMPLES = 500
"""Random configurations of the coarse-pair rule of :meth:`SphereModel.from_collision`."""

_CYL_SECTIONS = 64
_FIT_VERSION = 1


# ============================================================================ fitting
def _winding(points: FloatArray, tris: FloatArray) -> FloatArray:
    """Generalised winding number of each point (m, 3) w.r.t. triangles (nt, 3, 3)."""
    out = np.zeros(len(points))
    chunk = max(1, 2_000_000 // max(1, len(tris)))
    for s in range(0, len(points), chunk):
        x = points[s : s + chunk, None, None, :]
        d = tris[None, :, :, :] - x  # (m, nt, 3, 3)
        a, b, c = d[:, :, 0], d[:, :, 1], d[:, :, 2]
        la, lb, lc = (np.linalg.norm(v, axis=-1) for v in (a, b, c))
        num = np.einsum("mti,mti->mt", a, np.cross(b, c))
        den = (
            la * lb * lc
            + np.einsum("mti,mti->mt", a, b) * lc
            + np.einsum("mti,mti->mt", a, c) * lb
            + np.einsum("mti,mti->mt", b, c) * la
        )
        out[s : s + chunk] = np.sum(2.0 * np.arctan2(num, den), axis=1) / (4.0 * np.pi)
    return out


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
    import trimesh
    from scipy.spatial import cKDTree

    V = np.asarray(vertices, dtype=float)
    F = np.asarray(faces, dtype=np.int64)
    V2, F2 = trimesh.remesh.subdivide_to_size(V, F, max_edge=0.5 * tolerance, max_iter=30)
    V2 = np.asarray(V2, dtype=float)
    F2 = np.asarray(F2, dtype=np.int64)
    dense = cKDTree(np.vstack([V2, V2[F2].mean(axis=1)]))  # for distances to the surface
    pts = _voxel_subsample(np.vstack([V, V2]), 0.5 * tolerance)  # points the greedy covers
    lo, hi = V.min(axis=0), V.max(axis=0)
    ext = np.maximum(hi - lo, 1e-9)
    pitch = max(0.5 * tolerance, float(np.prod(ext) / 2000.0) ** (1.0 / 3.0))
    axes = [np.arange(lo[i] + 0.5 * pitch, hi[i], pitch) for i in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    if len(grid):
        grid = grid[np.abs(_winding(grid, V[F])) > 0.5]
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
    tri = V2[F2]  # (nt, 3, 3)
    owner = np.empty(len(tri), dtype=np.int64)
    need_own = np.empty(len(tri))
    step = max(1, 1_000_000 // (9 * len(centres)))
    for s0 in range(0, len(tri), step):
        t = tri[s0 : s0 + step]
        d = np.sqrt(((t[:, None, :, :] - centres[None, :, None, :]) ** 2).sum(axis=-1)).max(axis=2)
        o = np.argmin(d - nominal[None, :], axis=1)
        owner[s0 : s0 + step] = o
        need_own[s0 : s0 + step] = d[np.arange(len(t)), o]
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
    import trimesh

    from swarm_ik.errors import RobotModelError

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
    from swarm_ik.collision import cache_dir

    h = hashlib.sha256(json.dumps([_FIT_VERSION, round(tolerance, 12)]).encode())
    for g in geometries:
        h.update(_geometry_key(g))
    path = cache_dir() / f"spheres-{h.hexdigest()[:20]}.npz"
    if use_cache and path.is_file():
        try:
            with np.load(path) as z:
                body, centres, radii = z["body"], z["centres"], z["radii"]
            return [(centres[body == k], radii[body == k]) for k in range(len(geometries))]
        except (OSError, KeyError, ValueError):
            pass
    fits = [fit_spheres(g, tolerance) for g in geometries]
    if use_cache:
        tmp = path.with_name(path.stem + f".tmp{id(fits)}.npz")
        np.savez(
            tmp,
            body=np.concatenate([np.full(len(r), k) for k, (_, r) in enumerate(fits)]),
            centres=np.vstack([c for c, _ in fits]),
            radii=np.concatenate([r for _, r in fits]),
        )
        tmp.replace(path)
    return fits


# ======================================================================= compiled code
class SphereArrays(NamedTuple):
    """The sphere model as the penetration kernels read it (:func:`penetration`,
    :func:`penetration_cost`; held by :class:`SphereModel` and by the LM kernel's
    :class:`swarm_ik.kernels.lm.CollisionArrays`).

    Attributes:
        sph_body: Body of each sphere, ``(ns,)``, spheres grouped by body.
        sph_local: Sphere centres in their body frame [m], ``(ns, 3)``.
        sph_radius: Sphere radii [m], ``(ns,)``.
        body_start: Spheres of body ``b`` are ``body_start[b]:body_start[b + 1]``, ``(nb + 1,)``.
        bound_local: Centre of a sphere bounding each body's spheres, body frame, ``(nb, 3)``.
        bound_radius: Its radius [m], ``(nb,)``.
        self_pairs: Enabled self-collision body pairs, ``(npair, 2)``.
        obs_bodies: Bodies checked against the obstacles, ``(nob,)`` (the moving ones: a body
            fixed to the world cannot be moved by ``q`` and is left to the exact check).
        obs_kind: Obstacle kinds (``SPHERE``, ``BOX``, ``CAPSULE``, ``CYLINDER``), ``(no,)``.
        obs_rot: Obstacle world rotations, ``(no, 3, 3)``.
        obs_pos: Obstacle world positions [m], ``(no, 3)``.
        obs_dims: Sphere ``[r, 0, 0]``, box half extents, capsule and cylinder
            ``[r, half length, 0]`` [m], ``(no, 3)``.
    """

    sph_body: IntArray
    sph_local: FloatArray
    sph_radius: FloatArray
    body_start: IntArray
    bound_local: FloatArray
    bound_radius: FloatArray
    self_pairs: IntArray
    obs_bodies: IntArray
    obs_kind: IntArray
    obs_rot: FloatArray
    obs_pos: FloatArray
    obs_dims: FloatArray


@leaf
def _sdf(  # type: ignore[no-untyped-def]
    kind: int, rot: FloatArray, pos: FloatArray, dims: FloatArray, px: float, py: float, pz: float
):
    """Signed distance [m] of the world point ``(px, py, pz)`` to an obstacle and its world
    gradient."""
    dx = px - pos[0]
    dy = py - pos[1]
    dz = pz - pos[2]
    x = rot[0, 0] * dx + rot[1, 0] * dy + rot[2, 0] * dz
    y = rot[0, 1] * dx + rot[1, 1] * dy + rot[2, 1] * dz
    z = rot[0, 2] * dx + rot[1, 2] * dy + rot[2, 2] * dz
    gx, gy, gz = 1.0, 0.0, 0.0
    d = 0.0
    if kind == SPHERE:
        n = math.sqrt(x * x + y * y + z * z)
        d = n - dims[0]
        if n > 1e-12:
            gx, gy, gz = x / n, y / n, z / n
    elif kind == BOX:
        qx = abs(x) - dims[0]
        qy = abs(y) - dims[1]
        qz = abs(z) - dims[2]
        sx = 1.0 if x >= 0.0 else -1.0
        sy = 1.0 if y >= 0.0 else -1.0
        sz = 1.0 if z >= 0.0 else -1.0
        if qx > 0.0 or qy > 0.0 or qz > 0.0:
            ox, oy, oz = max(qx, 0.0), max(qy, 0.0), max(qz, 0.0)
            d = math.sqrt(ox * ox + oy * oy + oz * oz)
            gx, gy, gz = sx * ox / d, sy * oy / d, sz * oz / d
        elif qx >= qy and qx >= qz:
            d, gx, gy, gz = qx, sx, 0.0, 0.0
        elif qy >= qz:
            d, gx, gy, gz = qy, 0.0, sy, 0.0
        else:
            d, gx, gy, gz = qz, 0.0, 0.0, sz
    elif kind == CAPSULE:
        zc = min(max(z, -dims[1]), dims[1])
        vz = z - zc
        n = math.sqrt(x * x + y * y + vz * vz)
        d = n - dims[0]
        if n > 1e-12:
            gx, gy, gz = x / n, y / n, vz / n
    else:  # CYLINDER
        rr = math.sqrt(x * x + y * y)
        ux, uy = (x / rr, y / rr) if rr > 1e-12 else (1.0, 0.0)
        sz = 1.0 if z >= 0.0 else -1.0
        a = rr - dims[0]
        b = abs(z) - dims[1]
        if a > 0.0 or b > 0.0:
            oa, ob = max(a, 0.0), max(b, 0.0)
            d = math.sqrt(oa * oa + ob * ob)
            gx, gy, gz = ux * oa / d, uy * oa / d, sz * ob / d
        elif a >= b:
            d, gx, gy, gz = a, ux, uy, 0.0
        else:
            d, gx, gy, gz = b, 0.0, 0.0, sz
    wx = rot[0, 0] * gx + rot[0, 1] * gy + rot[0, 2] * gz
    wy = rot[1, 0] * gx + rot[1, 1] * gy + rot[1, 2] * gz
    wz = rot[2, 0] * gx + rot[2, 1] * gy + rot[2, 2] * gz
    return d, wx, wy, wz


@leaf
def _slot(res: float, out_res: FloatArray, rows: int) -> int:
    """Row to write a residual ``res`` into: the next free one, else the smallest one if
    ``res`` is larger, else -1."""
    if rows < out_res.shape[0]:
        return rows
    m = 0
    for k in range(1, out_res.shape[0]):
        if out_res[k] < out_res[m]:
            m = k
    return m if out_res[m] < res else -1


@leaf
def _account(
    res: float, want_rows: bool, out_res: FloatArray, rows: int, total: float, worst: float
) -> tuple[int, int, float, float]:  # pragma: no cover - compiled
    """Count an active pair's residual ``res`` [m] in the sums and, with ``want_rows``, find
    its row (:func:`_slot`); returns ``(row or -1, rows used, total, worst)``."""
    total += res * res
    worst = max(worst, res)
    s = _slot(res, out_res, rows) if want_rows else -1
    if s == rows:
        rows += 1
    return s, rows, total, worst


@leaf
def _add_point_row(
    sign: float,
    ux: float,
    uy: float,
    uz: float,
    w: FloatArray,
    jac: FloatArray,
    out: FloatArray,
) -> None:
    """out += sign · uᵀ (J_v − [w]× J_ω) = sign · (uᵀ J_v + (w × u)ᵀ J_ω)."""
    cx = w[1] * uz - w[2] * uy
    cy = w[2] * ux - w[0] * uz
    cz = w[0] * uy - w[1] * ux
    for k in range(jac.shape[1]):
        out[k] += sign * (
            ux * jac[0, k]
            + uy * jac[1, k]
            + uz * jac[2, k]
            + cx * jac[3, k]
            + cy * jac[4, k]
            + cz * jac[5, k]
        )


@leaf
def sphere_centres(
    body_rot: FloatArray,
    body_pos: FloatArray,
    sph_body: IntArray,
    sph_local: FloatArray,
    scratch: FloatArray,
) -> None:
    """World sphere centres into ``scratch[:, :3]`` and their offsets ``R c_local`` from the
    body origin into ``scratch[:, 3:]`` (``scratch`` shape ``(ns, 6)``)."""
    for i in range(sph_body.shape[0]):
        b = sph_body[i]
        for r in range(3):
            w = (
                body_rot[b, r, 0] * sph_local[i, 0]
                + body_rot[b, r, 1] * sph_local[i, 1]
                + body_rot[b, r, 2] * sph_local[i, 2]
            )
            scratch[i, 3 + r] = w
            scratch[i, r] = w + body_pos[b, r]


@leaf
def _bound_centre(
    body_rot: FloatArray, body_pos: FloatArray, bound_local: FloatArray, b: int
) -> tuple[float, float, float]:  # pragma: no cover - compiled
    """World centre of body ``b``'s bounding sphere."""
    x = (
        body_rot[b, 0, 0] * bound_local[b, 0]
        + body_rot[b, 0, 1] * bound_local[b, 1]
        + body_rot[b, 0, 2] * bound_local[b, 2]
        + body_pos[b, 0]
    )
    y = (
        body_rot[b, 1, 0] * bound_local[b, 0]
        + body_rot[b, 1, 1] * bound_local[b, 1]
        + body_rot[b, 1, 2] * bound_local[b, 2]
        + body_pos[b, 1]
    )
    z = (
        body_rot[b, 2, 0] * bound_local[b, 0]
        + body_rot[b, 2, 1] * bound_local[b, 1]
        + body_rot[b, 2, 2] * bound_local[b, 2]
        + body_pos[b, 2]
    )
    return x, y, z


@leaf
def penetration(
    body_rot: FloatArray,
    body_pos: FloatArray,
    body_jac: FloatArray,
    model: SphereArrays,
    margin: float,
    scratch: FloatArray,
    want_rows: bool,
    out_res: FloatArray,
    out_jac: FloatArray,
    out_pair: IntArray,
) -> tuple[int, float, float]:  # pragma: no cover - compiled
    """Penetration residual rows and their Jacobian (see the module docstring), and the sums
    over every active pair (:func:`penetration_cost` is this without rows).

    Args:
        body_rot: World rotation of each collision body, ``(nb, 3, 3)``.
        body_pos: World position of each body origin [m], ``(nb, 3)``.
        body_jac: Jacobian of each body frame, LOCAL_WORLD_ALIGNED at the body origin, rows
            ``[v; ω]``, ``(nb, 6, nq)`` (not read without ``want_rows``).
        model: The spheres, bounding spheres, self pairs and obstacles.
        margin: Wanted clearance [m].
        scratch: Work array, ``(ns, 6)``.
        want_rows: Write the rows (else only the sums).
        out_res: Residual rows [m] (written), ``(max_rows,)``.
        out_jac: Their Jacobian (written), ``(max_rows, nq)``.
        out_pair: Per row ``(sphere i, sphere j)`` for a self pair or ``(sphere i, -1 - k)`` for
            obstacle ``k`` (written), ``(max_rows, 2)``.

    Returns:
        ``(rows, total, worst)``: the rows written (when more pairs are active than
        ``max_rows`` the largest residuals are kept; rows are sorted by decreasing residual),
        the sum of squared residuals [m²] over every active pair and the largest [m].
    """
    (sph_body, sph_local, sph_radius, body_start, bound_local, bound_radius, self_pairs,
     obs_bodies, obs_kind, obs_rot, obs_pos, obs_dims) = model  # fmt: skip
    nq = out_jac.shape[1]
    sphere_centres(body_rot, body_pos, sph_body, sph_local, scratch)
    rows = 0
    total = 0.0
    worst = 0.0
    for pi in range(self_pairs.shape[0]):
        a = self_pairs[pi, 0]
        b = self_pairs[pi, 1]
        ax, ay, az = _bound_centre(body_rot, body_pos, bound_local, a)
        bx, by, bz = _bound_centre(body_rot, body_pos, bound_local, b)
        dd = math.sqrt((ax - bx) ** 2 + (ay - by) ** 2 + (az - bz) ** 2)
        if dd >= margin + bound_radius[a] + bound_radius[b]:
            continue
        for i in range(body_start[a], body_start[a + 1]):
            di = math.sqrt(
                (scratch[i, 0] - bx) ** 2 + (scratch[i, 1] - by) ** 2 + (scratch[i, 2] - bz) ** 2
            )
            if di >= margin + sph_radius[i] + bound_radius[b]:
                continue
            for j in range(body_start[b], body_start[b + 1]):
                ux = scratch[i, 0] - scratch[j, 0]
                uy = scratch[i, 1] - scratch[j, 1]
                uz = scratch[i, 2] - scratch[j, 2]
                dist = math.sqrt(ux * ux + uy * uy + uz * uz)
                res = margin + sph_radius[i] + sph_radius[j] - dist
                if res <= 0.0:
                    continue
                s, rows, total, worst = _account(res, want_rows, out_res, rows, total, worst)
                if s < 0:
                    continue
                if dist > 1e-12:
                    ux, uy, uz = ux / dist, uy / dist, uz / dist
                else:
                    ux, uy, uz = 1.0, 0.0, 0.0
                out_res[s] = res
                out_pair[s, 0] = i
                out_pair[s, 1] = j
                for k in range(nq):
                    out_jac[s, k] = 0.0
                _add_point_row(-1.0, ux, uy, uz, scratch[i, 3:], body_jac[a], out_jac[s])
                _add_point_row(1.0, ux, uy, uz, scratch[j, 3:], body_jac[b], out_jac[s])
    for ob in range(obs_kind.shape[0]):
        for a in obs_bodies:
            ax, ay, az = _bound_centre(body_rot, body_pos, bound_local, a)
            d0, _, _, _ = _sdf(obs_kind[ob], obs_rot[ob], obs_pos[ob], obs_dims[ob], ax, ay, az)
            if d0 >= margin + bound_radius[a]:
                continue
            for i in range(body_start[a], body_start[a + 1]):
                d, gx, gy, gz = _sdf(
                    obs_kind[ob], obs_rot[ob], obs_pos[ob], obs_dims[ob],
                    scratch[i, 0], scratch[i, 1], scratch[i, 2],
                )  # fmt: skip
                res = margin + sph_radius[i] - d
                if res <= 0.0:
                    continue
                s, rows, total, worst = _account(res, want_rows, out_res, rows, total, worst)
                if s < 0:
                    continue
                out_res[s] = res
                out_pair[s, 0] = i
                out_pair[s, 1] = -1 - ob
                for k in range(nq):
                    out_jac[s, k] = 0.0
                _add_point_row(-1.0, gx, gy, gz, scratch[i, 3:], body_jac[a], out_jac[s])
    # insertion sort by decreasing residual (rows is small)
    for m in range(1, rows):
        k = m
        while k > 0 and out_res[k - 1] < out_res[k]:
            out_res[k - 1], out_res[k] = out_res[k], out_res[k - 1]
            for c in range(2):
                out_pair[k - 1, c], out_pair[k, c] = out_pair[k, c], out_pair[k - 1, c]
            for c in range(nq):
                out_jac[k - 1, c], out_jac[k, c] = out_jac[k, c], out_jac[k - 1, c]
            k -= 1
    return rows, total, worst


@numba.njit(cache=True)
def penetration_cost(
    body_rot: FloatArray,
    body_pos: FloatArray,
    model: SphereArrays,
    margin: float,
    scratch: FloatArray,
) -> tuple[float, float]:  # pragma: no cover - compiled
    """Sum of squared residuals [m²] over every active pair and the largest residual [m]
    (0 when clear), without Jacobian: the swarm's fitness term.  Arguments as
    :func:`penetration`."""
    _, total, worst = penetration(
        body_rot, body_pos, np.empty((0, 6, 0)), model, margin, scratch, False, np.empty(0),
        np.empty((0, 0)), np.empty((0, 2), dtype=np.int64),
    )  # fmt: skip
    return total, worst


@numba.njit(cache=True)
def obstacle_sdf(
    kind: int, rot: FloatArray, pos: FloatArray, dims: FloatArray, p: FloatArray
) -> tuple[float, float, float, float]:
    """Signed distance [m] of world point ``p`` (3,) to one obstacle, and its world gradient
    (exposed for tests and for the lead's kernels)."""
    return _sdf(kind, rot, pos, dims, p[0], p[1], p[2])


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
    scratch = np.empty((len(spheres[2]), 6))
    no_bodies = np.zeros(0, np.int64)
    no_obs = (np.zeros(0, np.int64), np.zeros((0, 3, 3)), np.zeros((0, 3)), np.zeros((0, 3)))
    rng = np.random.default_rng(0)
    for q in robot.random_q(rng, samples):
        q_pin = robot.to_pinocchio(q)
        pin.computeCollisions(robot.model, data, gm, gd, q_pin, False)
        rot = np.array([np.array(m.rotation) for m in gd.oMg])
        pos = np.array([np.array(m.translation) for m in gd.oMg])
        for k in range(npair):
            touch[k] += gd.collisionResults[k].isCollision()
            pair_k = SphereArrays(*spheres, pairs[k : k + 1], no_bodies, *no_obs)
            c, _ = penetration_cost(rot, pos, pair_k, 0.0, scratch)
            overlap[k] += c > 0.0
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
        use_cache: bool = True,
        coarse_samples: int = COARSE_SAMPLES,
    ) -> SphereModel:
        """Fit spheres to every body of ``robot_collision`` and convert ``scene``.

        Args:
            robot_collision: A :class:`~swarm_ik.collision.RobotCollision`.
            scene: A :class:`~swarm_ik.scene.Scene` (or shapes, a JSON path, ``None``).
            tolerance: Fitting tolerance [m].
            self_collision: Keep the enabled self-collision body pairs (else none).
            use_cache: Read and write fitted spheres in the cache folder.
            coarse_samples: Random configurations of the coarse-pair rule (0: keep every
                pair): a self pair whose spheres overlap in at least 95 % of them while the
                exact geometry touches in none is left to the exact check alone (listed in
                ``coarse_pairs``); e.g. UR5's ``ee_link`` box, always a few millimetres from
                ``wrist_2_link``.
        """
        import coal

        from swarm_ik.errors import InvalidArgumentError
        from swarm_ik.scene import Box, Capsule, Cylinder, Mesh, Sphere, as_scene, coal_geometry

        tolerance = float(tolerance)
        if not (np.isfinite(tolerance) and tolerance > 0.0):
            raise InvalidArgumentError(f"tolerance must be a positive number [m], got {tolerance}")
        rc = robot_collision
        objs = list(rc.geom_model.geometryObjects)
        fits = fit_bodies([g.geometry for g in objs], tolerance, use_cache)
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
        if len(pairs) and coarse_samples > 0:
            pairs, coarse = _drop_coarse_pairs(rc, pairs, spheres, coarse_samples)
        kinds, rots, poss, dims, names = [], [], [], [], []
        sc = as_scene(scene)
        for name, o in zip(sc.names, sc.obstacles, strict=True):
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
                geo = coal_geometry(o)
                assert isinstance(geo, coal.BVHModelBase)
                ((c, r),) = fit_bodies([geo], tolerance, use_cache)
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
        return penetration_cost(rot, pos, self.arrays, float(margin), self.scratch())  # type: ignore[no-any-return]

    def world_spheres(self, q: Any) -> tuple[FloatArray, FloatArray]:
        """World sphere centres ``(ns, 3)`` [m] and radii ``(ns,)`` at ``q`` (for drawing)."""
        rot, pos, _ = self.body_kinematics(q)
        s = self.scratch()
        sphere_centres(rot, pos, self.arrays.sph_body, self.arrays.sph_local, s)
        return s[:, :3].copy(), self.arrays.sph_radius.copy()
