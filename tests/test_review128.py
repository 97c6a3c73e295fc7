"""Held-out review 128 (a new user's first hour with the README and the command line): what
it found, pinned as behaviour."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import cli_error

import swarm_ik
from swarm_ik.cli import main
from swarm_ik.errors import InvalidArgumentError


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    """``swarm-ik --version`` said that a COMMAND was required."""
    with pytest.raises(SystemExit) as done:
        main(["--version"])
    assert done.value.code == 0
    assert capsys.readouterr().out.strip() == f"swarm-ik {swarm_ik.__version__}"


def test_a_missing_urdf_named_like_a_robot_points_to_the_name(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``--robot panda.urdf`` (or the README's ``robots/yumi_left.urdf`` run outside the
    clone) said only that the file was not found."""
    monkeypatch.chdir(tmp_path)
    line = cli_error(capsys, "solve", "--robot", "robots/yumi_left.urdf", "--from-q", "0")
    assert line.endswith("'yumi_left' is a robot loadable by name (--robot yumi_left)")


def test_angles_beyond_a_full_turn_ask_whether_they_are_degrees() -> None:
    robot = swarm_ik.load_robot("panda")
    problem = swarm_ik.IKProblem(robot, robot.fk(robot.mid_q()))
    with pytest.warns(UserWarning, match=r"radians and metres are expected: degrees\?"):
        swarm_ik.solve(problem, q0=np.array([30, -45, 0, -90, 0, 90, 45.0]), max_evals=50)
    with warnings.catch_warnings(record=True) as caught:  # (just beyond a limit: no hint)
        warnings.simplefilter("always")
        swarm_ik.solve(problem, q0=robot.upper + 0.1, max_evals=50)
    assert caught and all("degrees" not in str(w.message) for w in caught)
    with pytest.raises(InvalidArgumentError, match="degrees"):
        swarm_ik.load_robot("panda", locked={"panda_joint4": -90})


def test_a_five_joint_arm_that_misses_a_full_pose_points_to_position_only(
    capsys: pytest.CaptureFixture[str],
) -> None:
    rc = main(["solve", "--robot", "so101", "--pose", "0.2", "0.1", "0.15", "0", "0", "0", "1"])
    out = capsys.readouterr().out
    assert rc == 1
    assert "why: an arm of 5 joints meets few full poses" in out and "--position-only" in out
