"""Held-out review 124 (a goal of one's own against the protocol): what it found, pinned as
behaviour."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest

import swarm_ik
from swarm_ik.errors import GoalWarning, InvalidArgumentError
from swarm_ik.goals import Goal, Position


def _z_angle(scale: float) -> Any:
    """A goal class (one per call: a class is checked once per robot): the tool's z axis at
    ``angle`` from the world's, its Jacobian multiplied by ``scale``."""

    @dataclass(frozen=True)
    class ZAngle(Goal):
        frame: str
        angle: float = 0.5

        def residual(self, state: Any) -> np.ndarray:
            return np.array([state.pose(self.frame)[2, 2] - math.cos(self.angle)])

        def jacobian(self, state: Any) -> np.ndarray:
            z = state.pose(self.frame)[:3, 2]
            dz = np.cross(state.jacobian(self.frame)[3:].T, z).T  # (dz/dq = ω × z)
            return np.asarray(scale * dz[2][None])

    return ZAngle


@pytest.mark.parametrize("scale", [0.5, 10.0, 180 / math.pi])
def test_a_jacobian_off_by_a_factor_is_accepted_with_a_warning(scale: float) -> None:
    """A Jacobian of the right sign but half or ten times the derivative (or in degrees) was
    accepted without a word and met none of ten UR5 targets (every solve ended "budget")."""
    robot = swarm_ik.load_robot("ur5")
    with pytest.warns(GoalWarning, match=f"looks {scale:.3g} times the residual's derivative"):
        swarm_ik.IKProblem(robot, goals=[_z_angle(scale)("tool0")])


def test_an_exact_jacobian_draws_no_warning_and_solves() -> None:
    robot = swarm_ik.load_robot("ur5")
    q = robot.random_q(np.random.default_rng(3))
    angle = math.acos(float(robot.fk_pinocchio(q)[2, 2]))
    with warnings.catch_warnings():
        warnings.simplefilter("error", GoalWarning)
        problem = swarm_ik.IKProblem(robot, goals=[_z_angle(1.0)("tool0", angle)])
    res = swarm_ik.solve(problem, seed=0, max_evals=3000)
    assert res.success
    assert abs(robot.fk_pinocchio(res.q)[2, 2] - math.cos(angle)) < 1e-5


@dataclass(frozen=True)
class _Height(Goal):
    """``1e200·(z − h)``: finite everywhere, its squares not."""

    frame: str
    height: float = 0.3

    def residual(self, state: Any) -> np.ndarray:
        return np.array([1e200 * (state.pose(self.frame)[2, 3] - self.height)])

    def jacobian(self, state: Any) -> np.ndarray:
        return np.asarray(1e200 * state.jacobian(self.frame)[2:3])


@pytest.mark.parametrize("solver", ["swarm", "hlfoa"])
def test_rows_whose_squares_overflow_are_refused_by_their_size(solver: str) -> None:
    """Rows of 1e200 (finite) overflowed the polish's ``JᵀJ``: numpy's overflow warnings
    leaked, and the goal was blamed for NaN values at a NaN ``q`` of the solver's making."""
    robot = swarm_ik.load_robot("ur5")
    problem = swarm_ik.IKProblem(
        robot, goals=[_Height("tool0"), Position("tool0", [0.3, 0.2, 0.3])]
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        with pytest.raises(InvalidArgumentError, match=r"_Height\(tool0\): its weighted rows"):
            swarm_ik.solve(problem, solver, seed=0, time_limit=0.2)
