"""Compiled residual rows shared by the goal kernels of :mod:`swarm_ik.goals`: a frame origin
at a point, a frame at an orientation, a frame axis along a direction.

Each writes unweighted rows ``r`` with ``r(q + δ) ≈ r − J δ`` and their step Jacobian ``J``
from the FK buffers of :func:`swarm_ik.kernels.fk.fk_one` (``J_v``, ``J_ω``: the
LOCAL_WORLD_ALIGNED frame Jacobian), and returns the error the tolerances judge:

==============  ====  ==============================  ========================================
rows            m     residual ``r``                  step Jacobian ``J``
==============  ====  ==============================  ========================================
position        3     ``p* − p``                      ``J_v``
rotation        3     ``log(R* Rᵀ)``                  ``Jr⁻¹(φ) J_ω`` ([LIE] eq. 144)
direction       3     ``d − u``, ``u = R a``          ``J_ω × u`` (+ ``(I − ddᵀ) J_v / L`` when
                                                      ``d`` points at a point at distance ``L``)
==============  ====  ==============================  ========================================
"""

from __future__ import annotations

import math

import numba
import numpy as np

from swarm_ik._types import FloatArray
from swarm_ik.kernels.lie import jr_inv_nb, log3_nb


@numba.njit(cache=True, inline="always")
def position_rows(
    point: FloatArray,
    f: int,
    f_pos: FloatArray,
    f_jac: FloatArray,
    want_jac: bool,
    res: FloatArray,
    jac: FloatArray,
) -> float:  # pragma: no cover - compiled
    """Rows ``p* − p`` of frame ``f`` (``point`` = ``p*`` (3,)); returns ``‖p* − p‖`` [m]."""
    dx = point[0] - f_pos[f, 0]
    dy = point[1] - f_pos[f, 1]
    dz = point[2] - f_pos[f, 2]
    res[0] = dx
    res[1] = dy
    res[2] = dz
    if want_jac:
        for a in range(3):
            for j in range(jac.shape[1]):
                jac[a, j] = f_jac[f, a, j]
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@numba.njit(cache=True, inline="always")
def rotation_rows(
    rot: FloatArray,
    f: int,
    f_rot: FloatArray,
    f_jac: FloatArray,
    want_jac: bool,
    res: FloatArray,
    jac: FloatArray,
    work: FloatArray,
) -> float:  # pragma: no cover - compiled
    """Rows ``log(R* Rᵀ)`` of frame ``f`` (``rot``: ``R*`` row-major (9,)); returns the
    angle of ``R*ᵀR`` [rad].  ``work``: scratch of at least 12 entries."""
    m3 = work[0:9].reshape((3, 3))
    v3 = work[9:12]
    for a in range(3):
        for b in range(3):
            m3[a, b] = (
                rot[3 * a] * f_rot[f, b, 0]
                + rot[3 * a + 1] * f_rot[f, b, 1]
                + rot[3 * a + 2] * f_rot[f, b, 2]
            )
    theta = log3_nb(m3, v3)
    for a in range(3):
        res[a] = v3[a]
    if want_jac:
        jr_inv_nb(v3, theta, m3)
        for a in range(3):
            ma0, ma1, ma2 = m3[a, 0], m3[a, 1], m3[a, 2]
            for j in range(jac.shape[1]):
                jac[a, j] = ma0 * f_jac[f, 3, j] + ma1 * f_jac[f, 4, j] + ma2 * f_jac[f, 5, j]
    return theta


@numba.njit(cache=True, inline="always")
def direction_rows(
    axis: FloatArray,
    target: FloatArray,
    at_point: bool,
    f: int,
    f_pos: FloatArray,
    f_rot: FloatArray,
    f_jac: FloatArray,
    want_jac: bool,
    res: FloatArray,
    jac: FloatArray,
) -> float:  # pragma: no cover - compiled
    """Rows ``d − u`` of frame ``f``: ``u = R a`` (``axis`` = ``a`` (3,), unit) and ``d`` the
    unit ``target`` direction, or, with ``at_point``, the unit vector from the frame origin to
    the point ``target``.  Returns the angle between ``u`` and ``d`` [rad], infinite where ``d`` is
    undefined (the point at the frame origin), so never within tolerance."""
    ux = f_rot[f, 0, 0] * axis[0] + f_rot[f, 0, 1] * axis[1] + f_rot[f, 0, 2] * axis[2]
    uy = f_rot[f, 1, 0] * axis[0] + f_rot[f, 1, 1] * axis[1] + f_rot[f, 1, 2] * axis[2]
    uz = f_rot[f, 2, 0] * axis[0] + f_rot[f, 2, 1] * axis[1] + f_rot[f, 2, 2] * axis[2]
    dist = 1.0
    undefined = False
    if at_point:
        ex = target[0] - f_pos[f, 0]
        ey = target[1] - f_pos[f, 1]
        ez = target[2] - f_pos[f, 2]
        raw = math.sqrt(ex * ex + ey * ey + ez * ez)
        undefined = raw < 1e-9
        dist = max(raw, 1e-9)
        dx, dy, dz = ex / dist, ey / dist, ez / dist
    else:
        dx, dy, dz = target[0], target[1], target[2]
    res[0] = dx - ux
    res[1] = dy - uy
    res[2] = dz - uz
    if want_jac:
        for j in range(jac.shape[1]):
            wx, wy, wz = f_jac[f, 3, j], f_jac[f, 4, j], f_jac[f, 5, j]
            jx = wy * uz - wz * uy
            jy = wz * ux - wx * uz
            jz = wx * uy - wy * ux
            if at_point:
                vx, vy, vz = f_jac[f, 0, j], f_jac[f, 1, j], f_jac[f, 2, j]
                dv = dx * vx + dy * vy + dz * vz
                jx += (vx - dx * dv) / dist
                jy += (vy - dy * dv) / dist
                jz += (vz - dz * dv) / dist
            jac[0, j] = jx
            jac[1, j] = jy
            jac[2, j] = jz
    if undefined:
        return np.inf
    cx = uy * dz - uz * dy
    cy = uz * dx - ux * dz
    cz = ux * dy - uy * dx
    return math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), ux * dx + uy * dy + uz * dz)
