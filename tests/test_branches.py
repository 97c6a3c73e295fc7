"""Branches modulo 2π: periodic joints, windings, same_branch, farthest-point spread."""

import numpy as np
import pytest

import swarm_ik
from swarm_ik import branches as br
from swarm_ik.problem import largest_errors


@pytest.fixture(scope="module")
def ur5():
    return swarm_ik.load_robot("ur5")


def test_periodic_mask_ur5(ur5):
    # UR joints are revolute with ±2π limits except the elbow (±π, a range of exactly 2π)
    assert br.periodic_mask(ur5).tolist() == [True] * 6
    narrow = br.periodic_mask(ur5, ur5.lower / 2, ur5.upper / 2)
    assert narrow.tolist() == [True, True, False, True, True, True]


def test_periodic_mask_panda_none():
    assert not br.periodic_mask(swarm_ik.load_robot("panda")).any()


def test_windings_count_and_pose(ur5):
    q = np.array([0.3, -1.0, 1.2, -0.5, 1.1, 0.2])
    copies = br.windings(q, ur5.lower, ur5.upper, br.revolute_mask(ur5))
    assert copies.shape == (32, 6)  # 2 copies on each of the five ±2π joints
    assert np.all(copies >= ur5.lower) and np.all(copies <= ur5.upper)
    pose = ur5.fk_pinocchio(q)
    for c in copies[::5]:
        assert np.allclose(ur5.fk_pinocchio(c), pose, atol=1e-12)
    assert np.all(br.branch_distance(copies, q, br.periodic_mask(ur5)) < 1e-12)


def test_windings_out_of_limits_is_empty():
    z1 = swarm_ik.load_robot("z1")
    q = z1.mid_q()
    q[1] = -1.0  # joint 2 of the z1 is limited to [0, 2.97]: no 2π copy fits
    assert br.windings(q, z1.lower, z1.upper, br.revolute_mask(z1)).shape == (0, 6)


def test_nearest_winding_picks_nearest(ur5):
    q = np.array([[3.0, 0.1, 0.2, -3.0, 0.0, 6.0]])
    ref = np.zeros(6)
    out, ok = br.nearest_winding(q, ur5.lower, ur5.upper, br.revolute_mask(ur5), ref)
    assert ok.all()
    assert np.allclose(out[0], [3.0, 0.1, 0.2, -3.0, 0.0, 6.0 - 2 * np.pi])


def test_same_branch_true_for_2pi_copy_and_false_for_other_branch(ur5):
    q = np.array([0.3, -1.0, 1.2, -0.5, 1.1, 0.2])
    problem = swarm_ik.IKProblem.from_q(ur5, q)
    copy = q + np.array([2 * np.pi, 0, 0, -2 * np.pi, 0, 0])
    assert br.same_branch(problem, q, copy + 1e-7)  # polished back onto the branch
    other = swarm_ik.solve_many(problem, method="numerical", seed=0)
    far = [r.q for r in other if br.branch_distance(r.q, q, br.periodic_mask(ur5)) > 1e-3]
    assert far and not br.same_branch(problem, q, far[0])


def test_refine_reaches_roundoff(ur5):
    rng = np.random.default_rng(0)
    q = ur5.random_q(rng)
    problem = swarm_ik.IKProblem.from_q(ur5, q)
    q2, dp, dr = br.refine(problem, q + 1e-4 * rng.standard_normal(6))
    assert dp < 1e-12 and dr < 1e-12
    assert br.branch_distance(q2, q, br.periodic_mask(ur5)) < br.BRANCH_TOL


def test_spread_select_and_covering_radius():
    rng = np.random.default_rng(1)
    pool = rng.uniform(-1, 1, size=(200, 2))
    mask = np.zeros(2, bool)
    picks = br.spread_select(pool, 10, mask, np.zeros(2))
    assert len(set(picks)) == 10
    assert picks[0] == int(np.argmin(np.linalg.norm(pool, axis=1)))
    spread = br.covering_radius(pool[picks], pool, mask)
    first10 = br.covering_radius(pool[:10], pool, mask)
    assert spread < first10  # farthest-point covers better than an arbitrary subset


def test_pose_errors_match_verify(ur5):
    rng = np.random.default_rng(3)
    problem = swarm_ik.IKProblem.from_q(ur5, ur5.random_q(rng))
    qs = ur5.random_q(rng, 6)
    dp, dr = br.pose_errors(problem, qs)
    for q, a, b in zip(qs, dp, dr, strict=True):
        assert (a, b) == pytest.approx(largest_errors(swarm_ik.verify(problem, q)), abs=1e-12)
    pos = swarm_ik.IKProblem.from_q(ur5, qs[0], w_rot=0.0)  # position-only: no rotation error
    dp, dr = br.pose_errors(pos, qs)
    assert dp[0] < 1e-12 and np.all(dr == 0.0)
    assert (dp[1], dr[1]) == largest_errors(swarm_ik.verify(pos, qs[1]))


def test_compiled_fold_matches_nearest_winding(ur5):
    from swarm_ik.many import _Folder

    rng = np.random.default_rng(5)
    qs = rng.uniform(-12, 12, size=(200, 6))
    ref = rng.uniform(-3, 3, size=6)
    rev = br.revolute_mask(ur5)
    lo, hi = ur5.lower / 2, ur5.upper / 2  # narrower: some rows have no in-limit copy
    fold = _Folder(lo, hi, rev, br.periodic_mask(ur5, lo, hi), ref)
    got, ok = fold(qs)
    want, ok2 = br.nearest_winding(qs, lo, hi, rev, ref)
    assert ok.tolist() == ok2.tolist() and 0 < ok.sum() < 200
    assert np.allclose(got[ok], want[ok], atol=1e-12)
    fold.kept = want[ok][:5]
    d = fold.dist(qs)
    ref_d = br.branch_distance(qs[:, None], fold.kept[None], fold.periodic).min(axis=1)
    assert np.allclose(d, ref_d, atol=1e-12)
    # greedy new rows: copies 2π apart and exact repeats are not new
    k0, k1 = fold.kept[0], fold.kept[1]
    cand = np.vstack([k0 + 2 * np.pi * np.eye(6)[0], k0 + 0.5, k0 + 0.5, k1 + 1e-9, k0 - 0.5])
    assert fold.new(cand, 1e-6) == [1, 4]
