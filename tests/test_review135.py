"""Review 135 (resource limits): a Ctrl-C that a kernel loses during a paper solver's run or
``solve_many`` is counted and raised, not returned as a normal answer at the budget's end."""

from __future__ import annotations

import signal
from dataclasses import dataclass

import numpy as np
import pytest

import swarm_ik
from swarm_ik import kernels
from swarm_ik.goals import Goal, Position


@dataclass(frozen=True)
class _Lost(Goal):
    """A frame origin held at a height whose residual records the Ctrl-C handler in place and
    plays a Ctrl-C that a kernel's clock read swallowed (counted, its exception gone)."""

    frame: str = "panda_hand_tcp"
    seen: list = None  # type: ignore[assignment]

    def residual(self, state):
        self.seen.append(signal.getsignal(signal.SIGINT))
        if len(self.seen) == 20:
            kernels.SIGINTS[0] += 1  # (what counted_sigint does; the KeyboardInterrupt lost)
        return np.array([state.pose(self.frame)[2, 3] - 0.4])

    def jacobian(self, state):
        return state.jacobian(self.frame)[2:3]


@pytest.mark.parametrize("solver", ["hlfoa", "gwo"])
def test_a_paper_solver_counts_ctrl_c_and_raises_one_a_kernel_lost(solver: str) -> None:
    robot = swarm_ik.load_robot("panda")
    seen: list = []
    problem = swarm_ik.IKProblem(
        robot, goals=[Position(robot.ee_frame, [0.4, 0.1, 0.5]), _Lost(seen=seen)]
    )
    with pytest.raises(KeyboardInterrupt):
        swarm_ik.solve(problem, solver, max_evals=2000, tol_pos=1e-300, tol_rot=1e-300)
    assert kernels.counted_sigint in seen
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # (put back)
    assert kernels.SIGINTS[0] == 0


def test_solve_many_raises_a_ctrl_c_a_kernel_lost() -> None:
    robot = swarm_ik.load_robot("panda")
    seen: list = []
    problem = swarm_ik.IKProblem(
        robot, goals=[Position(robot.ee_frame, [0.4, 0.1, 0.5]), _Lost(seen=seen)]
    )
    with pytest.raises(KeyboardInterrupt):
        swarm_ik.solve_many(problem, n=64, max_evals=5000)
    assert kernels.counted_sigint in seen
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_counted_ctrl_c_never_ends_in_a_normal_return() -> None:
    with pytest.raises(KeyboardInterrupt), kernels.ctrl_c_counted(raise_at_end=True):
        kernels.SIGINTS[0] += 1  # (counted, its exception lost on the way)
    assert kernels.SIGINTS[0] == 0
