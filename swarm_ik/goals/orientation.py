"""``Orientation``: a frame at a world orientation."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numba
import numpy as np

from swarm_ik.errors import InvalidTargetError
from swarm_ik.goals.base import Encoded, FloatArray, Goal, Pin, State, frame_index
from swarm_ik.kernels import lie
from swarm_ik.kernels.rows import rotation_rows
from swarm_ik.pose import as_pose

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel


@numba.njit(cache=True)
def orientation_kernel(par, ipar, q, f_pos, f_rot, f_jac, want_jac, res, jac, err, work):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Rows ``log(R* Rᵀ)`` of frame ``ipar[0]``; ``par = R*`` row-major (9)."""
    err[0] = np.nan
    err[1] = rotation_rows(par, ipar[0], f_rot, f_jac, want_jac, res, jac, work)


def _is_array(v: Any) -> bool:
    if getattr(getattr(v, "dtype", None), "kind", "") == "c":
        return False  # (refused by as_pose below, naming the complex values)
    try:
        np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        return False
    return True


@dataclass(frozen=True)
class Orientation(Goal):
    """The frame at a world orientation: ``r = log(R* Rᵀ)`` [rad].

    Args:
        frame: Goal frame name.
        rotation: ``(3, 3)`` rotation matrix or a quaternion ``(x, y, z, w)``.
        orth_tol: As :class:`~swarm_ik.goals.Pose` (keyword-only).
        weight, primary: As :class:`~swarm_ik.goals.Goal` (keyword-only).
    """

    frame: str
    rotation: Any
    orth_tol: float = field(default=1e-6, kw_only=True)
    kernel: ClassVar[Any] = orientation_kernel

    def __post_init__(self) -> None:
        r = np.asarray(self.rotation, dtype=float) if _is_array(self.rotation) else None
        if r is not None and r.ndim == 2 and min(r.shape) > 1 and r.shape != (3, 3):
            raise InvalidTargetError(
                f"Orientation.rotation must be a (3, 3) rotation matrix or a quaternion "
                f"(x, y, z, w), got a {r.shape[0]}×{r.shape[1]} matrix"
                + (" (a pose: use Pose, or its [:3, :3])" if r.shape == (4, 4) else "")
            )
        if r is not None and r.shape == (3, 3):
            pose = np.eye(4)
            pose[:3, :3] = r
            rot = as_pose(pose, orth_tol=self.orth_tol)[:3, :3]
        else:
            rot = as_pose((np.zeros(3), self.rotation), orth_tol=self.orth_tol)[:3, :3]
        object.__setattr__(self, "rotation", rot)
        super().__post_init__()

    def pin(self) -> Pin:
        """The rotation."""
        return Pin(self.frame, rotation=self.rotation)

    def encode(self, robot: RobotModel, q0: FloatArray | None) -> Encoded:
        ipar = np.array([frame_index(self, robot)], dtype=np.int64)
        return Encoded(np.ravel(self.rotation).astype(float), ipar, 3)

    def residual(self, state: State) -> FloatArray:
        return np.asarray(lie.log3(self.rotation @ state.pose(self.frame)[:3, :3].T))

    def jacobian(self, state: State) -> FloatArray:
        return -lie.jr_inv(self.residual(state)) @ state.jacobian(self.frame)[3:]

    def errors(self, state: State) -> tuple[float, float]:
        return float("nan"), lie.angle_between(self.rotation, state.pose(self.frame)[:3, :3])
