"""solve_many at a straight UR wrist (q5 = 0 or π: a continuum of solutions, where eaik returns
only least-squares points): the auto method never returns fewer solutions than the numerical
one, and nothing it returns misses the pose."""

import numpy as np
import pytest

import swarm_ik
from swarm_ik import branches as br

pytest.importorskip("eaik")

REVIEW_Q = [1.34, 2.884, 0.274, 5.467, 0.0, -6.249]


def straight_wrist_qs(robot, k=3, seed=1):
    """The held-out review's q and ``k`` seeded random ones with q5 = 0 or π."""
    rng = np.random.default_rng(seed)
    qs = [np.array(REVIEW_Q)]
    for i, q in enumerate(robot.random_q(rng, k)):
        q[4] = (0.0, np.pi)[i % 2]
        qs.append(np.clip(q, robot.lower, robot.upper))
    return qs


def _qs(results):
    return np.array([r.q for r in results]).reshape(-1, 6)


@pytest.mark.parametrize("name", ["ur5", "ur10"])
def test_auto_never_fewer_than_numerical_at_straight_wrist(name):
    robot = swarm_ik.load_robot(name)
    wrap = br.revolute_mask(robot)
    for q in straight_wrist_qs(robot):
        problem = swarm_ik.IKProblem.from_q(robot, q)
        auto = swarm_ik.solve_many(problem, n=16, seed=0)
        num = swarm_ik.solve_many(problem, n=16, method="numerical", seed=0)
        assert len(num) >= 1 and len(auto) >= len(num)
        assert all(r.success for r in auto)
        for r in auto:  # every one meets the pose, checked with Pinocchio directly
            np.testing.assert_allclose(robot.fk_pinocchio(r.q), problem.target, atol=1e-9)
        qa = _qs(auto)
        d = br.branch_distance(_qs(num)[:, None], qa[None], wrap)
        assert (d < br.BRANCH_TOL).any(axis=1).all()  # the numerical set is within auto's
        d = br.branch_distance(qa[:, None], qa[None], wrap)  # no duplicates modulo 2π
        assert np.min(d[~np.eye(len(auto), dtype=bool)], initial=np.inf) > br.BRANCH_TOL
        # nearest to the reference (the middle of the ranges) first
        ref = 0.5 * (problem.lower + problem.upper)
        dist = br.branch_distance(qa, ref, br.periodic_mask(robot))
        assert np.all(np.diff(dist) >= 0)
        assert {r.solver for r in auto} <= {"analytic", "swarm"}


def test_review_target_every_method_finds_solutions():
    robot = swarm_ik.load_robot("ur5")
    problem = swarm_ik.IKProblem.from_q(robot, REVIEW_Q)
    closed = swarm_ik.solve_many(problem, method="analytic")
    assert closed and all(r.solver == "analytic" and r.success for r in closed)
    auto = swarm_ik.solve_many(problem, n=4)
    assert len(auto) == 4 and all(r.success for r in auto)


def test_straight_wrist_fallback_obeys_budget_and_min_distance():
    robot = swarm_ik.load_robot("ur5")
    problem = swarm_ik.IKProblem.from_q(robot, REVIEW_Q)
    sols = swarm_ik.solve_many(problem, max_evals=400, seed=0)
    assert sols and all(r.n_evals <= 400 for r in sols)
    sols = swarm_ik.solve_many(problem, min_distance=0.5, seed=0)
    qs = _qs(sols)
    d = br.branch_distance(qs[:, None], qs[None], br.periodic_mask(robot))
    assert np.min(d[~np.eye(len(sols), dtype=bool)], initial=np.inf) >= 0.5


def test_generic_and_straight_elbow_targets_stay_closed_form():
    """No numerical fallback where the closed form is not known to miss solutions (a generic
    target; a straight elbow, where two branches meet at one double root)."""
    robot = swarm_ik.load_robot("ur5")
    for q in ([0.3, -1.0, 1.2, -0.5, 1.1, 0.2], [0.3, -1.0, 0.0, -0.5, 1.1, 0.2]):
        sols = swarm_ik.solve_many(swarm_ik.IKProblem.from_q(robot, q))
        assert sols and all(r.solver == "analytic" for r in sols)


@pytest.mark.parametrize("eps", [1e-9, 1e-7])
def test_auto_covers_numerical_near_straight_wrist(eps):
    robot = swarm_ik.load_robot("ur5")
    wrap = br.revolute_mask(robot)
    for q in robot.random_q(np.random.default_rng(21), 2):
        q[4] = eps
        problem = swarm_ik.IKProblem.from_q(robot, q)
        auto = swarm_ik.solve_many(problem, n=16, seed=0)
        num = swarm_ik.solve_many(problem, n=16, method="numerical", seed=0)
        assert auto and len(auto) >= len(num) and all(r.success for r in auto)
        if num:
            d = br.branch_distance(_qs(num)[:, None], _qs(auto)[None], wrap)
            assert (d < br.BRANCH_TOL).any(axis=1).all()
