"""Review 133 (whole-body goals as a user writes them): a support polygon of many vertices is
refused at once, huge bounds and margins give answers rather than overflows, and a locked
joint is named as locked."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import swarm_ik
from swarm_ik.errors import InvalidArgumentError
from swarm_ik.goals import CenterOfMass, JointValue, Pose
from swarm_ik.goals.center_of_mass import MAX_SUPPORT_VERTICES


def _disc(n: int) -> np.ndarray:
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[0.2 * np.cos(a), 0.2 * np.sin(a)]


def test_a_polygon_of_too_many_vertices_is_refused_and_one_within_the_cap_is_checked() -> None:
    goal = CenterOfMass(support=_disc(MAX_SUPPORT_VERTICES), margin=0.05)
    assert goal.support.shape == (MAX_SUPPORT_VERTICES, 2)
    with pytest.raises(InvalidArgumentError, match="vertices, more than"):
        CenterOfMass(support=_disc(10_000))
    bow_tie = np.r_[_disc(40)[:20], _disc(40)[20:][::-1]]  # (the second half reversed)
    with pytest.raises(InvalidArgumentError, match="self-intersecting"):
        CenterOfMass(support=bow_tie)
    with pytest.raises(InvalidArgumentError, match="repeats vertex"):
        CenterOfMass(support=np.r_[_disc(12), _disc(12)[3:4]])


@pytest.fixture(scope="module")
def talos() -> swarm_ik.RobotModel:
    return swarm_ik.load_robot(
        "talos", ["left_sole_link"], floating_base=True, locked=["torso_1_joint"]
    )


def test_huge_position_bounds_and_margins_give_answers_not_overflows(talos) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for big in (1e160, 1e300):
            goal = Pose("left_sole_link", np.eye(4), tolerance=(big, big, big, 0, 0, 0))
            res = swarm_ik.solve(swarm_ik.IKProblem(talos, goals=[goal]), time_limit=0.3)
            assert res.success, res.reason
        com = CenterOfMass(support=[[0, 0], [1, 0], [0, 1]], margin=1e300)
        res = swarm_ik.solve(swarm_ik.IKProblem(talos, goals=[com]), time_limit=0.2)
        assert not res.success and res.reason == "unreachable"


def test_a_locked_joint_is_named_as_locked(talos) -> None:
    with pytest.raises(InvalidArgumentError, match="torso_1_joint.*locked"):
        swarm_ik.IKProblem(talos, goals=[JointValue("torso_1_joint", 0.2)])
    with pytest.raises(InvalidArgumentError, match="floating base"):
        swarm_ik.load_robot(
            "talos", ["left_sole_link"], floating_base=True, locked={"root_joint": 0.0}
        )
