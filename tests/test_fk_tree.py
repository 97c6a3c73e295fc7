"""Multi-frame FK and Jacobians of chains and trees against Pinocchio and finite differences."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import swarm_ik

CASES = [
    ("yumi_left", None),
    ("panda", None),
    ("kinova", None),
    ("loading_manipulator_long", None),
    ("baxter", None),
    ("talos", ["gripper_left_base_link", "gripper_right_base_link", "torso_2_link", "head_2_link"]),
]


@pytest.mark.parametrize("name,frames", CASES)
def test_every_goal_frame_matches_pinocchio(name: str, frames: list[str] | None) -> None:
    robot = swarm_ik.load_robot(name, frames)
    rng = np.random.default_rng(7)
    model, data = robot.model, robot.model.createData()
    for q in robot.random_q(rng, 20):
        q = q + rng.uniform(-0.5, 0.5, robot.nq)  # outside the limits too
        poses, jacs = robot.tree.fk_jacobian(q)
        qp = robot.to_pinocchio(q)
        pin.computeJointJacobians(model, data, qp)
        pin.updateFramePlacements(model, data)
        for f, fid in enumerate(robot.frame_ids):
            np.testing.assert_allclose(poses[f], data.oMf[fid].homogeneous, atol=1e-12)
            ref = pin.getFrameJacobian(model, data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
            np.testing.assert_allclose(
                jacs[f], robot.jacobian_pinocchio(q, robot.frames[f]), atol=1e-12
            )
            if model.nv == robot.nq:
                np.testing.assert_allclose(jacs[f], ref, atol=1e-12)


def test_batched_fk_equals_single_calls() -> None:
    robot = swarm_ik.load_robot("baxter")
    qs = robot.random_q(np.random.default_rng(0), 5)
    batch = robot.fk_all(qs)
    for k, q in enumerate(qs):
        np.testing.assert_array_equal(batch[k], robot.fk_all(q))
    np.testing.assert_array_equal(robot.fk(qs, "right_gripper"), batch[:, 1])


def test_tree_reduces_to_union_of_paths() -> None:
    both = swarm_ik.load_robot("baxter")
    left = swarm_ik.load_robot("baxter_left")
    assert both.nq == 14 and left.nq == 7
    assert set(left.joint_names) < set(both.joint_names)
    assert both.frames == ("left_gripper", "right_gripper")
    assert both.ee_frame == "left_gripper"
    # the left arm's joints move the left gripper only
    q = both.mid_q()
    jac = both.fk_jacobian(q, "left_gripper")[1]
    right_cols = [i for i, n in enumerate(both.joint_names) if n.startswith("right")]
    assert np.all(jac[:, right_cols] == 0.0)


def test_jacobian_matches_central_differences_on_a_tree() -> None:
    robot = swarm_ik.load_robot("baxter")
    rng = np.random.default_rng(1)
    q = robot.random_q(rng)
    poses, jac = robot.tree.fk_jacobian(q)
    h = 1e-6
    for i in range(robot.nq):
        dq = np.zeros(robot.nq)
        dq[i] = h
        plus, minus = robot.fk_all(q + dq), robot.fk_all(q - dq)
        for f in range(len(robot.frames)):
            v = (plus[f, :3, 3] - minus[f, :3, 3]) / (2 * h)
            w = pin.log3(plus[f, :3, :3] @ minus[f, :3, :3].T) / (2 * h)
            np.testing.assert_allclose(jac[f, :3, i], v, atol=1e-7)
            np.testing.assert_allclose(jac[f, 3:, i], w, atol=1e-7)


def test_unknown_goal_frame_lists_the_valid_ones() -> None:
    robot = swarm_ik.load_robot("baxter")
    with pytest.raises(swarm_ik.UnknownNameError, match="left_gripper"):
        robot.fk(robot.mid_q(), "tool9")
    with pytest.raises(swarm_ik.UnknownNameError, match="unknown frame"):
        swarm_ik.load_robot("panda", ["panda_hand_tcp", "nope"])


def test_mimic_follower_on_the_chain_is_driven_by_its_driver(tmp_path) -> None:
    """A mimic joint on the chain reads ``multiplier·q + offset`` of its driver: FK and the
    Jacobian (the follower's column summed into the driver's) agree with Pinocchio."""
    joint = (
        '<joint name="{n}" type="revolute"><parent link="{p}"/><child link="{c}"/>'
        '<origin xyz="0 0 0.3" rpy="0 0.4 0"/><axis xyz="{ax}"/>'
        '<limit lower="-2" upper="2" effort="1" velocity="1"/>{extra}</joint>'
    )
    urdf = (
        '<robot name="m">'
        + "".join(f'<link name="{n}"/>' for n in "abcd")
        + joint.format(n="j1", p="a", c="b", ax="0 0 1", extra="")
        + joint.format(n="j2", p="b", c="c", ax="0 1 0", extra="")
        + joint.format(
            n="j3",
            p="c",
            c="d",
            ax="1 0 0",
            extra='<mimic joint="j1" multiplier="-0.5" offset="0.2"/>',
        )
        + "</robot>"
    )
    path = tmp_path / "mimic.urdf"
    path.write_text(urdf)
    robot = swarm_ik.load_robot(path, "d")
    assert robot.nq == 2 and robot.joint_names == ("j1", "j2")
    assert robot.mimic == {"j3": ("j1", -0.5, 0.2)}
    # the follower's range [-2, 2] narrows the driver's: -0.5 q + 0.2 in [-2, 2]
    assert robot.lower[0] == pytest.approx(-2.0) and robot.upper[0] == pytest.approx(2.0)
    rng = np.random.default_rng(3)
    for q in robot.random_q(rng, 5):
        np.testing.assert_allclose(robot.fk(q[None])[0], robot.fk_pinocchio(q), atol=1e-12)
        np.testing.assert_allclose(robot.fk_jacobian(q)[1], robot.jacobian_pinocchio(q), atol=1e-12)
        qp = robot.to_pinocchio(q)
        assert qp[2] == pytest.approx(-0.5 * q[0] + 0.2)
        np.testing.assert_array_equal(robot.fk_pinocchio_bound()(q), robot.fk_pinocchio(q))
    target = robot.fk(robot.random_q(rng))
    res = swarm_ik.solve(swarm_ik.IKProblem(robot, target, w_rot=0.0), seed=0)
    assert res.success


def test_mimic_whose_driver_is_off_the_chain_is_refused(tmp_path) -> None:
    joint = (
        '<joint name="{n}" type="revolute"><parent link="{p}"/><child link="{c}"/>'
        '<origin xyz="0 0 0.3"/><axis xyz="0 0 1"/>'
        '<limit lower="-2" upper="2" effort="1" velocity="1"/>{extra}</joint>'
    )
    urdf = (
        '<robot name="m">'
        + "".join(f'<link name="{n}"/>' for n in "abcd")
        + joint.format(n="j1", p="a", c="b", extra="")
        + joint.format(n="j2", p="b", c="c", extra='<mimic joint="j3"/>')
        + joint.format(n="j3", p="a", c="d", extra="")
        + "</robot>"
    )
    path = tmp_path / "m.urdf"
    path.write_text(urdf)
    with pytest.raises(swarm_ik.RobotModelError, match="mimics joint 'j3', which is not on the"):
        swarm_ik.load_robot(path, "c")


@pytest.mark.parametrize("name", ["panda", "kinova", "baxter"])
def test_fk_pinocchio_many_is_fk_pinocchio_row_by_row(name: str) -> None:
    """The batched reference FK (used by the branch checks) equals the single one exactly,
    continuous joints included (kinova: Pinocchio's q holds (cos, sin))."""
    robot = swarm_ik.load_robot(name)
    qs = robot.random_q(np.random.default_rng(5), 6)
    many = robot.fk_pinocchio_many(qs)
    assert many.shape == (6, 4, 4)
    for q, m in zip(qs, many, strict=True):
        np.testing.assert_array_equal(m, robot.fk_pinocchio(q))
        np.testing.assert_allclose(m, robot.fk(q), atol=1e-12)
