"""``MinimalDisplacement``: joints near the start of the solve."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from swarm_ik.goals.base import FloatArray
from swarm_ik.goals.joint import JointGoal

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel


@dataclass(frozen=True)
class MinimalDisplacement(JointGoal):
    """Joints near the start ``q0`` of the solve (BioIK's MinimalDisplacement): a posture at
    ``q0`` (at the mid-range when the solve has no ``q0``).

    Args:
        weight, primary: As :class:`~swarm_ik.goals.Goal` (keyword-only; ``primary`` default
            False).
    """

    uses_start: ClassVar[bool] = True
    """Its parameters depend on the solve's start (encoded again for each ``q0``)."""

    def reference(self, robot: RobotModel, q0: FloatArray | None) -> tuple[FloatArray, FloatArray]:
        ref = robot.mid_q() if q0 is None else np.asarray(q0, dtype=float)
        return ref, np.ones(robot.nq)
