"""Target poses: parsing, validation, projection onto SE(3), rotation helpers.

All poses are 4x4 homogeneous transforms in metres.  Quaternions are ``(x, y, z, w)``.
"""

from __future__ import annotations

import math
import reprlib
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarm_ik._types import FloatArray
from swarm_ik._validate import floats_or, one_line
from swarm_ik.errors import InvalidArgumentError, InvalidTargetError


def _floats(value: Any, what: str) -> FloatArray:
    """``value`` as a float array, or :class:`InvalidTargetError` naming it (strings, ragged
    nesting, None...)."""
    return floats_or(
        value,
        lambda: f"{what} must be numbers, got {one_line(reprlib.repr(value))}",
        InvalidTargetError,
    )


def is_finite_nonneg(value: Any) -> bool:
    """Whether ``value`` is a finite number ``>= 0`` (strings, booleans and None are not)."""
    if type(value) is float:  # the common case, first
        return 0.0 <= value < math.inf
    if isinstance(value, (str, bytes, bool, np.bool_)):
        return False
    try:
        v = float(value)
    except (TypeError, ValueError, OverflowError):  # (an int beyond a float: not finite)
        return False
    return bool(0.0 <= v < np.inf)


def check_tolerances(tol_pos: Any, tol_rot: Any) -> None:
    """Refuse success tolerances that are not positive finite numbers.

    Raises:
        InvalidArgumentError: ``tol_pos`` [m] or ``tol_rot`` [rad] named, with its value.
    """
    for label, tol in (("tol_pos", tol_pos), ("tol_rot", tol_rot)):
        if isinstance(tol, bool) or not (is_finite_nonneg(tol) and float(tol) > 0):
            raise InvalidArgumentError(f"{label} must be a positive number, got {tol!r}")


def unit(v: FloatArray) -> FloatArray | None:
    """``v`` (finite) divided by its norm, computed on ``v`` over its largest absolute entry
    first, so that entries such as 1e200, whose squares overflow, normalise exactly; None
    when the norm is below 1e-9 (no direction to read)."""
    big = float(np.max(np.abs(v)))
    scaled = v / big if big > 0.0 else v
    if not big * float(np.linalg.norm(scaled)) >= 1e-9:
        return None
    return scaled / np.linalg.norm(scaled)


def quat_to_matrix(quat_xyzw: Any) -> FloatArray:
    """Rotation matrix of a quaternion.

    Args:
        quat_xyzw: Quaternion ``(x, y, z, w)`` (or a ``pinocchio.Quaternion``: its
            ``coeffs()``), any finite norm of at least 1e-9 (it is normalised: divided by its
            largest absolute component first, so that a norm such as 1e200, whose square
            overflows, normalises exactly).

    Returns:
        Rotation matrix, shape ``(3, 3)``.

    Raises:
        InvalidTargetError: not 4 finite numbers, or norm (almost) zero.
    """
    if hasattr(quat_xyzw, "coeffs"):  # a pinocchio.Quaternion (Eigen's): its (x, y, z, w)
        quat_xyzw = np.asarray(quat_xyzw.coeffs(), dtype=float)
    q = _floats(quat_xyzw, "quaternion").ravel()
    if q.shape != (4,) or not np.all(np.isfinite(q)):
        raise InvalidTargetError(
            f"quaternion must be 4 finite numbers (x, y, z, w), got {q.tolist()}"
        )
    # (one quaternion in Python floats: the operations of _rotations_of_quaternions, in its
    # order, so both give the same bits, at a third of the batched code's cost for one)
    a0, a1, a2, a3 = q.tolist()
    big = max(abs(a0), abs(a1), abs(a2), abs(a3))
    if big > 0.0:
        a0, a1, a2, a3 = a0 / big, a1 / big, a2 / big, a3 / big
    norm = math.sqrt(((a0 * a0 + a1 * a1) + a2 * a2) + a3 * a3)
    if not big * norm >= 1e-9:
        raise InvalidTargetError(f"quaternion has zero norm: {q.tolist()}")
    x, y, z, w = a0 / norm, a1 / norm, a2 / norm, a3 / norm
    return unit_quaternion_matrix(x, y, z, w)


def _rotations_of_quaternions(q: FloatArray) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Rotation matrices ``(N, 3, 3)`` of finite quaternions ``(x, y, z, w)`` ``(N, 4)``, each
    divided by its largest absolute component, then by its norm (as :func:`unit`); and which
    have a norm (almost) zero ``(N,)`` (their matrices not meaningful).  The operations of
    :func:`quat_to_matrix` on one quaternion, in its order: both give the same bits."""
    big = np.max(np.abs(q), axis=1)
    scaled = q / np.where(big > 0.0, big, 1.0)[:, None]
    norm = np.sqrt(
        ((scaled[:, 0] ** 2 + scaled[:, 1] ** 2) + scaled[:, 2] ** 2) + scaled[:, 3] ** 2
    )
    with np.errstate(over="ignore"):  # (a norm of 1e308 and more: inf, as in Python floats)
        zero = ~(big * norm >= 1e-9)
    x, y, z, w = (scaled / np.where(zero, 1.0, norm)[:, None]).T
    # (unit_quaternion_matrix's entries, elementwise on the columns: (3, 3, N))
    return np.moveaxis(unit_quaternion_matrix(x, y, z, w), -1, 0), zero


def unit_quaternion_matrix(x: Any, y: Any, z: Any, w: Any) -> FloatArray:
    """Rotation matrix ``(3, 3)`` of the unit quaternion ``w + xi + yj + zk`` (already
    normalised: :func:`unit`); of arrays of ``N`` such quaternions' components, the matrices
    ``(3, 3, N)``."""
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def matrix_to_quat(rot: Any) -> FloatArray:
    """Quaternion ``(x, y, z, w)`` with ``w >= 0`` of a rotation matrix ``(3, 3)``."""
    from scipy.spatial.transform import Rotation

    q = Rotation.from_matrix(np.asarray(rot, dtype=float)).as_quat()
    return q if q[3] >= 0 else -q


def make_pose(position: Any, quat_xyzw: Any) -> FloatArray:
    """4x4 pose from a position ``(3,)`` [m] and a quaternion ``(x, y, z, w)``."""
    p = _floats(position, "position").ravel()
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise InvalidTargetError(f"position must be 3 finite numbers, got {p.tolist()}")
    pose = np.eye(4)
    pose[:3, :3] = quat_to_matrix(quat_xyzw)
    pose[:3, 3] = p
    return pose


def poses_from_rows(rows: FloatArray, first: int = 0) -> FloatArray:
    """Poses ``(N, 4, 4)`` of finite rows ``x y z qx qy qz qw`` ``(N, 7)``: :func:`make_pose`
    of each, all at once (each quaternion divided by its largest absolute component, then by
    its norm, as :func:`unit`).

    Raises:
        InvalidTargetError: a quaternion of norm (almost) zero (the first such row named, as
            target ``first + its row``).
    """
    rot, zero = _rotations_of_quaternions(rows[:, 3:7])
    if zero.any():
        i = int(np.flatnonzero(zero)[0])
        raise InvalidTargetError(
            f"target {first + i}: quaternion has zero norm: {rows[i, 3:7].tolist()}"
        )
    out = np.zeros((rows.shape[0], 4, 4))
    out[:, :3, :3] = rot
    out[:, :3, 3] = rows[:, :3]
    out[:, 3, 3] = 1.0
    return out


def project_to_se3(matrix: Any) -> FloatArray:
    """Nearest proper rigid transform to a 4x4 matrix (rotation block by SVD, det +1).

    Use it for printed, rounded matrices such as the target of [HLFOA].

    Args:
        matrix: Almost-rigid transform, shape ``(4, 4)``.

    Returns:
        A valid pose, shape ``(4, 4)``, same translation, bottom row ``[0, 0, 0, 1]``.
    """
    m = _floats(matrix, "matrix")
    if m.shape != (4, 4) or not np.all(np.isfinite(m)):
        raise InvalidTargetError(f"expected a finite 4x4 matrix, got shape {m.shape}")
    u, _, vt = np.linalg.svd(m[:3, :3])
    d = np.sign(np.linalg.det(u @ vt))
    out = np.eye(4)
    out[:3, :3] = u @ np.diag([1.0, 1.0, d]) @ vt
    out[:3, 3] = m[:3, 3]
    return out


_EYE3 = np.eye(3)
FLOAT64 = np.dtype(np.float64)
"""float64 (an array's dtype is this object, except for rare equal copies: those take the
full checks, which accept them)."""


def clearly_pose(
    orth_tol: float,
    a: float, b: float, c: float, x: float,
    d: float, e: float, f: float, y: float,
    g: float, h: float, i: float, z: float,
    p: float, q: float, r: float, w: float,
) -> bool:  # fmt: skip
    """Whether the 4×4 matrix of the 16 entries ``a … w`` (row by row) passes :func:`as_pose`'s
    checks with a margin: finite, bottom row ``[0, 0, 0, 1]`` within 1e-9, ``max |RᵀR − I|``
    and ``|det R − 1|`` within ``orth_tol / 2``.  False means "let the full checks judge" (a
    borderline or bad matrix).  Scalar arithmetic (2 µs where the numpy checks take 12 µs),
    kept in plain Python, as the whole module is (it loads no numba)."""
    if not math.isfinite(a + b + c + x + d + e + f + y + g + h + i + z + p + q + r + w):
        return False  # (a sum of finite numbers may overflow: then the full check decides)
    if abs(p) > 1e-9 or abs(q) > 1e-9 or abs(r) > 1e-9 or abs(w - 1.0) > 1e-9:
        return False
    tol = 0.5 * orth_tol
    if (
        abs(a * a + d * d + g * g - 1.0) > tol
        or abs(b * b + e * e + h * h - 1.0) > tol
        or abs(c * c + f * f + i * i - 1.0) > tol
        or abs(a * b + d * e + g * h) > tol
        or abs(a * c + d * f + g * i) > tol
        or abs(b * c + e * f + h * i) > tol
    ):
        return False
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    return abs(det - 1.0) <= tol


ORTH_TOL = 1e-6
"""The default tolerance on the orthonormality of a target's rotation (:func:`as_pose`)."""


def as_pose(target: Any, *, orth_tol: float = ORTH_TOL) -> FloatArray:
    """Validate and convert a target to a 4x4 pose.

    Args:
        target: A ``(4, 4)`` array; a ``(position (3,), quaternion xyzw (4,))`` pair; a flat
            array of 7 numbers ``x y z qx qy qz qw``; or a ``pinocchio.SE3``.
        orth_tol: Largest accepted ``max |RᵀR − I|`` and ``|det R − 1|`` of the rotation block.

    Returns:
        The pose, shape ``(4, 4)`` (a copy).

    Raises:
        InvalidTargetError: wrong shape, non-finite values, a bottom row other than
            ``[0, 0, 0, 1]``, or a rotation block further than ``orth_tol`` from a rotation.
    """
    if not is_finite_nonneg(orth_tol):
        raise InvalidArgumentError(
            f"orth_tol must be a finite non-negative number, got {orth_tol!r}"
        )
    if type(target) is np.ndarray and target.dtype is FLOAT64 and target.shape == (4, 4):
        (a, b, c, x), (d, e, f, y), (g, h, i, z), (p, q, r, w) = target.tolist()
        if clearly_pose(orth_tol, a, b, c, x, d, e, f, y, g, h, i, z, p, q, r, w):
            return target.copy()  # (the checks below would accept it)
    if hasattr(target, "homogeneous"):  # pinocchio.SE3
        target = np.asarray(target.homogeneous)
    if isinstance(target, (tuple, list)) and len(target) == 2:
        return make_pose(target[0], target[1])
    m = _floats(target, "target")
    if m.shape == (7,):
        return make_pose(m[:3], m[3:])
    if m.shape != (4, 4):
        got = f"shape {m.shape}" if m.ndim else reprlib.repr(target)
        raise InvalidTargetError(
            f"target must be a 4x4 matrix, (position, quaternion) or 7 numbers; got {got}"
        )
    if not np.all(np.isfinite(m)):
        where = [tuple(ij) for ij in np.argwhere(~np.isfinite(m)).tolist()]
        raise InvalidTargetError(f"target contains NaN or infinite values at (row, column) {where}")
    b = m[3].tolist()  # scalar maths: one small matrix (this runs on every solve)
    if abs(b[0]) > 1e-9 or abs(b[1]) > 1e-9 or abs(b[2]) > 1e-9 or abs(b[3] - 1.0) > 1e-9:
        raise InvalidTargetError(f"target's bottom row must be [0, 0, 0, 1], got {m[3].tolist()}")
    rot = m[:3, :3]
    orth = float(np.abs(rot.T @ rot - _EYE3).max())
    r = rot.tolist()
    det = (
        r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
        - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
        + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0])
    )
    if orth > orth_tol or abs(det - 1.0) > orth_tol:
        raise InvalidTargetError(
            f"target rotation is not orthonormal: max|RᵀR − I| = {orth:.3g}, det = {det:.9g} "
            f"(tolerance {orth_tol:g}); fix it with swarm_ik.pose.project_to_se3 or raise "
            "orth_tol"
        )
    return m


def rotation_angle(rot_err: FloatArray) -> FloatArray:
    """Angle [rad] of rotation matrices ``(..., 3, 3)`` → ``(...)`` in ``[0, π]``, accurate
    near 0 and π: :func:`swarm_ik.kernels.lie.angle` (the one set of rotation helpers)."""
    from swarm_ik.kernels.lie import angle

    return angle(rot_err)
