"""``Pose``: a frame at a full pose, exactly or within per-axis bounds of the target frame."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numba
import numpy as np

from swarm_ik._validate import nonnegative
from swarm_ik.errors import InvalidArgumentError
from swarm_ik.goals.base import Encoded, FloatArray, Goal, Pin, State, frame_index
from swarm_ik.kernels import lie
from swarm_ik.kernels.rows import (
    box_position_rows,
    box_rotation_rows,
    position_rows,
    rotation_rows,
)
from swarm_ik.pose import as_pose

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel


@numba.njit(cache=True)
def pose_kernel(par, ipar, q, f_pos, f_rot, f_jac, want_jac, res, jac, err, work):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Rows ``[p* − p; log(R* Rᵀ)]`` of frame ``ipar[0]``; ``par = [R* row-major (9), p* (3)]``
    (the exact form)."""
    f = ipar[0]
    err[0] = position_rows(par[9:12], f, f_pos, f_jac, want_jac, res[0:3], jac[0:3])
    err[1] = rotation_rows(par[0:9], f, f_rot, f_jac, want_jac, res[3:6], jac[3:6], work)


@numba.njit(cache=True)
def pose_bounded_kernel(par, ipar, q, f_pos, f_rot, f_jac, want_jac, res, jac, err, work):  # type: ignore[no-untyped-def]  # pragma: no cover
    """The dead-zone rows of :func:`~swarm_ik.kernels.rows.box_position_rows` and
    :func:`~swarm_ik.kernels.rows.box_rotation_rows` of frame ``ipar[0]`` (a
    :attr:`Pose.tolerance`); ``par = [R* (9), p* (3), position bounds (3), rotation bounds
    (3)]``.  Its own kernel, so the exact form compiles without it."""
    f = ipar[0]
    err[0] = box_position_rows(
        par[0:9], par[9:12], par[12:15], f, f_pos, f_jac, want_jac, res[0:3], jac[0:3]
    )
    err[1] = box_rotation_rows(
        par[0:9], par[15:18], f, f_rot, f_jac, want_jac, res[3:6], jac[3:6], work
    )


def pose_tolerance(value: Any) -> tuple[float, ...] | None:
    """``Pose.tolerance`` checked: None, or 6 finite numbers ``>= 0`` (metres, then radians
    ``<= π``) as a tuple of floats.

    Raises:
        InvalidArgumentError: anything else, naming ``Pose.tolerance``.
    """
    arr = nonnegative(
        value, "Pose.tolerance must be 6 numbers (tx, ty, tz [m], rx, ry, rz [rad])", (6,),
        "Pose.tolerance must be finite and >= 0",
    )  # fmt: skip
    if arr is None:
        return None
    if np.any(arr[3:] > math.pi):
        raise InvalidArgumentError(
            "Pose.tolerance: rotation bounds must be at most π (π frees the axis), got "
            f"{arr[3:].tolist()}"
        )
    return tuple(float(x) for x in arr)


def dead_zone(e: FloatArray, t: FloatArray) -> FloatArray:
    """``−sign(e)·max(0, |e| − t)`` elementwise (numpy twin of
    :func:`swarm_ik.kernels.rows.dead_zone`)."""
    return np.asarray(-np.sign(e) * np.maximum(np.abs(e) - t, 0.0))


_PARAMS_OF_POSE = np.array([0, 1, 2, 4, 5, 6, 8, 9, 10, 3, 7, 11])
"""Where :meth:`Pose.params` reads a target's 4×4 entries (flat, row-major): the
rotation row by row, then the position."""


@dataclass(frozen=True)
class Pose(Goal):
    """The frame at a full pose, exactly or within bounds.

    Exact (``tolerance=None``): ``r = [p* − p; log(R* Rᵀ)]`` (world axes; metres, radians),
    judged by ``‖p − p*‖`` [m] and the angle of ``R*ᵀ R`` [rad].

    Within bounds (``tolerance = (tx, ty, tz, rx, ry, rz)``), in the *target* frame: the
    position offset ``e = R*ᵀ(p − p*)`` [m] and the rotation vector ``φ = log(R*ᵀ R)`` [rad]
    give the dead-zone rows ``r = [dz(e, t_xyz); dz(φ, t_rxyz)]`` with
    ``dz(e, t) = −sign(e)·max(0, |e| − t)``: zero inside the bounds, continuous at them.  The
    step Jacobian (``r(q + δ) ≈ r − J δ``) is ``J = [R*ᵀ J_v; Jr⁻¹(φ) Rᵀ J_ω]`` (``J_ω`` the
    world angular Jacobian, so ``Rᵀ J_ω`` the body one) on every row, inside the bounds too:
    there it is the derivative of the offset, not of the zero row, so a row at rest holds its
    offset to first order (TRAC-IK's bounds keep the Jacobian likewise; a zero row lets the
    other rows push it out again: from 1.4–3.4× fewer random starts, see
    :mod:`swarm_ik.kernels.rows`); zero on a free axis.
    :meth:`jacobian` is this ``−J``.  The errors judged are the norms of the parts beyond the
    bounds (0 inside), so ``goal_errors`` reports the distance to the bounds.  A rotation
    bound of π frees that axis (``|φ_i| <= π``): ``(0, 0, 0, 0, 0, π)`` leaves the rotation
    about the target's z axis free.

    Args:
        frame: Goal frame name.
        target: ``(4, 4)`` pose [m], ``(position, quaternion xyzw)``, 7 numbers, or SE3.
        orth_tol: Tolerance on the orthonormality of the target rotation (keyword-only).
        tolerance: None (exact, the default), or 6 bounds: position half-widths ``>= 0`` [m]
            along the target's x, y, z, then bounds ``0 <= b <= π`` [rad] on the components
            of ``φ`` (keyword-only).
        weight, primary: As :class:`~swarm_ik.goals.Goal` (keyword-only).
    """

    frame: str
    target: Any
    orth_tol: float = field(default=1e-6, kw_only=True)
    tolerance: Any = field(default=None, kw_only=True)
    kernel: ClassVar[Any] = pose_kernel

    def __post_init__(self) -> None:
        object.__setattr__(self, "target", as_pose(self.target, orth_tol=self.orth_tol))
        object.__setattr__(self, "tolerance", pose_tolerance(self.tolerance))
        super().__post_init__()

    @classmethod
    def checked(cls, frame: str, target: FloatArray, orth_tol: float = 1e-6) -> Pose:
        """An exact Pose of a target already validated by :func:`swarm_ik.pose.as_pose` (with
        ``orth_tol``)."""
        goal = object.__new__(cls)
        goal.__dict__.update(
            frame=frame, target=target, weight=1.0, primary=True, orth_tol=orth_tol,
            tolerance=None,
        )  # fmt: skip
        return goal

    @staticmethod
    def params(target: FloatArray) -> FloatArray:
        """The float parameters of a target ``(4, 4)``, or of targets ``(N, 4, 4)`` as
        ``(N, 12)``: what :func:`swarm_ik.solve_batch` writes per target."""
        t = np.asarray(target, dtype=float)
        return t.reshape(t.shape[:-2] + (16,)).take(_PARAMS_OF_POSE, axis=-1)

    @property
    def exact(self) -> bool:
        return self.tolerance is None

    def kernel_of(self) -> Any:
        return pose_kernel if self.tolerance is None else pose_bounded_kernel

    def pin(self) -> Pin:
        """The target's point and rotation; a bounded goal's region reaches its box's
        half-diagonal and the norm of its rotation bounds (at most π) from them."""
        slack_p = slack_r = 0.0
        if self.tolerance is not None:
            t = np.asarray(self.tolerance, dtype=float)
            slack_p = math.hypot(*t[:3].tolist())  # (no overflow at 1e160 m)
            slack_r = min(float(np.linalg.norm(t[3:])), math.pi)
        return Pin(
            self.frame, point=self.target[:3, 3], point_slack=slack_p,
            rotation=self.target[:3, :3], rotation_slack=slack_r,
        )  # fmt: skip

    def encode(self, robot: RobotModel, q0: FloatArray | None) -> Encoded:
        f = frame_index(self, robot)
        if self.tolerance is None:  # (the per-call path of IKSolver: two slice copies; NumPy's
            # `take` there cost 1.1 µs in some processes and 15 µs in others, run after
            # another library's call, depending on where the process was loaded)
            t, par = self.target, np.empty(12)
            par[:9].reshape(3, 3)[...] = t[:3, :3]
            par[9:] = t[:3, 3]
            return Encoded(par, np.array([f], dtype=np.int64), 6)
        par = np.concatenate([self.params(self.target), np.asarray(self.tolerance, dtype=float)])
        return Encoded(par, np.array([f], dtype=np.int64), 6)

    # ------------------------------------------------------------- the bounded form
    def offsets(self, poses: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``(e, φ)`` of poses ``(..., 4, 4)`` in the target frame: ``e = R*ᵀ(p − p*)``
        ``(..., 3)`` [m] and ``φ = log(R*ᵀ R)`` ``(..., 3)`` [rad]."""
        m = np.asarray(poses, dtype=float)
        rt = self.target[:3, :3].T
        e = (m[..., :3, 3] - self.target[:3, 3]) @ rt.T
        return e, lie.log3(rt @ m[..., :3, :3])

    def pose_errors(self, poses: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The errors judged of poses ``(..., 4, 4)``: ``(position [m], angle [rad])``, each
        ``(...)`` (with a tolerance: the norms of the parts beyond the bounds)."""
        m = np.asarray(poses, dtype=float)
        if self.tolerance is None:
            dp = np.linalg.norm(m[..., :3, 3] - self.target[:3, 3], axis=-1)
            return dp, lie.relative_angles(self.target[:3, :3], m[..., :3, :3])
        t = np.asarray(self.tolerance)
        e, phi = self.offsets(m)
        dp = np.linalg.norm(dead_zone(e, t[:3]), axis=-1)
        return dp, np.linalg.norm(dead_zone(phi, t[3:]), axis=-1)

    # ------------------------------------------------------------- numpy reference
    def residual(self, state: State) -> FloatArray:
        pose = state.pose(self.frame)
        if self.tolerance is not None:
            t = np.asarray(self.tolerance)
            e, phi = self.offsets(pose)
            return np.concatenate([dead_zone(e, t[:3]), dead_zone(phi, t[3:])])
        phi = lie.log3(self.target[:3, :3] @ pose[:3, :3].T)
        return np.concatenate([self.target[:3, 3] - pose[:3, 3], phi])

    def jacobian(self, state: State) -> FloatArray:
        pose, jac = state.pose(self.frame), state.jacobian(self.frame)
        if self.tolerance is not None:
            t = np.asarray(self.tolerance)
            e, phi = self.offsets(pose)
            rt = self.target[:3, :3].T
            out = -np.vstack([rt @ jac[:3], lie.jr_inv(phi) @ pose[:3, :3].T @ jac[3:]])
            out[3:][t[3:] >= math.pi] = 0.0  # the free axes
            return out
        phi = lie.log3(self.target[:3, :3] @ pose[:3, :3].T)
        return -np.vstack([jac[:3], lie.jr_inv(phi) @ jac[3:]])

    def errors(self, state: State) -> tuple[float, float]:
        pose = state.pose(self.frame)
        if self.tolerance is not None:
            dp_b, dr_b = self.pose_errors(pose)
            return float(dp_b), float(dr_b)
        return lie.pose_errors_one(pose, self.target)  # type: ignore[no-any-return]
