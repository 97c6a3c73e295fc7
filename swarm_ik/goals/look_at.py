"""``LookAt``: a frame axis pointing at a world point."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numba
import numpy as np

from swarm_ik.goals.axis import FrameAxis, angle_between
from swarm_ik.goals.base import Encoded, FloatArray, State, frame_index, skew
from swarm_ik.kernels.rows import direction_rows

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel


@numba.njit(cache=True)
def look_at_kernel(par, ipar, q, f_pos, f_rot, f_jac, want_jac, res, jac, err, work):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Rows ``(t − p)/‖t − p‖ − R a`` of frame ``ipar[0]``; ``par = [a (3), t (3)]``."""
    err[0] = np.nan
    err[1] = direction_rows(
        par[0:3], par[3:6], True, ipar[0], f_pos, f_rot, f_jac, want_jac, res, jac
    )


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
    kernel: ClassVar[Any] = look_at_kernel
    vectors: ClassVar[tuple[str, ...]] = ("point",)

    def encode(self, robot: RobotModel, q0: FloatArray | None) -> Encoded:
        ipar = np.array([frame_index(self, robot)], dtype=np.int64)
        return Encoded(np.concatenate([self.axis, self.point]), ipar, 3)

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
