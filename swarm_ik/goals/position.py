"""``Position``: a frame origin at a world point."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numba
import numpy as np

from swarm_ik.goals.base import Encoded, FloatArray, Goal, State, frame_index
from swarm_ik.kernels.rows import position_rows

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel


@numba.njit(cache=True)
def position_kernel(par, ipar, q, f_pos, f_rot, f_jac, want_jac, res, jac, err, work):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Rows ``p* − p`` of frame ``ipar[0]``; ``par = p*`` (3)."""
    err[0] = position_rows(par, ipar[0], f_pos, f_jac, want_jac, res, jac)
    err[1] = np.nan


@dataclass(frozen=True)
class Position(Goal):
    """The frame origin at a world point: ``r = p* − p`` [m].

    Args:
        frame: Goal frame name.
        point: World point [m], 3 numbers.
        weight, primary: As :class:`~swarm_ik.goals.Goal` (keyword-only).
    """

    frame: str
    point: Any
    kernel: ClassVar[Any] = position_kernel
    vectors: ClassVar[tuple[str, ...]] = ("point",)

    @staticmethod
    def params(target: FloatArray) -> FloatArray:
        """The float parameters of a target pose ``(4, 4)`` (its position) or ``(N, 4, 4)``."""
        return np.asarray(target, dtype=float)[..., :3, 3].copy()

    def encode(self, robot: RobotModel, q0: FloatArray | None) -> Encoded:
        ipar = np.array([frame_index(self, robot)], dtype=np.int64)
        return Encoded(np.array(self.point, dtype=float), ipar, 3)

    def residual(self, state: State) -> FloatArray:
        return np.asarray(self.point - state.pose(self.frame)[:3, 3])

    def jacobian(self, state: State) -> FloatArray:
        return -state.jacobian(self.frame)[:3]

    def errors(self, state: State) -> tuple[float, float]:
        return float(np.linalg.norm(self.residual(state))), float("nan")
