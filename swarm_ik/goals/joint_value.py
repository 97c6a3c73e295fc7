"""``JointValue``: one joint at a value."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from swarm_ik.errors import InvalidArgumentError, unknown
from swarm_ik.goals.base import FloatArray
from swarm_ik.goals.joint import JointGoal

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel


@dataclass(frozen=True)
class JointValue(JointGoal):
    """One joint at a value: ``r = v − q_j``.  Primary by default.

    Args:
        joint: Joint name (one of ``robot.joint_names``).
        value: The value (rad or m).
        weight, primary: As :class:`~swarm_ik.goals.Goal` (keyword-only).
    """

    joint: str
    value: float
    primary: bool = field(default=True, kw_only=True)

    def __post_init__(self) -> None:
        if isinstance(self.value, (bool, str)):
            raise InvalidArgumentError(f"JointValue.value must be a number, got {self.value!r}")
        try:
            v = float(self.value)
        except (TypeError, ValueError):
            raise InvalidArgumentError(
                f"JointValue.value must be a number, got {self.value!r}"
            ) from None
        if not np.isfinite(v):
            raise InvalidArgumentError(f"JointValue.value must be finite, got {self.value!r}")
        object.__setattr__(self, "value", v)
        super().__post_init__()

    def describe(self) -> str:
        return f"JointValue({self.joint})"

    def reference(self, robot: RobotModel, q0: FloatArray | None) -> tuple[FloatArray, FloatArray]:
        if self.joint not in robot.joint_names:
            raise unknown("joint", self.joint, robot.joint_names)
        j = robot.joint_names.index(self.joint)
        lo, hi = float(robot.lower[j]), float(robot.upper[j])
        continuous = bool(robot.continuous_mask[j])
        if self.is_primary and not continuous and not lo - 1e-12 <= self.value <= hi + 1e-12:
            raise InvalidArgumentError(
                f"JointValue({self.joint}): {self.value:g} is outside the joint's limits "
                f"[{lo:g}, {hi:g}], so no configuration meets it (primary=False pulls the "
                "joint towards it instead)"
            )
        ref = np.zeros(robot.nq)
        ref[j] = self.value
        jw = np.zeros(robot.nq)
        jw[j] = 1.0
        return ref, jw
