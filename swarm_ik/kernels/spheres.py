"""Compiled sphere distances of collision goals: signed distances of obstacle primitives
(sphere, box, capsule, cylinder) and the penetration residual of a sphere model with its
Jacobian.  The spheres themselves are fitted by :mod:`swarm_ik.spheres`.

**Obstacles** keep their exact shape: signed distance functions of a sphere, box, capsule and
cylinder (exact Euclidean distances, so a robot sphere of radius ``r`` is clear of an obstacle
iff the SDF at its centre is ``>= r``).

**Residual** (:func:`penetration`): one row ``max(0, margin + r_i + r_j − |c_i − c_j|)`` per
active sphere pair of an enabled body pair and ``max(0, margin + r_i − sdf_k(c_i))`` per
active sphere–obstacle pair, with its Jacobian.  Body pairs (and body–obstacle pairs) are
culled first with each body's bounding sphere.  The centre ``c = R c_local + p`` of a sphere
moves with the body Jacobian ``J`` (LOCAL_WORLD_ALIGNED at the body origin, rows ``[v; ω]``)
as ``J_c = J_v − [R c_local]× J_ω``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba

from swarm_ik._types import FloatArray, IntArray

SPHERE = 0
BOX = 1
CAPSULE = 2
CYLINDER = 3
OBSTACLE_KINDS = ("sphere", "box", "capsule", "cylinder")


# ======================================================================= compiled code
class SphereArrays(NamedTuple):
    """The sphere model as the penetration kernel reads it (:func:`penetration`; held by
    :class:`SphereModel` and by the LM kernel's :class:`swarm_ik.kernels.lm.CollisionArrays`).

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


@numba.njit(cache=True)
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


@numba.njit(cache=True)
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


@numba.njit(cache=True)
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


@numba.njit(cache=True)
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


@numba.njit(cache=True)
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


@numba.njit(cache=True)
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


@numba.njit(cache=True)
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
    over every active pair (without ``want_rows``: the swarm's fitness term).

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
def obstacle_sdf(
    kind: int, rot: FloatArray, pos: FloatArray, dims: FloatArray, p: FloatArray
) -> tuple[float, float, float, float]:
    """Signed distance [m] of world point ``p`` (3,) to one obstacle, and its world gradient
    (exposed for tests and for the lead's kernels)."""
    return _sdf(kind, rot, pos, dims, p[0], p[1], p[2])
