"""``CenterJoints``: joints near the middle of their ranges."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from swarm_ik.goals.base import FloatArray
from swarm_ik.goals.joint import JointGoal

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel


@dataclass(frozen=True)
class CenterJoints(JointGoal):
    """Joints near the middle of their ranges (BioIK's CenterJoints): a posture at the
    mid-range, each joint's row scaled by ``2/range`` so every joint counts alike
    (continuous joints, which have no centre, not at all).

    Args:
        weight, primary: As :class:`~swarm_ik.goals.Goal` (keyword-only; ``primary`` default
            False).
    """

    def reference(self, robot: RobotModel, q0: FloatArray | None) -> tuple[FloatArray, FloatArray]:
        width = robot.upper - robot.lower
        jw = np.where(width > 0, 2.0 / np.where(width > 0, width, 1.0), 0.0)
        jw[robot.continuous_mask] = 0.0
        return robot.mid_q(), jw
