"""``--floating-base``, ``--base-box`` and ``--lock`` on the command line (their bad values are
in ``tests/test_robustness.py``, with the command line's other errors), the whole-body goals
in a ``--goals`` file, and the whole URDF's configuration in the JSON report."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from conftest import FROM_Q, cli_error, cli_json

import swarm_ik

TALOS = [
    "--robot", "talos", "--frame", "left_sole_link", "--frame", "right_sole_link",
    "--frame", "gripper_left_base_link", "--floating-base",
]  # fmt: skip
SUPPORT = [[-0.1, -0.15], [0.1, -0.15], [0.1, 0.15], [-0.1, 0.15]]


def _goals_file(tmp_path: Path) -> str:
    goals = [
        {"type": "Pose", "frame": "left_sole_link", "target": [0, 0.085, 0, 0, 0, 0, 1]},
        {"type": "Pose", "frame": "right_sole_link", "target": [0, -0.085, 0, 0, 0, 0, 1]},
        {"type": "Position", "frame": "gripper_left_base_link", "point": [0.35, 0.3, 0.9]},
        {"type": "CenterOfMass", "support": SUPPORT, "margin": 0.01},
    ]
    path = tmp_path / "goals.json"
    path.write_text(json.dumps(goals))
    return str(path)


def test_humanoid_goals_file_solved_and_checkable_with_pinocchio_alone(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = cli_json(
        capsys, "solve", *TALOS, "--lock", "torso_1_joint=0.05", "--lock", "torso_2_joint",
        "--goals", _goals_file(tmp_path), "--time-limit", "2",
    )  # fmt: skip
    assert out["joint_names"][:6] == list(swarm_ik.robot.FREE_FLYER_ENTRIES)
    assert "torso_1_joint" not in out["joint_names"]
    # the check a user makes with nothing but Pinocchio
    path = swarm_ik.robot.resolve_robot_path("talos")[0]
    model = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    q = np.array(out["full_configuration"])
    assert q.shape == (model.nq,)
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    left = data.oMf[model.getFrameId("left_sole_link")]
    np.testing.assert_allclose(left.translation, [0, 0.085, 0], atol=1e-5)
    np.testing.assert_allclose(left.rotation, np.eye(3), atol=1e-5)
    hand = data.oMf[model.getFrameId("gripper_left_base_link")].translation
    np.testing.assert_allclose(hand, [0.35, 0.3, 0.9], atol=1e-5)
    com = pin.centerOfMass(model, data, q)
    assert -0.09 - 1e-6 <= com[0] <= 0.09 + 1e-6 and -0.14 - 1e-6 <= com[1] <= 0.14 + 1e-6
    assert q[model.joints[model.getJointId("torso_1_joint")].idx_q] == 0.05
    assert q[model.joints[model.getJointId("torso_2_joint")].idx_q] == 0.0


def test_lock_on_an_arm_holds_the_joint(capsys: pytest.CaptureFixture[str]) -> None:
    q = ["0.1", "-0.5", "0.2", "-1.5", "-0.2", "1.4", "0.1"]
    robot = swarm_ik.load_robot("panda")
    pose = robot.fk(np.array(q, dtype=float))
    quat = pin.Quaternion(pose[:3, :3]).coeffs()
    target = [*map(str, pose[:3, 3]), *map(str, quat)]
    out = cli_json(
        capsys, "solve", "--robot", "panda", "--lock", "panda_joint4=-1.5", "--pose", *target
    )
    assert len(out["q"]) == 6
    model = robot.full_model
    full = np.array(out["full_configuration"])
    assert full[model.joints[model.getJointId("panda_joint4")].idx_q] == -1.5


def test_bad_whole_body_goal_in_file_exits_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "bad.json"
    path.write_text(json.dumps([{"type": "CenterOfMass", "support": [[0, 0], [1, 0]]}]))
    assert "at least 3" in cli_error(capsys, "solve", *TALOS, "--goals", str(path))


@pytest.mark.parametrize(
    ("lock", "expected"),
    [
        (
            "panda_joint4=0.5",
            "--lock panda_joint4=0.5: 0.5 is outside its limits [-3.0718, -0.0698]",
        ),
        (
            "panda_joint4",
            "--lock panda_joint4: its neutral value 0 is outside its limits [-3.0718, -0.0698]; "
            "give the value to hold: --lock panda_joint4=VALUE",
        ),
    ],
)
@pytest.mark.parametrize("command", ["solve", "batch", "reach"])
def test_lock_outside_the_limits_is_refused_in_the_words_of_the_option(
    command: str, lock: str, expected: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A ``--lock`` outside its joint's limits names the option as typed and the limits (it
    was ``locked joint 'panda_joint4': ...; give the value to hold: locked={'panda_joint4': v}``,
    the keyword of ``load_robot``)."""
    rest = {
        "solve": FROM_Q,
        "batch": ["--random", "3", "--out", str(tmp_path / "r.npz")],
        "reach": ["--out", str(tmp_path / "m.npz"), "--no-png", "--no-html"],
    }[command]
    line = cli_error(capsys, command, "--robot", "panda", "--lock", lock, *rest)
    assert line == f"swarm-ik: error: {expected}"
    assert "locked" not in line and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("value", ["nan", "inf", "-inf"])
def test_lock_with_a_value_not_finite_is_refused_when_parsed(
    value: str, capsys: pytest.CaptureFixture[str], no_robot_loading: None
) -> None:
    line = cli_error(
        capsys, "solve", "--robot", "panda", "--lock", f"panda_joint4={value}", *FROM_Q
    )
    assert "argument --lock: expected JOINT=VALUE with a finite number" in line
