"""``Posture``: joints near a reference posture."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from swarm_ik._validate import degrees_hint, user_stacklevel
from swarm_ik.errors import GoalWarning, InvalidArgumentError
from swarm_ik.goals.base import WEIGHT_RANGE, FloatArray
from swarm_ik.goals.joint import JointGoal

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel


@dataclass(frozen=True)
class Posture(JointGoal):
    """Joints near a reference posture: ``r = w_j·(q_ref − q)`` (continuous joints wrapped).

    Secondary by default (optimised in the null space of the primary goals).

    Args:
        q_ref: Reference joint vector ``(nq,)`` (rad / m).
        joint_weights: Optional per-joint weights ``(nq,)`` (default all 1; keyword-only).
        weight, primary: As :class:`~swarm_ik.goals.Goal` (keyword-only; ``primary`` default
            False).
    """

    q_ref: Any
    joint_weights: Any = field(default=None, kw_only=True)

    def preferred_start(self, robot: RobotModel) -> Any:
        """The reference posture: a search without ``q0`` starts there."""
        return self.q_ref

    def reference(self, robot: RobotModel, q0: FloatArray | None) -> tuple[FloatArray, FloatArray]:
        ref = robot.check_q(self.q_ref, "Posture.q_ref")
        beyond = ((ref < robot.lower) | (ref > robot.upper)) & ~robot.continuous_mask
        hint = degrees_hint(ref[beyond])
        if hint:  # (review 136: degrees were solved silently)
            names = [robot.joint_names[i] for i in np.flatnonzero(beyond)]
            warnings.warn(
                f"Posture.q_ref lies outside the joint limits at {names}{hint}",
                GoalWarning,
                stacklevel=user_stacklevel(),
            )
        jw = (
            np.ones(robot.nq)
            if self.joint_weights is None
            else robot.check_q(self.joint_weights, "Posture.joint_weights")
        )
        high = WEIGHT_RANGE[1]
        if np.any(jw < 0) or np.any(jw > high):
            raise InvalidArgumentError(
                f"Posture.joint_weights must be between 0 and {high:g} (weights are relative, "
                f"as a goal's weight), got {jw.tolist()}"
            )
        return ref, jw
