"""``Axis``: a frame axis along a world direction, the rotation about it free."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numba
import numpy as np

from swarm_ik.goals.base import Encoded, FloatArray, Goal, Pin, State, frame_index, skew
from swarm_ik.kernels.rows import direction_rows

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel


@numba.njit(cache=True)
def frame_axis_kernel(par, ipar, q, f_pos, f_rot, f_jac, want_jac, res, jac, err, work):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Rows ``d − R a`` of frame ``ipar[0]``; ``par = [a (3), t (3)]``, ``a`` a unit vector,
    ``d = t`` (a unit direction: :class:`Axis`) or, where ``ipar[1]`` is 1, the unit vector
    from the frame origin to the point ``t`` (:class:`~swarm_ik.goals.LookAt`)."""
    err[0] = np.nan
    err[1] = direction_rows(
        par[0:3], par[3:6], ipar[1] != 0, ipar[0], f_pos, f_rot, f_jac, want_jac, res, jac
    )


def angle_between(u: FloatArray, v: FloatArray) -> float:
    """Angle between two vectors [rad] (infinite when ``v`` is zero: undefined)."""
    if not np.linalg.norm(v) > 1e-9:
        return float("inf")
    return float(np.arctan2(np.linalg.norm(np.cross(u, v)), float(np.dot(u, v))))


@dataclass(frozen=True)
class FrameAxis(Goal):
    """Base of the goals on one axis ``a`` of a frame, the rotation about it free
    (:class:`Axis`, :class:`~swarm_ik.goals.LookAt`): its fields ``frame`` and ``axis``
    (normalised)."""

    frame: str
    axis: Any
    kernel: ClassVar[Any] = frame_axis_kernel
    units: ClassVar[tuple[str, ...]] = ("axis",)

    def _encode(self, robot: RobotModel, target: FloatArray, at_point: bool) -> Encoded:
        """``par = [axis, target]``, ``ipar = [frame, at_point]`` (:func:`frame_axis_kernel`)."""
        ipar = np.array([frame_index(self, robot), int(at_point)], dtype=np.int64)
        return Encoded(np.concatenate([self.axis, target]), ipar, 3)


@dataclass(frozen=True)
class Axis(FrameAxis):
    """A frame axis along a world direction, the rotation about it free.

    ``u = R·a`` (the frame axis ``a`` in world axes), ``r = d − u``: zero only when the axis
    points along ``d`` (not against it).  Error: the angle between ``u`` and ``d``.

    Args:
        frame: Goal frame name.
        axis: The axis in the frame's own coordinates (normalised; not zero).
        direction: The world direction (normalised; not zero).
        weight, primary: As :class:`~swarm_ik.goals.Goal` (keyword-only).
    """

    direction: Any
    units: ClassVar[tuple[str, ...]] = ("axis", "direction")

    def pin(self) -> Pin:
        """The axis along the direction."""
        return Pin(self.frame, axis=self.axis, direction=self.direction)

    def encode(self, robot: RobotModel, q0: FloatArray | None) -> Encoded:
        return self._encode(robot, self.direction, at_point=False)

    def residual(self, state: State) -> FloatArray:
        return np.asarray(self.direction - state.pose(self.frame)[:3, :3] @ self.axis)

    def jacobian(self, state: State) -> FloatArray:
        u = state.pose(self.frame)[:3, :3] @ self.axis
        # du = ω × u = −[u]× ω; r = d − u  =>  ∂r/∂q = [u]× J_ω
        return skew(u) @ state.jacobian(self.frame)[3:]

    def errors(self, state: State) -> tuple[float, float]:
        u = state.pose(self.frame)[:3, :3] @ self.axis
        return float("nan"), angle_between(u, self.direction)
