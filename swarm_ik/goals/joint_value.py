"""``JointValue``: one joint at a value."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from swarm_ik._validate import degrees_hint
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

    def infeasible(self, robot: RobotModel, tol_pos: float, tol_rot: float) -> str | None:
        """A value beyond the joint's limits by more than ``tol_pos`` (the tolerance its error
        is judged by; continuous joints wrap: never)."""
        if self.joint not in robot.joint_names:
            return None  # (refused by name when the problem is made)
        j = robot.joint_names.index(self.joint)
        lo, hi = float(robot.lower[j]), float(robot.upper[j])
        if bool(robot.continuous_mask[j]) or lo - tol_pos <= self.value <= hi + tol_pos:
            return None
        hint = degrees_hint(self.value)  # (review 136: degrees, most likely)
        return (
            f"JointValue({self.joint}) at {self.value:g} beyond the limits [{lo:g}, {hi:g}]{hint}"
        )

    def reference(self, robot: RobotModel, q0: FloatArray | None) -> tuple[FloatArray, FloatArray]:
        if self.joint not in robot.joint_names:
            if self.joint in robot.locked_joints:  # (review 133: "unknown" misled)
                raise InvalidArgumentError(
                    f"JointValue({self.joint}): the joint is locked in this robot model (held "
                    "by locked=, or off the paths from the root to the goal frames), so no goal "
                    "can move it; load the robot without locking it"
                )
            raise unknown("joint", self.joint, robot.joint_names)
        j = robot.joint_names.index(self.joint)
        ref = np.zeros(robot.nq)
        ref[j] = self.value
        jw = np.zeros(robot.nq)
        jw[j] = 1.0
        return ref, jw
