"""Review 136 (a newcomer's first hour): mistakes named with what to do instead."""

from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin
import pytest

import swarm_ik
from swarm_ik.errors import GoalWarning, RobotModelError
from swarm_ik.goals import JointValue, Position, Posture


def test_an_unknown_flag_is_named_with_the_commands_help_and_a_close_flag(refused) -> None:
    line = refused("solve", "--robot", "panda", "--from-q", *["0"] * 7, "--timeout", "1")
    assert "unrecognized arguments: --timeout" in line
    assert "did you mean --time-limit?" in line and "`swarm-ik solve --help`" in line
    line = refused("solve", "--robot", "panda", "--target", "1", "2", "3")
    assert "unrecognized arguments: --target" in line and "--pose --goals --from-q" in line
    line = refused("path", "--robot", "panda", "--max-joint-step", "0.2")
    assert "did you mean --max-step?" in line and "`swarm-ik path --help`" in line


def test_a_pinocchio_quaternion_is_read_as_its_coefficients() -> None:
    robot = swarm_ik.load_robot("panda")
    rot = pin.Quaternion(pin.exp3(np.array([0.3, -0.2, 0.5])))
    problem = swarm_ik.IKProblem(robot, ([0.4, 0.1, 0.5], rot))
    np.testing.assert_allclose(problem.target[:3, :3], rot.matrix(), atol=1e-15)
    with pytest.raises(swarm_ik.InvalidTargetError) as info:
        swarm_ik.IKProblem(robot, rot)  # (a rotation alone is no pose: refused on one line)
    assert "\n" not in str(info.value)


def test_a_urdfs_own_floating_joint_names_floating_base(tmp_path) -> None:
    urdf = tmp_path / "floating.urdf"
    urdf.write_text(
        """<robot name="f"><link name="world"/><link name="base"/><link name="tool"/>
        <joint name="root" type="floating"><parent link="world"/><child link="base"/></joint>
        <joint name="j1" type="revolute"><parent link="base"/><child link="tool"/>
          <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
        </robot>"""
    )
    with pytest.raises(RobotModelError, match="floating_base=True"):
        swarm_ik.load_robot(str(urdf))


def test_degrees_given_for_radians_are_hinted() -> None:
    robot = swarm_ik.load_robot("panda")
    degrees = np.degrees(robot.mid_q()) + 20.0
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        goals = [Position(robot.ee_frame, [0.5, 0.0, 0.3]), Posture(degrees)]
        swarm_ik.solve(swarm_ik.IKProblem(robot, goals=goals), max_evals=50)
    hints = [
        w for w in seen if issubclass(w.category, GoalWarning) and "degrees?" in str(w.message)
    ]
    assert hints, [str(w.message) for w in seen]
    why = JointValue("panda_joint1", 45.0).infeasible(robot, 1e-5, 1e-5)
    assert why is not None and "degrees?" in why
    assert "degrees?" not in (JointValue("panda_joint1", 3.0).infeasible(robot, 1e-5, 1e-5) or "")
