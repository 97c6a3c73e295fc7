"""Batched FK and Jacobian against Pinocchio, on example-robot-data arms and bundled robots."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import robot

import swarm_ik

ARMS = ["panda", "ur5", "ur10", "kinova", "xarm7", "z1", "baxter_left"]
BUNDLED = ["yumi_left", "loading_manipulator", "loading_manipulator_long"]


@pytest.mark.parametrize("name", ARMS + BUNDLED)
def test_batched_fk_matches_pinocchio(name: str) -> None:
    r = robot(name)
    rng = np.random.default_rng(0)
    q = r.random_q(rng, 40)
    poses = r.fk(q)
    assert poses.shape == (40, 4, 4)
    for i in range(40):
        np.testing.assert_allclose(poses[i], r.fk_pinocchio(q[i]), atol=1e-12, rtol=0)
    # single vector -> single pose
    np.testing.assert_allclose(r.fk(q[3]), poses[3], atol=1e-15, rtol=0)


@pytest.mark.parametrize("name", ["panda", "kinova", "loading_manipulator_long", "yumi_left"])
def test_jacobian_matches_pinocchio_and_finite_differences(name: str) -> None:
    r = robot(name)
    rng = np.random.default_rng(1)
    q = r.random_q(rng, 10)
    poses, jac = r.fk_jacobian(q)
    np.testing.assert_allclose(poses, r.fk(q), atol=1e-15)
    h = 1e-6
    for i in range(10):
        np.testing.assert_allclose(jac[i], r.jacobian_pinocchio(q[i]), atol=1e-12, rtol=0)
        # central differences: linear part from positions, angular from log of R⁺ R⁻ᵀ
        for j in range(r.nq):
            dq = np.zeros(r.nq)
            dq[j] = h
            tp, tm = r.fk(q[i] + dq), r.fk(q[i] - dq)
            v = (tp[:3, 3] - tm[:3, 3]) / (2 * h)
            import pinocchio as pin

            w = pin.log3(tp[:3, :3] @ tm[:3, :3].T) / (2 * h)
            np.testing.assert_allclose(jac[i][:3, j], v, atol=1e-7)
            np.testing.assert_allclose(jac[i][3:, j], w, atol=1e-7)


def test_joint_kinds_limits_and_continuous_conversion() -> None:
    r = robot("kinova")
    assert r.joint_kinds.count("continuous") == 3
    m = r.continuous_mask
    np.testing.assert_array_equal(r.lower[m], -np.pi)
    np.testing.assert_array_equal(r.upper[m], np.pi)
    q = r.random_q(np.random.default_rng(2))
    q_pin = r.to_pinocchio(q)
    assert q_pin.shape == (r.model.nq,) and r.model.nq == r.nq + 3
    np.testing.assert_allclose(r.from_pinocchio(q_pin), q, atol=1e-14)
    # a continuous joint turned by 2π gives the same pose
    q2 = q.copy()
    q2[np.flatnonzero(m)[0]] += 2 * np.pi
    np.testing.assert_allclose(r.fk(q2), r.fk(q), atol=1e-12)


def test_prismatic_joints_in_metres() -> None:
    r = robot("loading_manipulator_long")
    assert r.joint_kinds.count("prismatic") == 3
    q = r.mid_q()
    i = r.joint_kinds.index("prismatic")
    q2 = q.copy()
    q2[i] += 0.25
    moved = np.linalg.norm(r.fk(q2)[:3, 3] - r.fk(q)[:3, 3])
    assert moved == pytest.approx(0.25, abs=1e-12)


def test_tree_is_reduced_to_the_chain() -> None:
    r = robot("panda")
    assert r.nq == 7
    assert set(r.locked_joints) == {"panda_finger_joint1", "panda_finger_joint2"}
    assert r.ee_frame == "panda_hand_tcp"


def test_fk_refuses_wrong_shapes() -> None:
    r = robot("panda")
    with pytest.raises(swarm_ik.InvalidArgumentError, match="nq = 7"):
        r.fk(np.zeros(6))
    with pytest.raises(swarm_ik.InvalidArgumentError):
        r.fk(np.zeros((3, 8)))


@pytest.mark.parametrize("name", ["panda", "kinova"])
def test_to_pinocchio_copies_unless_asked_not_to(name: str) -> None:
    r = robot(name)
    q = r.random_q(np.random.default_rng(5))
    out = r.to_pinocchio(q)
    assert out is not q and np.array_equal(r.to_pinocchio(q, copy=False), out)
    same = r.model.nq == r.nq and not r.mimic  # panda: the same vector; kinova: (cos, sin)
    assert np.shares_memory(r.to_pinocchio(q, copy=False), q) == same
    out[:] = 0.0  # the default copy is the caller's to change
    assert np.array_equal(r.to_pinocchio(q), r.to_pinocchio(q, copy=False))
