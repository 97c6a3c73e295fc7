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


def test_fewer_goal_rows_than_joints_is_a_self_motion_not_a_crash() -> None:
    """UR5 with a point and a one-row goal written in Python (4 rows, 6 joints): the
    solutions form a self-motion, solved as for a redundant arm (the valley walk of isolated
    branches assumed a square Jacobian and raised numpy's matmul ValueError); solve_path
    over such goal lists works too.  Found by a held-out review."""
    import math
    from dataclasses import dataclass

    from swarm_ik.goals import Goal, Position

    @dataclass(frozen=True)
    class Tilt(Goal):
        """The frame's z axis within ``alpha`` [rad] of straight down (one row)."""

        frame: str
        alpha: float = 0.1

        def residual(self, state):
            c = float(np.clip(-state.pose(self.frame)[2, 2], -1.0, 1.0))
            return np.array([max(0.0, math.acos(c) - self.alpha)])

        def jacobian(self, state):
            z = state.pose(self.frame)[:3, 2]
            c = float(np.clip(-z[2], -1.0, 1.0))
            if math.acos(c) <= self.alpha:
                return np.zeros((1, state.q.shape[0]))
            dc = np.cross(z, [0.0, 0.0, -1.0]) @ state.jacobian(self.frame)[3:]
            return (-dc / max(1e-12, math.sqrt(1.0 - c * c)))[None]

    robot = swarm_ik.load_robot("ur5")
    ee = robot.frames[0]
    points = [[0.4, -0.2 + 0.04 * i, 0.3] for i in range(6)]
    prob = swarm_ik.IKProblem(robot, goals=[Position(ee, points[5]), Tilt(ee)])
    sols = swarm_ik.solve_many(prob, n=8, seed=0, max_starts=256)
    assert sols and all(r.success for r in sols)
    for r in sols:
        assert all(e.met for e in prob.verify(r.q))
    path = swarm_ik.solve_path(robot, None, goals=[[Position(ee, p), Tilt(ee)] for p in points])
    assert path.success
