"""``RobotModel.from_full_configuration``: the inverse of ``full_configuration`` on fixed and
floating bases and continuous joints, and every bad configuration refused with one
:class:`~swarm_ik.errors.InvalidArgumentError` (wrong shape, text, complex, NaN/inf, a
quaternion or (cos, sin) pair of zero norm); a non-unit quaternion is normalised."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import swarm_ik
from swarm_ik.errors import InvalidArgumentError, SwarmIKError


@pytest.fixture(scope="module")
def panda() -> swarm_ik.RobotModel:
    return swarm_ik.load_robot("panda")


@pytest.fixture(scope="module")
def floating() -> swarm_ik.RobotModel:
    return swarm_ik.load_robot("panda", floating_base=True)


@pytest.fixture(scope="module")
def kinova() -> swarm_ik.RobotModel:
    return swarm_ik.load_robot("kinova")  # three continuous joints: (cos, sin) pairs


def test_round_trip_fixed_base(panda: swarm_ik.RobotModel) -> None:
    rng = np.random.default_rng(0)
    for _ in range(5):
        q = panda.random_q(rng)
        qf = panda.full_configuration(q)
        assert qf.shape == (panda.full_model.nq,)
        back = panda.from_full_configuration(qf)
        assert back.shape == (panda.nq,)
        np.testing.assert_array_equal(back, q)
    # a list is accepted as well as an array
    q = panda.mid_q()
    np.testing.assert_array_equal(
        panda.from_full_configuration(panda.full_configuration(q).tolist()), q
    )


def test_round_trip_floating_base(floating: swarm_ik.RobotModel) -> None:
    assert floating.floating_base
    rng = np.random.default_rng(1)
    for _ in range(5):
        q = floating.random_q(rng)
        qf = floating.full_configuration(q)
        np.testing.assert_allclose(np.linalg.norm(qf[3:7]), 1.0)
        np.testing.assert_allclose(floating.from_full_configuration(qf), q, atol=1e-12)


def test_round_trip_continuous_joints(kinova: swarm_ik.RobotModel) -> None:
    assert kinova.joint_kinds.count("continuous") == 3
    rng = np.random.default_rng(2)
    for _ in range(5):
        q = kinova.random_q(rng)
        np.testing.assert_allclose(
            kinova.from_full_configuration(kinova.full_configuration(q)), q, atol=1e-14
        )


@pytest.mark.parametrize("scale", [3.0, 0.25, -1.0, 1e-6, 1e200])
def test_non_unit_quaternion_is_normalised(floating: swarm_ik.RobotModel, scale: float) -> None:
    """Any nonzero multiple of the quaternion is the same rotation (as for targets)."""
    q = floating.random_q(np.random.default_rng(3))
    qf = floating.full_configuration(q)
    qf[3:7] *= scale
    np.testing.assert_allclose(floating.from_full_configuration(qf), q, atol=1e-12)


def test_scaled_cos_sin_pair_reads_the_same_angle(kinova: swarm_ik.RobotModel) -> None:
    q = kinova.random_q(np.random.default_rng(4))
    qf = kinova.full_configuration(q)
    j = _first_continuous(kinova)
    assert j.nq == 2
    qf[j.idx_q : j.idx_q + 2] *= 5.0
    np.testing.assert_allclose(kinova.from_full_configuration(qf), q, atol=1e-14)


def _first_continuous(robot: swarm_ik.RobotModel) -> Any:
    """The full model's joint of the robot's first continuous joint."""
    name = robot.joint_names[int(np.flatnonzero(robot.continuous_mask)[0])]
    return robot.full_model.joints[robot.full_model.getJointId(name)]


def _refused(robot: swarm_ik.RobotModel, q_full: object, match: str) -> None:
    with pytest.raises(InvalidArgumentError, match=match) as info:
        robot.from_full_configuration(q_full)
    assert isinstance(info.value, (SwarmIKError, ValueError))
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("robot_name", ["panda", "floating"])
def test_wrong_shape_refused(robot_name: str, request: pytest.FixtureRequest) -> None:
    robot: swarm_ik.RobotModel = request.getfixturevalue(robot_name)
    n = robot.full_model.nq
    qf = robot.full_configuration(robot.mid_q())
    _refused(robot, qf[:-1], rf"must hold {n} values .*got shape \({n - 1},\)")
    _refused(robot, np.append(qf, 0.0), rf"got shape \({n + 1},\)")
    _refused(robot, qf[None], rf"got shape \(1, {n}\)")
    _refused(robot, [], r"got shape \(0,\)")
    _refused(robot, 0.0, r"got shape \(\)")
    # a joint vector q given instead: the message says so
    _refused(robot, robot.mid_q(), "length of a joint vector q")


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("robot_name", ["panda", "floating"])
def test_non_finite_refused(robot_name: str, bad: float, request: pytest.FixtureRequest) -> None:
    robot: swarm_ik.RobotModel = request.getfixturevalue(robot_name)
    qf = robot.full_configuration(robot.mid_q())
    for i in (0, len(qf) - 1):  # a solved joint and the last entry (a finger, not solved)
        bad_qf = qf.copy()
        bad_qf[i] = bad
        _refused(robot, bad_qf, "NaN or infinite")


def test_not_numbers_refused(panda: swarm_ik.RobotModel) -> None:
    n = panda.full_model.nq
    qf = panda.full_configuration(panda.mid_q())
    _refused(panda, qf.astype(complex), "complex")
    _refused(panda, qf + 1e-3j, "complex")
    _refused(panda, ["a"] * n, f"must be {n} numbers")
    _refused(panda, None, "got shape")
    _refused(panda, [[0.0, 1.0], [0.0]], f"must be {n} numbers")


@pytest.mark.parametrize("norm", [0.0, 1e-12])
def test_zero_quaternion_refused(floating: swarm_ik.RobotModel, norm: float) -> None:
    """A (near) zero quaternion is no rotation: refused, not read as the identity."""
    qf = floating.full_configuration(floating.random_q(np.random.default_rng(5)))
    qf[3:7] = [0.0, 0.0, 0.0, norm]
    _refused(floating, qf, r"quaternion of root_joint \(entries 3 to 6\) has zero norm")


def test_zero_cos_sin_pair_refused(kinova: swarm_ik.RobotModel) -> None:
    qf = kinova.full_configuration(kinova.mid_q())
    j = _first_continuous(kinova)
    qf[j.idx_q : j.idx_q + 2] = 0.0
    _refused(kinova, qf, r"\(cos, sin\) pair of .* has zero norm")
