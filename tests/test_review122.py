"""Held-out review 122 (whole body): what it found, pinned as behaviour."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import swarm_ik
from swarm_ik.errors import InvalidArgumentError, RobotModelWarning
from swarm_ik.goals import CenterOfMass, Pose, Position

TALOS_FRAMES = ["left_sole_link", "right_sole_link", "gripper_left_base_link"]


def test_center_of_mass_refuses_fields_that_would_do_nothing() -> None:
    with pytest.raises(InvalidArgumentError, match="margin applies to a support polygon"):
        CenterOfMass(point=[0, 0, 0], margin=0.1)
    with pytest.raises(InvalidArgumentError, match="axes .* applies to a point"):
        CenterOfMass(support=[[0, 0], [1, 0], [0, 1]], axes="z")
    CenterOfMass(point=[0, 0, 1], support=[[0, 0], [1, 0], [0, 1]], axes="z", margin=0.01)


@pytest.mark.parametrize(
    "make",
    [
        lambda: Position("f", [0, 0, 0], tolerance=(0.1, 0.1, 0.1)),
        lambda: Pose("f", np.eye(4), tol=1e-3),
        lambda: CenterOfMass(point=[0, 0, 0], margn=0.1),
        lambda: Position(),
    ],
)
def test_a_goal_called_with_arguments_it_does_not_take_is_refused_by_name(make) -> None:  # type: ignore[no-untyped-def]
    """A bare ``TypeError`` before; a goals file's unknown field was already refused."""
    with pytest.raises(InvalidArgumentError, match="valid fields: .*weight, primary"):
        make()


def test_the_way_back_says_when_held_joints_differ() -> None:
    talos = swarm_ik.load_robot(
        "talos", TALOS_FRAMES, floating_base=True, locked={"torso_1_joint": 0.2}
    )
    full = talos.full_configuration(talos.mid_q())
    with warnings.catch_warnings():
        warnings.simplefilter("error", RobotModelWarning)
        np.testing.assert_allclose(talos.from_full_configuration(full), talos.mid_q(), atol=1e-12)
    joint = talos.full_model.joints[talos.full_model.getJointId("torso_1_joint")]
    full[joint.idx_q] = 0.5
    with pytest.warns(RobotModelWarning, match=r"1 joint\(s\) it does not solve \(torso_1_joint\)"):
        talos.from_full_configuration(full)


def test_a_base_rotation_vector_beyond_pi_starts_at_the_same_rotation() -> None:
    """``q0`` with the base turned 4 rad about z was clipped to π (another heading)."""
    from swarm_ik.api import prepare_q0

    talos = swarm_ik.load_robot("talos", TALOS_FRAMES, floating_base=True)
    q0 = talos.mid_q()
    k = talos.joint_names.index("root_joint.rx")
    q0[k : k + 3] = [0.0, 0.0, 4.0]
    problem = swarm_ik.IKProblem(talos, goals=[Position("left_sole_link", [0, 0.1, 0])])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # (no "clipped" warning: the rotation is in range)
        q = prepare_q0(problem, q0)
    assert q is not None
    np.testing.assert_allclose(q[k : k + 3], [0.0, 0.0, 4.0 - 2 * np.pi], atol=1e-12)


def test_a_point_beyond_a_floating_bases_box_and_reach_is_unreachable_at_once() -> None:
    """The bound was the fixed reach plus the box's three strokes (11.3 m for TIAGo's tool in
    a 3 m box): a point 2.5 m beyond the box ran the whole time limit."""
    tiago = swarm_ik.load_robot(
        "tiago_no_hand", ["arm_tool_link"], floating_base=True, base_box=3.0
    )
    far = swarm_ik.IKProblem(tiago, goals=[Position("arm_tool_link", [5.5, 0, 0.8])])
    res = swarm_ik.solve(far, time_limit=2.0)
    from swarm_ik.api import UNREACHABLE_BUDGET

    assert res.reason == "unreachable" and res.n_evals <= UNREACHABLE_BUDGET[1]  # (not 2 s)
    near = swarm_ik.IKProblem(tiago, goals=[Position("arm_tool_link", [4.5, 0, 0.8])])
    assert swarm_ik.solve(near, time_limit=2.0).success


def test_locked_joints_as_bytes_are_refused_in_words() -> None:
    with pytest.raises(InvalidArgumentError, match="list of joint names"):
        swarm_ik.load_robot("talos", TALOS_FRAMES, locked=b"torso_1_joint")
