"""``Pose``: a frame at a full pose."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numba
import numpy as np

from swarm_ik.goals.base import Encoded, FloatArray, Goal, State, frame_index
from swarm_ik.kernels import lie
from swarm_ik.kernels.rows import position_rows, rotation_rows
from swarm_ik.pose import as_pose

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel


@numba.njit(cache=True)
def pose_kernel(par, ipar, q, f_pos, f_rot, f_jac, want_jac, res, jac, err, work):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Rows ``[p* − p; log(R* Rᵀ)]`` of frame ``ipar[0]``; ``par = [R* row-major (9), p* (3)]``."""
    f = ipar[0]
    err[0] = position_rows(par[9:12], f, f_pos, f_jac, want_jac, res[0:3], jac[0:3])
    err[1] = rotation_rows(par[0:9], f, f_rot, f_jac, want_jac, res[3:6], jac[3:6], work)


@dataclass(frozen=True)
class Pose(Goal):
    """The frame at a full pose: ``r = [p* − p; log(R* Rᵀ)]`` (world axes; metres, radians).

    Args:
        frame: Goal frame name.
        target: ``(4, 4)`` pose [m], ``(position, quaternion xyzw)``, 7 numbers, or SE3.
        orth_tol: Tolerance on the orthonormality of the target rotation (keyword-only).
        weight, primary: As :class:`~swarm_ik.goals.Goal` (keyword-only).
    """

    frame: str
    target: Any
    orth_tol: float = field(default=1e-6, kw_only=True)
    kernel: ClassVar[Any] = pose_kernel

    def __post_init__(self) -> None:
        object.__setattr__(self, "target", as_pose(self.target, orth_tol=self.orth_tol))
        super().__post_init__()

    @classmethod
    def checked(cls, frame: str, target: FloatArray) -> Pose:
        """A Pose of a target already validated by :func:`swarm_ik.pose.as_pose`."""
        goal = object.__new__(cls)
        goal.__dict__.update(frame=frame, target=target, weight=1.0, primary=True, orth_tol=1e-6)
        return goal

    @staticmethod
    def params(target: FloatArray) -> FloatArray:
        """The float parameters of a target ``(4, 4)``, or of targets ``(N, 4, 4)`` as
        ``(N, 12)``: what :func:`swarm_ik.solve_batch` writes per target."""
        t = np.asarray(target, dtype=float)
        return np.concatenate([t[..., :3, :3].reshape(t.shape[:-2] + (9,)), t[..., :3, 3]], -1)

    def encode(self, robot: RobotModel, q0: FloatArray | None) -> Encoded:
        ipar = np.array([frame_index(self, robot)], dtype=np.int64)
        return Encoded(self.params(self.target), ipar, 6)

    def residual(self, state: State) -> FloatArray:
        pose = state.pose(self.frame)
        phi = lie.log3(self.target[:3, :3] @ pose[:3, :3].T)
        return np.concatenate([self.target[:3, 3] - pose[:3, 3], phi])

    def jacobian(self, state: State) -> FloatArray:
        pose, jac = state.pose(self.frame), state.jacobian(self.frame)
        phi = lie.log3(self.target[:3, :3] @ pose[:3, :3].T)
        return -np.vstack([jac[:3], lie.jr_inv(phi) @ jac[3:]])

    def errors(self, state: State) -> tuple[float, float]:
        pose = state.pose(self.frame)
        d = (pose[:3, 3] - self.target[:3, 3]).tolist()
        dp = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        return dp, lie.angle_between(self.target[:3, :3], pose[:3, :3])
