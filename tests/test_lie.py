"""The one set of rotation helpers: compiled and numpy twins against each other and against
Pinocchio's log3 / Jlog3, near 0, generic, and near π."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from swarm_ik.kernels import lie

ANGLES = [0.0, 1e-12, 1e-7, 1e-4, 1e-3, 0.5, 2.0, np.pi - 1e-2, np.pi - 1e-4, np.pi - 1e-9, np.pi]


@pytest.mark.parametrize("theta", ANGLES)
def test_log3_angle_and_twins_agree_with_pinocchio(theta: float) -> None:
    rng = np.random.default_rng(int(theta * 1e3))
    for _ in range(5):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        m = pin.exp3(theta * axis)
        out = np.empty(3)
        t_nb = lie.log3_nb(m, out)
        t_np = float(lie.angle(m))
        v_np = lie.log3(m)
        assert t_nb == pytest.approx(theta, abs=1e-9) and t_np == pytest.approx(theta, abs=1e-9)
        assert lie.angle_nb(m) == pytest.approx(t_np, abs=1e-15)
        if theta < np.pi - 1e-6:  # at π the axis sign is arbitrary
            np.testing.assert_allclose(out, pin.log3(m), atol=1e-9)
            np.testing.assert_allclose(v_np, out, atol=1e-12)
        else:
            np.testing.assert_allclose(pin.exp3(out), m, atol=1e-9)
            np.testing.assert_allclose(pin.exp3(v_np), m, atol=1e-9)


def test_batched_numpy_log3_equals_the_compiled_one_row_by_row() -> None:
    rng = np.random.default_rng(1)
    rots = np.array([pin.exp3(rng.normal(size=3)) for _ in range(50)])
    batched = lie.log3(rots)
    for r, v in zip(rots, batched, strict=True):
        out = np.empty(3)
        lie.log3_nb(r, out)
        np.testing.assert_allclose(v, out, atol=1e-12)
    np.testing.assert_allclose(lie.angle(rots), np.linalg.norm(batched, axis=1), atol=1e-12)


@pytest.mark.parametrize("scale", [1e-6, 1e-3, 0.5, 2.0, 3.0])
def test_jr_inverse_twins_equal_pinocchio_jlog3(scale: float) -> None:
    rng = np.random.default_rng(2)
    for _ in range(5):
        phi = rng.normal(size=3)
        phi *= scale / np.linalg.norm(phi)
        out = np.empty((3, 3))
        lie.jr_inv_nb(phi, float(np.linalg.norm(phi)), out)
        np.testing.assert_allclose(out, lie.jr_inv(phi), atol=1e-12)
        np.testing.assert_allclose(out, pin.Jlog3(pin.exp3(phi)), atol=1e-9)


@pytest.mark.parametrize("theta", ANGLES)
def test_relative_angle_one_pair_equals_the_batched_one_bit_for_bit(theta: float) -> None:
    rng = np.random.default_rng(3 + int(theta * 1e3))
    r_a = np.array([pin.exp3(rng.normal(size=3)) for _ in range(20)])
    axes = rng.normal(size=(20, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    r_b = np.array([a @ pin.exp3(theta * ax) for a, ax in zip(r_a, axes, strict=True)])
    batched = lie.relative_angles(r_a, r_b)  # (one target per row, as the batch's check)
    shared = lie.relative_angles(r_a[0], r_b)  # (one target, many answers)
    for k in range(20):
        assert lie.angle_between(r_a[k], r_b[k]) == batched[k]  # the same bits
        assert lie.angle_between(r_a[0], r_b[k]) == shared[k]
        assert batched[k] == pytest.approx(theta, abs=1e-7)
        assert batched[k] == pytest.approx(float(lie.angle(r_a[k].T @ r_b[k])), abs=1e-12)
    # the judge's compiled errors of one pose: the same bits as the batched check's
    for k in range(20):
        target, pose = np.eye(4), np.eye(4)
        target[:3, :3], pose[:3, :3] = r_a[k], r_b[k]
        target[:3, 3] = rng.normal(size=3)
        pose[:3, 3] = target[:3, 3] + rng.normal(size=3) * 10.0 ** rng.uniform(-9, 0)
        dp, dr = lie.pose_errors_one(pose, target)
        assert dr == batched[k]
        assert dp == float(np.linalg.norm(pose[None, :3, 3] - target[:3, 3], axis=-1)[0])
