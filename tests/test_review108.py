"""Review 108 (held out, the goal protocol on a robot of its choice): goals that ask for
values no configuration gives together are named as conflicting whatever the budget (the
answer kept, of least summed error, may be one where the squared pulls do not cancel);
``solve_path`` names such goals and calls a waypoint unreachable only where that is proven;
a Python goal cannot write into the solver's joint vector; a ``pin()`` naming a frame the
robot lacks is refused; a user's exception text is quoted from its start."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numba
import numpy as np
import pytest

import swarm_ik
from swarm_ik.goals import Goal, Pin, Position
from swarm_ik.goals.base import Encoded
from swarm_ik.kernels.lm import GOAL_SIGNATURE


@dataclass(frozen=True)
class Height(Goal):
    """The frame origin's height ``z = h`` [m] (one row)."""

    frame: str
    height: float = 0.5

    def residual(self, state: swarm_ik.goals.State) -> np.ndarray:
        return np.array([self.height - state.pose(self.frame)[2, 3]])

    def jacobian(self, state: swarm_ik.goals.State) -> np.ndarray:
        return -state.jacobian(self.frame)[2:3]


@dataclass(frozen=True)
class Writes(Height):
    """A goal that changes the state's joint vector in place."""

    def residual(self, state: swarm_ik.goals.State) -> np.ndarray:
        state.q[:] = 0.0
        return super().residual(state)


@dataclass(frozen=True)
class Typo(Height):
    """A goal whose pin names a frame the robot does not have."""

    def pin(self) -> Pin:
        return Pin(self.frame + "_typo", point=np.array([5.0, 0.0, 0.5]))


@dataclass(frozen=True)
class Raises(Height):
    """A goal whose residual raises with a long message, its point in the middle."""

    def residual(self, state: swarm_ik.goals.State) -> np.ndarray:
        raise ValueError("the residual needs a calibration table: " + "x" * 20 + " MISSING-KEY k")


@numba.njit(GOAL_SIGNATURE)
def _height_nan_kernel(par, ipar, q, f_pos, f_rot, f_jac, want_jac, res, jac, err, work):
    """The frame origin's height at ``par[0]``, NaN wherever the first joint is negative."""
    if want_jac:
        jac[0, :] = f_jac[ipar[0], 2, :]
    res[0] = par[0] - f_pos[ipar[0], 2] if q[0] >= 0.0 else math.nan
    err[0], err[1] = abs(res[0]), np.nan


@dataclass(frozen=True)
class HeightNaN(Height):
    """Height's compiled twin, with a kernel that writes NaN in half of the joint space."""

    kernel: ClassVar[Any] = _height_nan_kernel

    def encode(self, robot: swarm_ik.RobotModel, q0: Any) -> Encoded:
        frame = np.array([robot.frames.index(self.frame)], dtype=np.int64)
        return Encoded(np.array([self.height]), frame, 1)


@pytest.fixture(scope="module")
def panda() -> swarm_ik.RobotModel:
    return swarm_ik.load_robot("panda")


@pytest.mark.parametrize("max_evals", [600, 4000])
def test_two_heights_at_once_are_conflicting_goals_whatever_the_budget(panda, max_evals) -> None:
    """Every point between z = 0.3 and z = 0.9 has the same summed error (0.6 m): the answer
    kept was often an unbalanced one (budget, not conflicting_goals, more often with a larger
    budget)."""
    f = panda.ee_frame
    problem = swarm_ik.IKProblem(panda, goals=[Height(f, 0.3), Height(f, 0.9)])
    for seed in range(3):
        res = swarm_ik.solve(problem, seed=seed, max_evals=max_evals)
        assert not res.success
        assert res.reason == "conflicting_goals", (seed, res.reason, res.goal_errors)
        errors = sorted(e.position_error for e in res.goal_errors)
        assert abs(sum(errors) - 0.6) < 1e-3  # (what makes the conflict: their sum is fixed)


def test_a_path_names_conflicting_python_goals_and_proves_nothing(panda) -> None:
    f = panda.ee_frame
    goals = [[Height(f, 0.3), Height(f, 0.9)] for _ in range(2)]
    res = swarm_ik.solve_path(panda, None, goals=goals, seed=0, max_evals=3000)
    assert not res.success
    assert "pull against each other" in res.reason and "Height(" in res.reason, res.reason
    assert "unreachable" not in res.reason, res.reason  # (a search found nothing: no proof)


def test_a_waypoint_missed_without_a_proof_is_not_called_unreachable(panda) -> None:
    """A point beyond the reach is proven unreachable; one the search merely missed is 'not
    reached' (it was 'unreachable: no IK solution found')."""
    f = panda.ee_frame
    far = [[Position(f, [3.0, 0.0, 0.5])]] * 2
    assert "unreachable" in swarm_ik.solve_path(panda, None, goals=far, max_evals=2000).reason
    res = swarm_ik.solve_path(panda, None, goals=[[Height(f, 0.3), Height(f, 0.9)]] * 2)
    assert not res.success and "not reached" in res.reason, res.reason
    assert "unreachable" not in res.reason, res.reason


def test_a_goal_cannot_write_into_the_joint_vector_it_is_given(panda) -> None:
    problem = swarm_ik.IKProblem(panda, goals=[Writes(panda.ee_frame, 0.5)])
    with pytest.raises(swarm_ik.InvalidArgumentError, match="read-only"):
        swarm_ik.solve(problem, seed=0, max_evals=200)
    state = swarm_ik.goals.State(panda, panda.mid_q())
    assert not state.q.flags.writeable
    q = state.q.copy()  # (a copy is the goal's own)
    q[0] += 1e-3
    assert swarm_ik.goals.State(panda, q).q[0] == q[0]


def test_a_pin_naming_an_unknown_frame_is_refused(panda) -> None:
    problem = swarm_ik.IKProblem(panda, goals=[Typo(panda.ee_frame, 0.5)])
    with pytest.raises(swarm_ik.UnknownNameError, match="_typo"):
        swarm_ik.solve(problem, seed=0)  # (no budget: the proofs read every pin)


def test_a_users_exception_text_is_quoted_from_its_start(panda) -> None:
    problem = swarm_ik.IKProblem(panda, goals=[Raises(panda.ee_frame, 0.5)])
    with pytest.raises(swarm_ik.InvalidArgumentError) as info:
        swarm_ik.solve(problem, seed=0, max_evals=100)
    text = str(info.value)
    assert "calibration table: " + "x" * 20 + " MISSING-KEY k" in text, text
    assert "\n" not in text


def test_a_compiled_kernel_writing_nan_somewhere_is_refused(panda) -> None:
    """Its one probe (first joint positive) passed, and the search took the half of the
    joint space where the kernel writes NaN as a wall: every solve ended with its budget."""
    goal = HeightNaN(panda.ee_frame, 0.5)
    with pytest.raises(swarm_ik.InvalidArgumentError, match="NaN or infinite rows"):
        swarm_ik.solve(swarm_ik.IKProblem(panda, goals=[goal]), seed=0, max_evals=500)


def test_only_the_waypoints_proven_unreachable_are_called_so() -> None:
    """Review 112: a UR5 line leaving the workspace called every missed waypoint
    'unreachable' because its last ten are beyond the reach; those in reach that the search
    missed are 'not reached'."""
    from swarm_ik.api import reach_limit

    robot = swarm_ik.load_robot("ur5")
    rng = np.random.default_rng(1)
    for _ in range(2):
        a = robot.fk(robot.random_q(rng))
        robot.random_q(rng)
    poses = np.repeat(a[None], 30, 0)
    poses[:, :3, 3] += np.linspace(0.0, 0.8, 30)[:, None] * a[:3, 3] / np.linalg.norm(a[:3, 3])
    res = swarm_ik.solve_path(robot, poses, seed=1)
    limit = reach_limit(robot.reach_radius(robot.ee_frame), 1e-5)  # (the default tol_pos)
    far = [i for i in range(30) if np.linalg.norm(poses[i, :3, 3]) > limit]
    near_missed = [i for i in np.flatnonzero(~res.reached) if i not in far]
    assert far and near_missed, res.reason
    head = "waypoints " + ", ".join(str(i) for i in far[:10])
    assert f"{head} unreachable: " in res.reason, res.reason
    assert f"waypoints {near_missed[0]}, " in res.reason and " not reached: " in res.reason
