"""Every URDF of example-robot-data loads by name, as the README promises."""

from __future__ import annotations

import pytest

import swarm_ik
from swarm_ik.cli import main
from swarm_ik.errors import UnknownNameError
from swarm_ik.robot import EXAMPLE_ROBOTS, example_robot_files


def test_every_file_of_the_package_has_a_name() -> None:
    files = example_robot_files()
    assert {"tiago", "romeo", "solo12", "b1_z1", "go2", "pr2"} <= set(files)
    names = swarm_ik.robot_names()["example-robot-data"]
    assert set(EXAMPLE_ROBOTS) <= set(names) and set(files) <= set(names)


@pytest.mark.parametrize("name", ["tiago", "romeo", "solo12", "b1_z1"])
def test_loads_by_name_and_solves(name: str) -> None:
    robot = swarm_ik.load_robot(name)
    q = robot.mid_q()
    res = swarm_ik.solve(swarm_ik.IKProblem(robot, robot.fk(q), w_rot=0.0), seed=0)
    assert res.success


def test_humanoid_by_name_with_a_floating_base() -> None:
    robot = swarm_ik.load_robot("romeo", ["l_gripper", "r_gripper"], floating_base=True)
    assert robot.joint_names[0] == "root_joint.x"


def test_unknown_name_lists_the_package_names() -> None:
    with pytest.raises(UnknownNameError, match="tiago"):
        swarm_ik.load_robot("no_such_robot")


def test_robots_command_lists_every_name(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["robots"]) == 0
    out = capsys.readouterr().out
    for name in ("panda", "tiago", "solo12", "b1_z1"):
        assert f"  {name} " in out
