# A compiled goal (the AtHeight of docs/goals.md) as a user types it at a prompt: run as
# `python - < this file` by tests/test_goal_protocol.py (no file for numba to cache beside).
import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numba
import numpy as np

import swarm_ik
from swarm_ik.goals import Goal, Position
from swarm_ik.goals.base import Encoded, frame_index


@numba.njit
def height_rows(par, ipar, q, f_pos, f_rot, f_jac, want_jac, res, jac, err, work):  # type: ignore[no-untyped-def]
    f = ipar[0]
    res[0] = par[0] - f_pos[f, 2]
    if want_jac:
        for j in range(q.shape[0]):
            jac[0, j] = f_jac[f, 2, j]
    err[0] = abs(res[0])
    err[1] = math.nan


@dataclass(frozen=True)
class AtHeight(Goal):
    frame: str
    height: float = 0.0
    kernel: ClassVar[Any] = height_rows

    def encode(self, robot: Any, q0: Any) -> Encoded:
        ipar = np.array([frame_index(self, robot)], dtype=np.int64)
        return Encoded(np.array([float(self.height)]), ipar, 1)

    def residual(self, s: Any) -> Any:
        return np.array([self.height - s.pose(self.frame)[2, 3]])

    def jacobian(self, s: Any) -> Any:
        return -s.jacobian(self.frame)[2:3]


robot = swarm_ik.load_robot("panda")
goals = [AtHeight("panda_hand_tcp", height=0.3), Position("panda_hand_tcp", [0.5, 0.1, 0.3])]
r = swarm_ik.solve(swarm_ik.IKProblem(robot, goals=goals), seed=0)
print(r.success, r.reason)
