"""Compiled residual rows shared by the goal kernels of :mod:`swarm_ik.goals`: a frame origin
at a point, a frame at an orientation, a frame axis along a direction, and the bounded forms (a
frame within a box and rotation bounds of its target, an origin within a ball).

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
box position    3     ``dz(e, t)``,                   ``R*ᵀ J_v`` (every row)
                      ``e = R*ᵀ(p − p*)``
box rotation    3     ``dz(φ, t)``,                   ``Jr⁻¹(φ) Rᵀ J_ω`` (zero on a free axis,
                      ``φ = log(R*ᵀ R)``              ``t = π``)
ball            3     ``−max(0, ‖d‖ − ρ)·u``,         ``[(1 − ρ/‖d‖)(I − uuᵀ) + uuᵀ] J_v``
                      ``d = p − p*``, ``u = d/‖d‖``   outside, ``uuᵀ J_v`` inside
==============  ====  ==============================  ========================================

``dz(e, t) = −sign(e)·max(0, |e| − t)`` (per row) is a dead zone: zero within the bounds,
continuous at them; the errors of the bounded rows are the norms of the parts beyond the
bounds.  Their step Jacobian is kept inside the bounds (the derivative of the offset, not of
the zero residual, as TRAC-IK's bounds keep the Jacobian): a row at rest then holds its offset
to first order, where a zero row would let the goal's other rows push it out again, and the
Jacobian is continuous at the bounds.  Measured on Panda, UR5 and xArm7 (100–200 random
targets, one random start each, the LM alone): with zero rows inside, a box of 1 cm / 0.05 rad
converged from 2.4–3.4× fewer starts than the exact pose (1.4× for 5 cm / 0.3 rad), and the
one-row ball ``−max(0, ‖d‖ − ρ)`` from 2–3× fewer than the exact point; in the form above both
converge from as many starts as the exact goals, or more.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from swarm_ik._types import FloatArray
from swarm_ik.kernels.lie import jr_inv_entries, jr_inv_nb, log3_entries, log3_nb


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
    angle of ``R*ᵀR`` [rad].  ``work`` is not used (the product is kept in scalars: views of
    a scratch array cost the LM loop a reference count each, 4–6 % of a batch)."""
    r = rot
    m00 = r[0] * f_rot[f, 0, 0] + r[1] * f_rot[f, 0, 1] + r[2] * f_rot[f, 0, 2]
    m01 = r[0] * f_rot[f, 1, 0] + r[1] * f_rot[f, 1, 1] + r[2] * f_rot[f, 1, 2]
    m02 = r[0] * f_rot[f, 2, 0] + r[1] * f_rot[f, 2, 1] + r[2] * f_rot[f, 2, 2]
    m10 = r[3] * f_rot[f, 0, 0] + r[4] * f_rot[f, 0, 1] + r[5] * f_rot[f, 0, 2]
    m11 = r[3] * f_rot[f, 1, 0] + r[4] * f_rot[f, 1, 1] + r[5] * f_rot[f, 1, 2]
    m12 = r[3] * f_rot[f, 2, 0] + r[4] * f_rot[f, 2, 1] + r[5] * f_rot[f, 2, 2]
    m20 = r[6] * f_rot[f, 0, 0] + r[7] * f_rot[f, 0, 1] + r[8] * f_rot[f, 0, 2]
    m21 = r[6] * f_rot[f, 1, 0] + r[7] * f_rot[f, 1, 1] + r[8] * f_rot[f, 1, 2]
    m22 = r[6] * f_rot[f, 2, 0] + r[7] * f_rot[f, 2, 1] + r[8] * f_rot[f, 2, 2]
    theta, px, py, pz = log3_entries(m00, m01, m02, m10, m11, m12, m20, m21, m22)
    res[0] = px
    res[1] = py
    res[2] = pz
    if want_jac:
        a00, a01, a02, a10, a11, a12, a20, a21, a22 = jr_inv_entries(px, py, pz, theta)
        for j in range(jac.shape[1]):
            w0, w1, w2 = f_jac[f, 3, j], f_jac[f, 4, j], f_jac[f, 5, j]
            jac[0, j] = a00 * w0 + a01 * w1 + a02 * w2
            jac[1, j] = a10 * w0 + a11 * w1 + a12 * w2
            jac[2, j] = a20 * w0 + a21 * w1 + a22 * w2
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


@numba.njit(cache=True, inline="always")
def dead_zone(e: float, t: float) -> float:  # pragma: no cover - compiled
    """``−sign(e)·max(0, |e| − t)``: zero for ``|e| ≤ t``, ``−e ± t`` beyond (continuous)."""
    if e > t:
        return t - e
    if e < -t:
        return -t - e
    return 0.0


@numba.njit(cache=True, inline="always")
def box_position_rows(
    rot: FloatArray,
    point: FloatArray,
    half: FloatArray,
    f: int,
    f_pos: FloatArray,
    f_jac: FloatArray,
    want_jac: bool,
    res: FloatArray,
    jac: FloatArray,
) -> float:  # pragma: no cover - compiled
    """Rows of frame ``f``'s origin in a box of the target frame: ``e = R*ᵀ(p − p*)``
    (``rot``: ``R*`` row-major (9,), ``point``: ``p*`` (3,)), row ``i`` the dead zone
    ``dz(e_i, half_i)``, step Jacobian ``R*ᵀ J_v`` on every row (inside the box too: a row at
    rest holds its offset to first order, so the other rows' steps do not push it out).
    Returns the norm of the rows: the distance beyond the box [m]."""
    dx = f_pos[f, 0] - point[0]
    dy = f_pos[f, 1] - point[1]
    dz = f_pos[f, 2] - point[2]
    out = 0.0
    for i in range(3):
        c0, c1, c2 = rot[i], rot[3 + i], rot[6 + i]
        r = dead_zone(c0 * dx + c1 * dy + c2 * dz, half[i])
        res[i] = r
        out += r * r
        if want_jac:
            for j in range(jac.shape[1]):
                jac[i, j] = c0 * f_jac[f, 0, j] + c1 * f_jac[f, 1, j] + c2 * f_jac[f, 2, j]
    return math.sqrt(out)


@numba.njit(cache=True, inline="always")
def box_rotation_rows(
    rot: FloatArray,
    bounds: FloatArray,
    f: int,
    f_rot: FloatArray,
    f_jac: FloatArray,
    want_jac: bool,
    res: FloatArray,
    jac: FloatArray,
    work: FloatArray,
) -> float:  # pragma: no cover - compiled
    """Rows of frame ``f``'s rotation in bounds of the target frame: ``φ = log(R*ᵀ R)``
    (``rot``: ``R*`` row-major (9,)), row ``i`` the dead zone ``dz(φ_i, bounds_i)``, step
    Jacobian ``Jr⁻¹(φ) Rᵀ J_ω`` on every row whose bound is below π (inside the bounds too, as
    :func:`box_position_rows`), zero on a free axis (bound π: ``|φ_i| <= π`` always).
    Returns the norm of the rows: the angle beyond the bounds [rad].  ``work``: scratch of at
    least 21 entries."""
    m3 = work[0:9].reshape((3, 3))
    v3 = work[9:12]
    for a in range(3):
        for b in range(3):
            m3[a, b] = (
                rot[a] * f_rot[f, 0, b] + rot[3 + a] * f_rot[f, 1, b] + rot[6 + a] * f_rot[f, 2, b]
            )
    theta = log3_nb(m3, v3)
    out = 0.0
    for i in range(3):
        r = dead_zone(v3[i], bounds[i])
        res[i] = r
        out += r * r
    if want_jac:
        jr_inv_nb(v3, theta, m3)
        a3 = work[12:21].reshape((3, 3))  # Jr⁻¹(φ) Rᵀ
        for a in range(3):
            for b in range(3):
                a3[a, b] = (
                    m3[a, 0] * f_rot[f, b, 0]
                    + m3[a, 1] * f_rot[f, b, 1]
                    + m3[a, 2] * f_rot[f, b, 2]
                )
        for i in range(3):
            if bounds[i] >= math.pi:
                for j in range(jac.shape[1]):
                    jac[i, j] = 0.0
            else:
                c0, c1, c2 = a3[i, 0], a3[i, 1], a3[i, 2]
                for j in range(jac.shape[1]):
                    jac[i, j] = c0 * f_jac[f, 3, j] + c1 * f_jac[f, 4, j] + c2 * f_jac[f, 5, j]
    return math.sqrt(out)


@numba.njit(cache=True, inline="always")
def ball_rows(
    point: FloatArray,
    radius: float,
    f: int,
    f_pos: FloatArray,
    f_jac: FloatArray,
    want_jac: bool,
    res: FloatArray,
    jac: FloatArray,
) -> float:  # pragma: no cover - compiled
    """Rows ``−max(0, ‖d‖ − ρ)·u`` of frame ``f``'s origin and the ball of radius ``ρ`` about
    ``point`` (``d = p − p*``, ``u = d/‖d‖``): the offset from the origin to the ball's nearest
    point, zero inside.  Step Jacobian ``[(1 − ρ/‖d‖)(I − uuᵀ) + uuᵀ] J_v`` outside, ``uuᵀ J_v``
    inside (continuous at the sphere; zero at ``d ≈ 0``).  ``ρ = 0`` gives the rows of
    :func:`position_rows`.  Returns the distance beyond the ball [m]."""
    dx = f_pos[f, 0] - point[0]
    dy = f_pos[f, 1] - point[1]
    dz = f_pos[f, 2] - point[2]
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    out = max(d - radius, 0.0)
    ux, uy, uz = 0.0, 0.0, 0.0
    if d > 1e-12:
        ux, uy, uz = dx / d, dy / d, dz / d
    res[0] = -out * ux
    res[1] = -out * uy
    res[2] = -out * uz
    if want_jac:
        s = 0.0  # 1 − ρ/‖d‖ outside, 0 inside (1 for ρ = 0: the point's rows at d = 0 too)
        if out > 0.0:
            s = out / d
        elif radius == 0.0:
            s = 1.0
        # M = s·I + (1 − s)·uuᵀ
        m00, m11, m22 = s + (1.0 - s) * ux * ux, s + (1.0 - s) * uy * uy, s + (1.0 - s) * uz * uz
        m01, m02, m12 = (1.0 - s) * ux * uy, (1.0 - s) * ux * uz, (1.0 - s) * uy * uz
        for j in range(jac.shape[1]):
            vx, vy, vz = f_jac[f, 0, j], f_jac[f, 1, j], f_jac[f, 2, j]
            jac[0, j] = m00 * vx + m01 * vy + m02 * vz
            jac[1, j] = m01 * vx + m11 * vy + m12 * vz
            jac[2, j] = m02 * vx + m12 * vy + m22 * vz
    return out
