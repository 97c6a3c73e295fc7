"""Rotation helpers in one place: ``exp3``, ``log3``, the rotation angle, ``Jr`` and ``Jr⁻¹``.

Each has a compiled twin (``*_nb``, numba, one rotation, no allocation) for the kernels and a
numpy version for Python code; ``tests/test_lie.py`` checks them against each other and
against Pinocchio's ``log3`` / ``Jlog3``.

Conventions: a rotation vector ``φ = θ·u`` (``θ ∈ [0, π]``), ``exp([φ]×) = R``.  The right
Jacobian inverse is ``Jr⁻¹(φ) = I + ½[φ]× + k(θ)[φ]×²`` with
``k = 1/θ² − (1 + cos θ)/(2θ sin θ)`` ([LIE], eq. 144).
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np

from swarm_ik._types import FloatArray


@numba.njit(cache=True)
def angle_nb(m: FloatArray) -> float:  # pragma: no cover - compiled
    """Rotation angle θ ∈ [0, π] of the rotation matrix ``m`` (3, 3), accurate near 0 and π
    (``atan2`` of the skew and trace parts)."""
    s0 = m[2, 1] - m[1, 2]
    s1 = m[0, 2] - m[2, 0]
    s2 = m[1, 0] - m[0, 1]
    c = m[0, 0] + m[1, 1] + m[2, 2] - 1.0
    return math.atan2(math.sqrt(s0 * s0 + s1 * s1 + s2 * s2), c)


@numba.njit(cache=True, inline="always")
def log3_entries(
    m00: float,
    m01: float,
    m02: float,
    m10: float,
    m11: float,
    m12: float,
    m20: float,
    m21: float,
    m22: float,
) -> tuple[float, float, float, float]:  # pragma: no cover - compiled
    """``(θ, φx, φy, φz)``: the angle and rotation vector of the rotation whose entries are
    given row by row (scalars: no array for the kernels' inner loop to count references of).

    Accurate near 0 (``atan2`` of the skew part) and near π (axis from the symmetric part
    ``B = c I + (1 − c) a aᵀ``, from its largest diagonal entry).
    """  # fmt: skip
    s0 = 0.5 * (m21 - m12)
    s1 = 0.5 * (m02 - m20)
    s2 = 0.5 * (m10 - m01)
    sn = math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
    c = 0.5 * (m00 + m11 + m22 - 1.0)
    theta = math.atan2(sn, c)
    if theta < 1e-5:
        scale = 1.0 + theta * theta / 6.0
        return theta, s0 * scale, s1 * scale, s2 * scale
    if theta < math.pi - 1e-3:
        scale = theta / sn
        return theta, s0 * scale, s1 * scale, s2 * scale
    one_c = 1.0 - c
    if m00 >= m11 and m00 >= m22:
        ai = math.sqrt(max((m00 - c) / one_c, 0.0))
        a0, a1, a2 = ai, 0.5 * (m10 + m01) / (one_c * ai), 0.5 * (m20 + m02) / (one_c * ai)
    elif m11 >= m22:
        ai = math.sqrt(max((m11 - c) / one_c, 0.0))
        a0, a1, a2 = 0.5 * (m01 + m10) / (one_c * ai), ai, 0.5 * (m21 + m12) / (one_c * ai)
    else:
        ai = math.sqrt(max((m22 - c) / one_c, 0.0))
        a0, a1, a2 = 0.5 * (m02 + m20) / (one_c * ai), 0.5 * (m12 + m21) / (one_c * ai), ai
    norm = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
    if a0 * s0 + a1 * s1 + a2 * s2 < 0.0:
        norm = -norm
    return theta, theta * a0 / norm, theta * a1 / norm, theta * a2 / norm


@numba.njit(cache=True, inline="always")
def log3_nb(m: FloatArray, out: FloatArray) -> float:  # pragma: no cover - compiled
    """Rotation vector of ``m`` (3, 3) into ``out`` (3,); returns the angle θ
    (:func:`log3_entries`)."""
    theta, out[0], out[1], out[2] = log3_entries(
        m[0, 0], m[0, 1], m[0, 2], m[1, 0], m[1, 1], m[1, 2], m[2, 0], m[2, 1], m[2, 2]
    )
    return theta


@numba.njit(cache=True, inline="always")
def jr_inv_entries(
    px: float, py: float, pz: float, theta: float
) -> tuple[float, float, float, float, float, float, float, float, float]:  # pragma: no cover
    """The entries of ``Jr⁻¹(φ)`` row by row for the rotation vector ``φ = (px, py, pz)`` of
    angle ``θ`` (``I + ½[φ]× + k[φ]×²``, the module docstring)."""
    if theta < 1e-3:
        k = 1.0 / 12.0 + theta * theta / 720.0
    else:
        k = 1.0 / (theta * theta) - (1.0 + math.cos(theta)) / (2.0 * theta * math.sin(theta))
    # [φ]× = [[0, -pz, py], [pz, 0, -px], [-py, px, 0]]; [φ]×² = φφᵀ − θ² I
    n2 = px * px + py * py + pz * pz
    return (
        1.0 + k * (px * px - n2), -0.5 * pz + k * px * py, 0.5 * py + k * px * pz,
        0.5 * pz + k * py * px, 1.0 + k * (py * py - n2), -0.5 * px + k * py * pz,
        -0.5 * py + k * pz * px, 0.5 * px + k * pz * py, 1.0 + k * (pz * pz - n2),
    )  # fmt: skip


@numba.njit(cache=True, inline="always")
def jr_inv_nb(phi: FloatArray, theta: float, out: FloatArray) -> None:  # pragma: no cover
    """``Jr⁻¹(φ)`` (3, 3) into ``out`` for the rotation vector ``φ`` of angle ``θ``
    (:func:`jr_inv_entries`).

    With ``φ = log(R* Rᵀ)`` in world axes and ``ω`` the world angular velocity,
    ``dφ/dt = −Jr⁻¹(φ)·ω`` … up to the sign convention used by the kernel (see
    :mod:`swarm_ik.kernels.lm`); only the matrix is computed here.
    """
    (
        out[0, 0], out[0, 1], out[0, 2], out[1, 0], out[1, 1], out[1, 2],
        out[2, 0], out[2, 1], out[2, 2],
    ) = jr_inv_entries(phi[0], phi[1], phi[2], theta)  # fmt: skip


@numba.njit(cache=True, inline="always")
def exp3_coeffs(rx: float, ry: float, rz: float) -> tuple[float, float, float]:  # pragma: no cover
    """``(sin θ/θ, (1 − cos θ)/θ², (θ − sin θ)/θ³)`` of the rotation vector ``(rx, ry, rz)``
    (θ its norm): the coefficients of ``exp`` and of the right Jacobian ``Jr`` of SO(3)
    ([LIE] eqs. 77 and 143), free of cancellation: ``(1 − cos θ)/θ² = ½ (sin(θ/2)/(θ/2))²``,
    and ``(θ − sin θ)/θ³`` by its Taylor series up to ``θ¹⁰`` below ``θ² = 0.1`` (the quotient
    lost ``6ε/θ²`` of its value there: 2e-12 m/rad of a 5.6 m floating-base Jacobian at
    θ = 1.1e-4)."""
    t2 = rx * rx + ry * ry + rz * rz
    if t2 < 1e-8:
        a, b = 1.0 - t2 / 6.0, 0.5 - t2 / 24.0
    else:
        t = math.sqrt(t2)
        h = math.sin(0.5 * t) / (0.5 * t)
        a, b = math.sin(t) / t, 0.5 * h * h
    if t2 < 0.1:
        c = 1.0 / 6.0 + t2 * (
            -1.0 / 120.0
            + t2
            * (1.0 / 5040.0 + t2 * (-1.0 / 362880.0 + t2 * (1.0 / 39916800.0 - t2 / 6227020800.0)))
        )
    else:
        t = math.sqrt(t2)
        c = (t - math.sin(t)) / (t2 * t)
    return a, b, c


@numba.njit(cache=True, inline="always")
def exp3_nb(rx: float, ry: float, rz: float, out: FloatArray) -> None:  # pragma: no cover
    """``out = exp([r]×) = I + a[r]× + b[r]×²`` (3, 3) of the rotation vector ``r``."""
    a, b, _ = exp3_coeffs(rx, ry, rz)
    xx, yy, zz = rx * rx, ry * ry, rz * rz
    out[0, 0] = 1.0 - b * (yy + zz)
    out[1, 1] = 1.0 - b * (xx + zz)
    out[2, 2] = 1.0 - b * (xx + yy)
    out[0, 1] = -a * rz + b * rx * ry
    out[1, 0] = a * rz + b * rx * ry
    out[0, 2] = a * ry + b * rx * rz
    out[2, 0] = -a * ry + b * rx * rz
    out[1, 2] = -a * rx + b * ry * rz
    out[2, 1] = a * rx + b * ry * rz


@numba.njit(cache=True, inline="always")
def jr_nb(rx: float, ry: float, rz: float, out: FloatArray) -> None:  # pragma: no cover
    """``out = Jr(r) = I − b[r]× + c[r]×²`` (3, 3), the right Jacobian of SO(3): the body
    angular velocity of ``exp([r]×)`` is ``Jr(r)·ṙ`` ([LIE] eq. 143)."""
    _, b, c = exp3_coeffs(rx, ry, rz)
    xx, yy, zz = rx * rx, ry * ry, rz * rz
    out[0, 0] = 1.0 - c * (yy + zz)
    out[1, 1] = 1.0 - c * (xx + zz)
    out[2, 2] = 1.0 - c * (xx + yy)
    out[0, 1] = b * rz + c * rx * ry
    out[1, 0] = -b * rz + c * rx * ry
    out[0, 2] = -b * ry + c * rx * rz
    out[2, 0] = b * ry + c * rx * rz
    out[1, 2] = b * rx + c * ry * rz
    out[2, 1] = -b * rx + c * ry * rz


# --------------------------------------------------------------------------- numpy twins
def angle(rot: FloatArray) -> FloatArray:
    """Rotation angles θ ∈ [0, π] of rotations ``(..., 3, 3)`` → ``(...)``, accurate near 0
    and π."""
    r = np.asarray(rot, dtype=float)
    s = np.stack(
        [r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0], r[..., 1, 0] - r[..., 0, 1]],
        axis=-1,
    )
    c = r[..., 0, 0] + r[..., 1, 1] + r[..., 2, 2] - 1.0
    return np.arctan2(np.linalg.norm(s, axis=-1), c)


def relative_angles(r_a: FloatArray, r_b: FloatArray) -> FloatArray:
    """Rotation angles θ ∈ [0, π] of ``r_aᵀ r_b`` → ``(...)``, for rotations ``r_a`` and
    ``r_b`` ``(..., 3, 3)`` (broadcast), accurate near 0 and π.

    The product's entries are written out, ``m_ij = a_0i b_0j + a_1i b_1j + a_2i b_2j`` in
    that order, each an elementwise NumPy operation, then :func:`angle`'s ``atan2`` of the
    skew and trace parts (libm's, per element): :func:`angle_between` runs the same operations
    on Python floats, so a batched check (:func:`swarm_ik.branches.pose_errors_of`) and the
    one-answer judge (``Pose.errors``) agree to the last bit, where a matrix product may sum
    in another order.
    """
    a = np.asarray(r_a, dtype=float)
    b = np.asarray(r_b, dtype=float)

    def m(i: int, j: int) -> FloatArray:
        return (  # type: ignore[no-any-return]
            a[..., 0, i] * b[..., 0, j] + a[..., 1, i] * b[..., 1, j] + a[..., 2, i] * b[..., 2, j]
        )

    s0 = m(2, 1) - m(1, 2)
    s1 = m(0, 2) - m(2, 0)
    s2 = m(1, 0) - m(0, 1)
    c = m(0, 0) + m(1, 1) + m(2, 2) - 1.0
    y = np.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
    # libm's atan2 per element: NumPy's arctan2 runs SIMD code on some CPUs (AVX-512) whose
    # last bit differs from math.atan2's in about one case in twelve
    theta = map(math.atan2, np.ravel(y).tolist(), np.ravel(c).tolist())
    return np.fromiter(theta, dtype=float, count=np.size(y)).reshape(np.shape(y))


@numba.njit(cache=True, inline="always")
def _angle_of_blocks(a: FloatArray, b: FloatArray) -> float:  # pragma: no cover - compiled
    """θ of ``aᵀb`` for the rotation blocks (the first three rows and columns) of ``a`` and
    ``b``: the product's entries written out in :func:`relative_angles`' order, then libm's
    ``sqrt`` and ``atan2`` (numba calls libm's and fuses no multiply-add by default), so the
    bits are the batched check's (``tests/test_lie.py``)."""
    a00, a01, a02 = a[0, 0], a[0, 1], a[0, 2]
    a10, a11, a12 = a[1, 0], a[1, 1], a[1, 2]
    a20, a21, a22 = a[2, 0], a[2, 1], a[2, 2]
    b00, b01, b02 = b[0, 0], b[0, 1], b[0, 2]
    b10, b11, b12 = b[1, 0], b[1, 1], b[1, 2]
    b20, b21, b22 = b[2, 0], b[2, 1], b[2, 2]
    s0 = (a02 * b01 + a12 * b11 + a22 * b21) - (a01 * b02 + a11 * b12 + a21 * b22)
    s1 = (a00 * b02 + a10 * b12 + a20 * b22) - (a02 * b00 + a12 * b10 + a22 * b20)
    s2 = (a01 * b00 + a11 * b10 + a21 * b20) - (a00 * b01 + a10 * b11 + a20 * b21)
    c = (
        (a00 * b00 + a10 * b10 + a20 * b20)
        + (a01 * b01 + a11 * b11 + a21 * b21)
        + (a02 * b02 + a12 * b12 + a22 * b22)
        - 1.0
    )
    return math.atan2(math.sqrt(s0 * s0 + s1 * s1 + s2 * s2), c)


def angle_between(r_a: Any, r_b: Any) -> float:
    """Rotation angle θ ∈ [0, π] of ``r_aᵀ r_b`` for two rotations ``(3, 3)``, or the
    rotations of two poses ``(4, 4)``, as arrays or nested lists (rows): the one-pair twin of
    :func:`relative_angles`, with the same bits (one compiled call)."""
    a = np.ascontiguousarray(r_a, dtype=float)
    b = np.ascontiguousarray(r_b, dtype=float)
    if a.ndim != 2 or b.ndim != 2 or min(a.shape + b.shape) < 3:
        raise ValueError(
            f"angle_between needs two (3, 3) or (4, 4) matrices, got {a.shape}, {b.shape}"
        )
    return float(_angle_of_blocks(a, b))  # (inlined where compiled code calls it)


@numba.njit(cache=True)
def pose_errors_one(pose: FloatArray, target: FloatArray) -> tuple[float, float]:
    """``(‖p − p*‖ [m], θ [rad])`` of one pose ``(4, 4)`` against a target ``(4, 4)``: the
    judge's errors of an exact :class:`~swarm_ik.goals.Pose`, compiled (θ of ``R*ᵀR`` as
    :func:`angle_between`; the offset's norm as the in-order sum of squares), in one call
    instead of two ``tolist`` and 60 operations on Python floats (about 1 µs against 4 µs
    per answer)."""
    d0 = pose[0, 3] - target[0, 3]
    d1 = pose[1, 3] - target[1, 3]
    d2 = pose[2, 3] - target[2, 3]
    return math.sqrt(d0 * d0 + d1 * d1 + d2 * d2), _angle_of_blocks(target, pose)


def log3(rot: FloatArray) -> FloatArray:
    """Rotation vectors ``(..., 3)`` of rotations ``(..., 3, 3)``, accurate near 0 and π.

    Vectorised twin of :func:`log3_nb`: ``φ = θ/sin θ · vee(R − Rᵀ)/2`` away from π, the axis
    from the symmetric part ``(R + Rᵀ)/2 = cos θ·I + (1 − cos θ)·aaᵀ`` near π.
    """
    r = np.asarray(rot, dtype=float)
    shape = r.shape[:-2]
    r = r.reshape(-1, 3, 3)
    s = 0.5 * np.stack(
        [r[:, 2, 1] - r[:, 1, 2], r[:, 0, 2] - r[:, 2, 0], r[:, 1, 0] - r[:, 0, 1]], -1
    )
    sn = np.linalg.norm(s, axis=-1)
    c = 0.5 * (np.trace(r, axis1=1, axis2=2) - 1.0)
    theta = np.arctan2(sn, c)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(theta < 1e-5, 1.0 + theta**2 / 6.0, theta / np.where(sn > 0, sn, 1.0))
    out = s * scale[:, None]
    near = theta >= np.pi - 1e-3
    if np.any(near):
        rn, cn, sv, tn = r[near], c[near], s[near], theta[near]
        sym = 0.5 * (rn + np.swapaxes(rn, 1, 2))
        diag = np.diagonal(sym, axis1=1, axis2=2)
        i = np.argmax(diag, axis=1)
        rows = np.arange(rn.shape[0])
        col = sym[rows, :, i] / (1.0 - cn)[:, None]  # a · a_i
        col[rows, i] = np.sqrt(np.maximum((diag[rows, i] - cn) / (1.0 - cn), 0.0)) ** 2
        a = col / np.linalg.norm(col, axis=-1, keepdims=True)
        sign = np.where(np.einsum("ij,ij->i", a, sv) < 0.0, -1.0, 1.0)
        out[near] = a * (sign * tn)[:, None]
    return out.reshape(shape + (3,))


def jr_inv(phi: FloatArray) -> FloatArray:
    """``Jr⁻¹(φ) = I + ½[φ]× + k[φ]×²`` (3, 3) of one rotation vector ``φ`` (3,)."""
    p = np.asarray(phi, dtype=float).reshape(3)
    theta = float(np.linalg.norm(p))
    if theta < 1e-3:
        k = 1.0 / 12.0 + theta**2 / 720.0
    else:
        k = 1.0 / theta**2 - (1.0 + np.cos(theta)) / (2.0 * theta * np.sin(theta))
    sk = np.array([[0.0, -p[2], p[1]], [p[2], 0.0, -p[0]], [-p[1], p[0], 0.0]])
    return np.eye(3) + 0.5 * sk + k * (sk @ sk)


def exp3(phi: FloatArray) -> FloatArray:
    """``exp([φ]×)`` (3, 3) of one rotation vector ``φ`` (3,) (twin of :func:`exp3_nb`)."""
    p = np.asarray(phi, dtype=float).reshape(3)
    out = np.empty((3, 3))
    exp3_nb(float(p[0]), float(p[1]), float(p[2]), out)
    return out


def jr(phi: FloatArray) -> FloatArray:
    """The right Jacobian ``Jr(φ)`` (3, 3) of SO(3) (twin of :func:`jr_nb`)."""
    p = np.asarray(phi, dtype=float).reshape(3)
    out = np.empty((3, 3))
    jr_nb(float(p[0]), float(p[1]), float(p[2]), out)
    return out
