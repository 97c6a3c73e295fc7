"""Review 98 (the model layer, held out): a driver's range narrowed to [0, -0.0] by a mimic
follower, text given to the compiled FK's entry points, and a link's inertial that urdfdom
could not read."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import swarm_ik
from swarm_ik.errors import InvalidArgumentError, RobotModelWarning


def test_a_pr2_finger_driver_range_of_one_point_is_sampled_and_solved() -> None:
    """pr2's finger driver is narrowed by a follower of multiplier -1 to [0, -0.0]: numpy's
    uniform refused it (``high - low < 0``), so random_q and the paper solvers raised a bare
    ValueError (the CLI: exit 3)."""
    robot = swarm_ik.load_robot("pr2", "r_gripper_l_finger_link")
    rng = np.random.default_rng(0)
    q = robot.random_q(rng, 20)
    assert all(robot.within_limits(row) for row in q)
    problem = swarm_ik.IKProblem(robot, robot.fk(q[0]))
    for solver in ("gwo", "hlfoa"):
        res = swarm_ik.solve(problem, solver, max_evals=400)
        assert res.within_limits and res.n_evals <= 400


@pytest.mark.parametrize("method", ["fk", "fk_all", "fk_jacobian"])
def test_text_given_to_the_forward_kinematics_is_refused_by_name(method: str) -> None:
    robot = swarm_ik.load_robot("panda")
    with pytest.raises(InvalidArgumentError, match="q must be real joint values.*text"):
        getattr(robot, method)(["a"] * robot.nq)


def test_a_link_whose_inertial_urdfdom_could_not_read_is_named_in_a_warning(
    tmp_path: Path,
) -> None:
    """urdfdom reports the bad mass and loads the link without one; swarm_ik kept that at
    DEBUG, and the next thing the user saw was "the URDF gives no link masses"."""
    path = tmp_path / "m.urdf"
    path.write_text(
        '<robot name="r"><link name="base"/><link name="l1"><inertial><mass value="abc"/>'
        '<inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>'
        '<link name="l2"/><joint name="j1" type="revolute"><parent link="base"/>'
        '<child link="l1"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" '
        'velocity="1"/></joint><joint name="j2" type="revolute"><parent link="l1"/>'
        '<child link="l2"/><origin xyz="0 0 0.5"/><axis xyz="1 0 0"/><limit lower="-1" '
        'upper="1" effort="1" velocity="1"/></joint></robot>'
    )
    with pytest.warns(RobotModelWarning, match=r"inertial of link 'l1'.*mass \[abc\]"):
        robot = swarm_ik.load_robot(path, "l2")
    assert robot.nq == 2
