"""Fitness values on hand-computed cases, and pose validation."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import robot
from scipy.spatial.transform import Rotation

import swarm_ik
from swarm_ik.fitness import FITNESS, wrap_angle, zyz_euler
from swarm_ik.pose import as_pose, make_pose, matrix_to_quat, project_to_se3


def _pose(rotvec=(0, 0, 0), pos=(0, 0, 0)) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = Rotation.from_rotvec(rotvec).as_matrix()
    t[:3, 3] = pos
    return t


@pytest.mark.parametrize("name", sorted(FITNESS))
def test_fitness_zero_at_target_positive_elsewhere(name: str) -> None:
    r = robot("panda")
    rng = np.random.default_rng(0)
    q = r.random_q(rng, 5)
    for qi in q:
        prob = swarm_ik.IKProblem.from_q(r, qi, name)
        f = prob.fitness(np.vstack([qi, r.random_q(rng, 4)]))
        assert f[0] == pytest.approx(0.0, abs=1e-12)
        assert np.all(f[1:] > 1e-6)


def test_se3_known_offset() -> None:
    target = _pose()
    poses = np.stack([_pose((0, 0, 0.3), (0.03, 0.04, 0.0))])
    f = FITNESS["se3"](poses, target, w_rot=1.0)
    assert f[0] == pytest.approx(0.05 + 0.3, abs=1e-12)
    f = FITNESS["se3"](poses, target, w_rot=2.0)
    assert f[0] == pytest.approx(0.05 + 0.6, abs=1e-12)
    assert FITNESS["se3"](poses, target, w_rot=0.0)[0] == pytest.approx(0.05, abs=1e-12)


def test_se3_rotation_angle_is_accurate_near_zero_and_pi() -> None:
    target = _pose()
    for angle in (1e-10, 1e-6, 1.0, np.pi - 1e-9):
        poses = np.stack([_pose((angle, 0, 0))])
        assert FITNESS["se3"](poses, target)[0] == pytest.approx(angle, rel=1e-7, abs=1e-15)


def test_paper_l1_known_offset_matches_paper_units() -> None:
    """λ = 10 per metre equals the paper's λ = 1e-2 per millimetre."""
    target = _pose()
    poses = np.stack([_pose((0, 0, 0), (0.001, -0.002, 0.003))])
    f = FITNESS["paper-l1"](poses, target)
    assert f[0] == pytest.approx(1e-2 * (1 + 2 + 3), abs=1e-12)  # mm with 1e-2
    rot = _pose((0, 0, 0.1))
    f = FITNESS["paper-l1"](np.stack([rot]), target)
    c, s = np.cos(0.1), np.sin(0.1)
    assert f[0] == pytest.approx(2 * (1 - c) + 2 * s, abs=1e-12)


def test_euler_zyz_known_offset_and_wrapping() -> None:
    target = _pose()
    target[:3, :3] = Rotation.from_euler("ZYZ", [3.1, 0.5, -3.1]).as_matrix()
    pose = np.eye(4)
    pose[:3, :3] = Rotation.from_euler("ZYZ", [-3.1, 0.5, 3.1]).as_matrix()
    pose[:3, 3] = [0.1, 0.0, -0.2]
    f = FITNESS["euler-zyz"](pose[None], target)
    # α and γ differ by 6.2 rad, i.e. 2π − 6.2 ≈ 0.0832 after wrapping
    expected = 0.3 + 2 * (2 * np.pi - 6.2)
    assert f[0] == pytest.approx(expected, abs=1e-9)
    ang = zyz_euler(target[None, :3, :3])[0]
    np.testing.assert_allclose(ang, [3.1, 0.5, -3.1], atol=1e-12)
    assert wrap_angle(np.array([np.pi + 0.1]))[0] == pytest.approx(-np.pi + 0.1)


def test_paper_pso_known_offset() -> None:
    target = _pose()
    poses = np.stack([_pose((0.2, 0, 0), (0.1, 0, 0))])
    tr = 1 + 2 * np.cos(0.2)
    assert FITNESS["paper-pso"](poses, target)[0] == pytest.approx(0.01 + (tr - 3) ** 2)


def test_pose_parsing_and_validation() -> None:
    t = make_pose([0.1, 0.2, 0.3], [0, 0, np.sin(0.25), np.cos(0.25)])
    np.testing.assert_allclose(as_pose(([0.1, 0.2, 0.3], [0, 0, np.sin(0.25), np.cos(0.25)])), t)
    np.testing.assert_allclose(as_pose(np.r_[[0.1, 0.2, 0.3], matrix_to_quat(t[:3, :3])]), t)
    with pytest.raises(swarm_ik.InvalidTargetError, match="NaN"):
        as_pose(np.full((4, 4), np.nan))
    with pytest.raises(swarm_ik.InvalidTargetError, match="shape"):
        as_pose(np.eye(3))
    bad = np.eye(4)
    bad[0, 0] = 1.001
    with pytest.raises(swarm_ik.InvalidTargetError, match="orthonormal"):
        as_pose(bad)
    as_pose(bad, orth_tol=1e-2)  # loose tolerance accepts it
    fixed = project_to_se3(bad)
    np.testing.assert_allclose(fixed[:3, :3].T @ fixed[:3, :3], np.eye(3), atol=1e-12)
    with pytest.raises(swarm_ik.InvalidTargetError, match="zero norm"):
        make_pose([0, 0, 0], [0, 0, 0, 0])


def test_paper_000_printed_target_needs_loose_tolerance() -> None:
    printed = np.array(
        [
            [-0.53812, -0.17516, 0.82447, 0.02184134],
            [0.77431, 0.28371, 0.56565, 0.07269408],
            [-0.33299, 0.94278, -0.01704, 0.23475475],
            [0, 0, 0, 1],
        ]
    )
    r = robot("yumi_left")
    with pytest.raises(swarm_ik.InvalidTargetError):
        swarm_ik.IKProblem(r, printed, "paper-l1")
    prob = swarm_ik.IKProblem(r, printed, "paper-l1", orth_tol=1e-4)
    np.testing.assert_array_equal(prob.target, printed)


def test_residual_jacobian_is_a_gauss_newton_direction() -> None:
    r = robot("panda")
    rng = np.random.default_rng(5)
    q = r.random_q(rng)
    prob = swarm_ik.IKProblem.from_q(r, q)
    q1 = q + 0.01 * rng.standard_normal(r.nq)
    f, err, jac = prob.residual_jacobian(q1[None])
    q2 = q1 + np.linalg.pinv(jac[0]) @ err[0]
    assert prob.fitness(q2[None])[0] < 1e-2 * f[0]


def test_as_pose_fast_check_accepts_only_what_the_full_check_accepts() -> None:
    """as_pose's scalar fast check of a float64 4×4 array (``clearly_pose``) passes only
    matrices the full numpy checks accept; a matrix it does not pass gets the full verdict
    (the same error or acceptance as a list of lists, which always takes the full path)."""
    from swarm_ik.pose import clearly_pose

    rng = np.random.default_rng(7)
    n_fast = 0
    for k in range(3000):
        m = make_pose(rng.normal(size=3), rng.normal(size=4))
        scale = 10.0 ** rng.uniform(-9, -4)
        m[rng.integers(0, 4), rng.integers(0, 4)] += scale * rng.normal()
        if k % 50 == 0:
            m[rng.integers(0, 4), rng.integers(0, 4)] = [np.nan, np.inf, -np.inf, 1e308][k % 4]
        fast = clearly_pose(1e-6, *m.ravel().tolist())
        n_fast += fast
        try:
            full = as_pose(m.tolist())  # nested lists: the full checks only
        except swarm_ik.InvalidTargetError as err:
            assert not fast, m
            with pytest.raises(swarm_ik.InvalidTargetError, match=str(err)[:20]):
                as_pose(m)
        else:
            np.testing.assert_array_equal(as_pose(m), full)
    assert 500 < n_fast < 3000  # both verdicts occur


def test_as_pose_accepts_a_float64_dtype_that_is_not_numpys_own_object() -> None:
    # (the fast path tests the dtype by identity: an equal copy takes the full checks)
    from swarm_ik.pose import as_pose

    t = np.eye(4)
    t[:3, 3] = (0.3, -0.2, 0.5)
    other = np.dtype("f8").newbyteorder("=")
    assert other == np.float64 and other is not np.dtype(np.float64)
    out = as_pose(t.view(other))
    assert np.array_equal(out, t) and out.dtype == np.float64


def test_a_string_where_the_goals_go_is_a_fitness_given_once() -> None:
    """A held-out review: ``goals="euler-zyz"`` silently overrode ``fitness="se3"``, and
    ``goals="Pose"`` was refused as a missing target, naming neither."""
    r = robot("panda")
    target = r.fk(r.mid_q())
    assert swarm_ik.IKProblem(r, target, "euler-zyz").fitness_name == "euler-zyz"
    assert swarm_ik.IKProblem(r, target, "euler-zyz", "euler-zyz").fitness_name == "euler-zyz"
    assert swarm_ik.IKProblem(r, target, fitness="se3").fitness_name == "se3"
    with pytest.raises(swarm_ik.InvalidArgumentError, match="two fitness names"):
        swarm_ik.IKProblem(r, target, goals="euler-zyz", fitness="se3")
    with pytest.raises(swarm_ik.InvalidArgumentError, match=r"goals must be a list.*'Pose'"):
        swarm_ik.IKProblem(r, goals="Pose")
