"""``LookAt``: a frame axis pointing at a world point."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from swarm_ik.goals.axis import FrameAxis, angle_between
from swarm_ik.goals.base import Encoded, FloatArray, Pin, State, skew

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel


@dataclass(frozen=True)
class LookAt(FrameAxis):
    """A frame axis pointing at a world point (a camera looking at a target).

    ``u = R·a``, ``d = (t − p)/‖t − p‖``, ``r = d − u``.  Error: the angle between them;
    undefined (never met) while the point is at the frame origin.

    Args:
        frame, axis: As :class:`~swarm_ik.goals.Axis` (``axis``: the viewing axis).
        point: The world point to look at [m].
        weight, primary: As :class:`~swarm_ik.goals.Goal` (keyword-only).
    """

    point: Any
    vectors: ClassVar[tuple[str, ...]] = ("point",)

    def pin(self) -> Pin:
        """The axis towards the point."""
        return Pin(self.frame, axis=self.axis, look_at=np.asarray(self.point, dtype=float))

    def encode(self, robot: RobotModel, q0: FloatArray | None) -> Encoded:
        return self._encode(robot, self.point, at_point=True)

    def _parts(self, state: State) -> tuple[FloatArray, FloatArray, float]:
        pose = state.pose(self.frame)
        e = self.point - pose[:3, 3]
        dist = max(float(np.linalg.norm(e)), 1e-9)
        return pose[:3, :3] @ self.axis, e / dist, dist

    def residual(self, state: State) -> FloatArray:
        u, d, _ = self._parts(state)
        return np.asarray(d - u)

    def jacobian(self, state: State) -> FloatArray:
        u, d, dist = self._parts(state)
        jac = state.jacobian(self.frame)
        # dd = −(I − d dᵀ)/L · dp ; du = −[u]× ω ; r = d − u
        return -(np.eye(3) - np.outer(d, d)) / dist @ jac[:3] + skew(u) @ jac[3:]

    def errors(self, state: State) -> tuple[float, float]:
        pose = state.pose(self.frame)
        return float("nan"), angle_between(pose[:3, :3] @ self.axis, self.point - pose[:3, 3])
