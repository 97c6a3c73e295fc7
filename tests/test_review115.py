"""Review 115 (held out: a roboticist's own URDFs): an unexpanded xacro file is refused by the
API as by the command line (its macros' links and joints were dropped in silence); a
``<limit>`` without ``lower``/``upper`` warns that URDF's default holds the joint still; the
default frame warns where it stops before mimic joints the model refuses; a joint that
mimics itself is named so."""

from __future__ import annotations

from pathlib import Path

import pytest

import swarm_ik
from swarm_ik.errors import RobotModelError, RobotModelWarning

LIMIT = '<limit lower="-2" upper="2" effort="1" velocity="1"/>'


def _arm(tmp_path: Path, extra: dict[int, str] | None = None, limits: dict[int, str] | None = None,
         head: str = '<robot name="r">', name: str = "arm.urdf") -> Path:  # fmt: skip
    """A six-joint arm l0 … l6; ``extra[k]``: more XML inside joint k; ``limits[k]``: its
    ``<limit>`` element instead of the default."""
    links = "".join(f'<link name="l{k}"/>' for k in range(7))
    joints = "".join(
        f'<joint name="j{k}" type="revolute"><parent link="l{k - 1}"/><child link="l{k}"/>'
        f'<origin xyz="0.05 0.02 0.1"/><axis xyz="{"0 0 1" if k % 2 else "0 1 0"}"/>'
        f"{(limits or {}).get(k, LIMIT)}{(extra or {}).get(k, '')}</joint>"
        for k in range(1, 7)
    )
    path = tmp_path / name
    path.write_text(f'<?xml version="1.0"?>{head}{links}{joints}</robot>')
    return path


def test_an_unexpanded_xacro_file_is_refused_by_the_api(tmp_path: Path) -> None:
    head = '<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">'
    macro = head + '<xacro:property name="L" value="0.3"/>'
    with pytest.raises(RobotModelError, match=r"a xacro file \(<xacro:property>\).*expanded"):
        swarm_ik.load_robot(_arm(tmp_path, head=macro, name="m.urdf"))
    expr = _arm(tmp_path, extra={3: '<dynamics damping="${d}"/>'}, name="e.urdf")
    with pytest.raises(RobotModelError, match=r"a xacro file \(\$\{\.\.\.\}\)"):
        swarm_ik.load_robot(expr)
    assert swarm_ik.load_robot(_arm(tmp_path)).nq == 6  # (the plain file loads)


def test_a_limit_without_lower_and_upper_warns_that_it_holds_the_joint(tmp_path: Path) -> None:
    path = _arm(tmp_path, limits={2: '<limit effort="1" velocity="1"/>'})
    with pytest.warns(RobotModelWarning, match="'j2' has a <limit> without lower and upper"):
        robot = swarm_ik.load_robot(path)
    assert robot.lower[1] == robot.upper[1] == 0.0  # (URDF's default, as Pinocchio reads it)


def test_the_default_frame_says_where_refused_mimic_joints_cut_the_arm(tmp_path: Path) -> None:
    """j4 mimics j3 and j5 mimics j4 (a chain of mimic joints, refused): the default frame was
    the tip of j1 … j2 without a word, a six-joint arm solved as two joints."""
    path = _arm(tmp_path, extra={4: '<mimic joint="j3"/>', 5: '<mimic joint="j4"/>'})
    with pytest.warns(RobotModelWarning, match="stops before joint 'j3'.*'l6', 6 joints"):
        robot = swarm_ik.load_robot(path)
    assert robot.nq == 2
    with pytest.raises(RobotModelError, match="'j5' mimics 'j4', itself a mimic joint"):
        swarm_ik.load_robot(path, "l6")


def test_a_joint_that_mimics_itself_is_named_so(tmp_path: Path) -> None:
    path = _arm(tmp_path, extra={4: '<mimic joint="j4"/>'})
    with pytest.raises(RobotModelError, match="'j4' mimics itself"):
        swarm_ik.load_robot(path, "l6")
