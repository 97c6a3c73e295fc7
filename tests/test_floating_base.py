"""Floating bases and locked joints: FK, Jacobians and the free flyer's integration against
Pinocchio; the whole-URDF configuration; locked joints held on every path; bad input refused."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import swarm_ik
from swarm_ik import goals
from swarm_ik.errors import InvalidArgumentError, UnknownNameError
from swarm_ik.kernels import lie

TALOS_FRAMES = [
    "left_sole_link",
    "right_sole_link",
    "gripper_left_base_link",
    "gripper_right_base_link",
]


@pytest.fixture(scope="module")
def talos() -> swarm_ik.RobotModel:
    return swarm_ik.load_robot(
        "talos", TALOS_FRAMES, floating_base=True, locked={"torso_1_joint": 0.1}
    )


def _full_poses(robot: swarm_ik.RobotModel, q: np.ndarray) -> np.ndarray:
    """Poses of the goal frames through Pinocchio on the WHOLE URDF model."""
    full = robot.full_model
    data = full.createData()
    pin.framesForwardKinematics(full, data, robot.full_configuration(q))
    return np.array([data.oMf[full.getFrameId(f)].homogeneous for f in robot.frames])


def test_floating_base_adds_six_entries_first(talos: swarm_ik.RobotModel) -> None:
    assert talos.floating_base
    assert talos.joint_names[:6] == swarm_ik.robot.FREE_FLYER_ENTRIES
    assert talos.joint_kinds[:6] == ("prismatic",) * 3 + ("ball",) * 3
    assert "torso_1_joint" not in talos.joint_names
    assert talos.full_model.joints[1].shortname() == "JointModelFreeFlyer"
    np.testing.assert_allclose(talos.lower[3:6], -np.pi)
    np.testing.assert_allclose(talos.upper[:3], 2.0)


@pytest.mark.parametrize("floating", [False, True])
def test_fk_and_jacobian_match_pinocchio_and_finite_differences(floating: bool) -> None:
    robot = swarm_ik.load_robot("talos", TALOS_FRAMES, floating_base=floating)
    rng = np.random.default_rng(3)
    for _ in range(4):
        q = robot.random_q(rng)
        poses = robot.fk_all(q)
        np.testing.assert_allclose(poses, robot.fk_pinocchio_all(q), atol=1e-12)
        np.testing.assert_allclose(poses, _full_poses(robot, q), atol=1e-12)
        for i, frame in enumerate(robot.frames):
            _, jac = robot.fk_jacobian(q, frame)
            np.testing.assert_allclose(jac, robot.jacobian_pinocchio(q, frame), atol=1e-12)
            h = 1e-6
            num = np.zeros_like(jac)
            for k in range(robot.nq):
                dq = np.zeros(robot.nq)
                dq[k] = h
                ta, tb = robot.fk(q + dq, frame), robot.fk(q - dq, frame)
                num[:3, k] = (ta[:3, 3] - tb[:3, 3]) / (2 * h)
                w = (ta[:3, :3] - tb[:3, :3]) / (2 * h) @ poses[i][:3, :3].T
                num[3:, k] = [w[2, 1], w[0, 2], w[1, 0]]
            np.testing.assert_allclose(jac, num, atol=1e-7)


def test_free_flyer_step_is_pinocchio_integrate(talos: swarm_ik.RobotModel) -> None:
    """A step δ of (p, r) is the free flyer's motion v = (Rᵀ δp, Jr(r) δr) on SE(3):
    ``full_configuration(q + δ)`` agrees with ``pinocchio.integrate`` to second order."""
    rng = np.random.default_rng(5)
    q = talos.random_q(rng)
    full = talos.full_model
    for scale in (1e-3, 1e-4):
        d = np.zeros(talos.nq)
        d[:6] = scale * rng.standard_normal(6)
        rot = lie.exp3(q[3:6])
        v = np.zeros(full.nv)
        v[0:3] = rot.T @ d[0:3]
        v[3:6] = lie.jr(q[3:6]) @ d[3:6]
        want = pin.integrate(full, talos.full_configuration(q), v)
        got = talos.full_configuration(q + d)
        if want[6] * got[6] < 0:  # q and −q are the same rotation
            want[3:7] *= -1
        assert np.abs(got - want).max() < 10 * scale**2


def test_rotation_vector_has_no_gimbal_lock(talos: swarm_ik.RobotModel) -> None:
    """Pitch at ±90° (where Euler angles lock) keeps three independent rotation columns."""
    q = talos.mid_q()
    q[3:6] = [0.0, np.pi / 2, 0.0]
    _, jac = talos.fk_jacobian(q, "left_sole_link")
    assert np.linalg.matrix_rank(jac[3:, 3:6], tol=1e-6) == 3


def test_full_configuration_round_trip_and_held_values(talos: swarm_ik.RobotModel) -> None:
    rng = np.random.default_rng(7)
    q = talos.random_q(rng)
    qf = talos.full_configuration(q)
    assert qf.shape == (talos.full_model.nq,)
    np.testing.assert_allclose(np.linalg.norm(qf[3:7]), 1.0)
    np.testing.assert_allclose(talos.from_full_configuration(qf), q, atol=1e-12)
    torso = talos.full_model.joints[talos.full_model.getJointId("torso_1_joint")]
    assert qf[torso.idx_q] == 0.1
    head = talos.full_model.joints[talos.full_model.getJointId("head_1_joint")]
    assert qf[head.idx_q] == 0.0  # off every path: neutral


def test_random_q_draws_any_orientation_within_bounds(talos: swarm_ik.RobotModel) -> None:
    qs = talos.random_q(np.random.default_rng(0), 2000)
    assert np.all(qs >= talos.lower) and np.all(qs <= talos.upper)
    norms = np.linalg.norm(qs[:, 3:6], axis=1)
    assert norms.max() <= np.pi + 1e-12
    assert np.quantile(norms, 0.9) > 2.5  # uniform over SO(3): large angles are common
    np.testing.assert_allclose(talos.mid_q()[:6], 0.0)


def test_whole_body_poses_solved_on_reachable_targets(talos: swarm_ik.RobotModel) -> None:
    rng = np.random.default_rng(11)
    for k in range(5):
        q = talos.random_q(rng)
        poses = talos.fk_all(q)
        problem = swarm_ik.IKProblem(
            talos, goals=[goals.Pose(f, poses[i]) for i, f in enumerate(talos.frames)]
        )
        res = swarm_ik.solve(problem, seed=k, time_limit=1.0)
        assert res.success, res.reason
        np.testing.assert_allclose(_full_poses(talos, res.q), poses, atol=1e-5)
        assert (
            talos.full_configuration(res.q)[
                talos.full_model.joints[talos.full_model.getJointId("torso_1_joint")].idx_q
            ]
            == 0.1
        )


def test_locked_joint_on_the_chain_is_held() -> None:
    robot = swarm_ik.load_robot("panda", locked={"panda_joint4": -1.5})
    assert robot.nq == 6 and "panda_joint4" not in robot.joint_names
    assert robot.held == {"panda_joint4": -1.5}
    rng = np.random.default_rng(2)
    for k in range(5):
        target = robot.fk(robot.random_q(rng))
        res = swarm_ik.solve(swarm_ik.IKProblem(robot, target), seed=k)
        assert res.success
        full = robot.full_configuration(res.q)
        j4 = robot.full_model.joints[robot.full_model.getJointId("panda_joint4")]
        assert full[j4.idx_q] == -1.5
        data = robot.full_model.createData()
        pin.framesForwardKinematics(robot.full_model, data, full)
        pose = data.oMf[robot.full_model.getFrameId(robot.ee_frame)].homogeneous
        np.testing.assert_allclose(pose, target, atol=1e-5)


def test_locked_list_holds_the_neutral_value() -> None:
    robot = swarm_ik.load_robot("panda", locked=["panda_joint1", "panda_joint7"])
    assert robot.nq == 5
    assert robot.held == {"panda_joint1": 0.0, "panda_joint7": 0.0}


@pytest.mark.parametrize(
    ("kwargs", "error", "words"),
    [
        ({"locked": {"no_such_joint": 0.0}}, UnknownNameError, "unknown joint .*panda_joint1"),
        ({"locked": {"panda_joint4": 0.5}}, InvalidArgumentError, "outside its limits"),
        ({"locked": {"panda_joint4": float("nan")}}, InvalidArgumentError, "finite"),
        ({"locked": {"panda_joint4": "a"}}, InvalidArgumentError, "finite"),
        ({"locked": 3}, InvalidArgumentError, "locked must be"),
        # held at its neutral 0, which is outside panda_joint4's limits [-3.07, -0.07]
        (
            {"locked": ["panda_joint4"]},
            InvalidArgumentError,
            "neutral value 0 is outside its limits.*give the value",
        ),
        # a mimic follower is held through its driver (panda_finger_joint2 mimics joint1)
        (
            {"locked": {"panda_finger_joint2": 0.01}},
            InvalidArgumentError,
            "mimics 'panda_finger_joint1'.*lock its driver",
        ),
        ({"floating_base": "yes"}, InvalidArgumentError, "floating_base"),
        ({"floating_base": True, "base_box": -1.0}, InvalidArgumentError, "base_box"),
        ({"floating_base": True, "base_box": [1.0, 2.0]}, InvalidArgumentError, "base_box"),
        # (review 90: a box without a floating base was dropped without a word)
        ({"base_box": (1.0, 2.0, 3.0)}, InvalidArgumentError, "give floating_base=True with it"),
    ],
)
def test_bad_input_refused(kwargs: dict, error: type, words: str) -> None:
    with pytest.raises(error, match=words):
        swarm_ik.load_robot("panda", **kwargs)


def test_every_joint_locked_is_refused() -> None:
    held = {f"panda_joint{i}": -1.0 if i == 4 else 0.0 for i in range(1, 8)}  # (in limits)
    with pytest.raises(swarm_ik.errors.RobotModelError, match="nothing to solve"):
        swarm_ik.load_robot("panda", locked=held)


def test_locked_joint_held_on_every_solve_path() -> None:
    """IKSolver, a paper solver, solve_many, solve_batch and solve_path: the locked joint is
    out of q, and every answer's whole-URDF configuration holds it at its value."""
    from swarm_ik.path import solve_path

    robot = swarm_ik.load_robot("panda", locked={"panda_joint4": -1.2})
    model = robot.full_model
    j4 = model.joints[model.getJointId("panda_joint4")].idx_q
    rng = np.random.default_rng(13)
    qs = robot.random_q(rng, 4)
    targets = robot.fk(qs)
    answers = [swarm_ik.IKSolver(robot).solve(targets[0], seed=0).q]
    answers.append(swarm_ik.solve(swarm_ik.IKProblem(robot, targets[1]), "pso", seed=0).q)
    answers += [r.q for r in swarm_ik.solve_many(swarm_ik.IKProblem(robot, targets[2]), 4)]
    answers += list(swarm_ik.solve_batch(robot, targets, seed=0).q)
    line = np.array([targets[3]] * 2)
    line[1, 2, 3] += 0.01
    answers += list(solve_path(robot, line, q0=qs[3]).q)
    for q in answers:
        assert q.shape == (6,)
        assert robot.full_configuration(q)[j4] == -1.2
