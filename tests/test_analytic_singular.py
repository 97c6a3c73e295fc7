"""Solver 'analytic' at singular targets: a straight UR wrist (q5 = 0 or π, a continuum of
solutions) where eaik returns only least-squares points, and a straight elbow (a double root)."""

import numpy as np
import pytest

import swarm_ik
from swarm_ik import branches as br
from swarm_ik.solvers import analytic

eaik = pytest.importorskip("eaik")

REVIEW_Q = [1.34, 2.884, 0.274, 5.467, 0.0, -6.249]
"""The held-out review's target: eaik gave three least-squares points, 5.6 cm off, and the
closed form nothing (solve ended 'local_minima', solve_many with 0 solutions)."""


def straight_wrist_qs(robot, k=4, seed=0):
    """The review's q and ``k`` seeded random ones with q5 = 0 or ±π (a straight wrist)."""
    rng = np.random.default_rng(seed)
    qs = [np.array(REVIEW_Q)]
    for i, q in enumerate(robot.random_q(rng, k)):
        q[4] = (0.0, np.pi, 0.0, -np.pi)[i % 4]
        qs.append(np.clip(q, robot.lower, robot.upper))
    return qs


def _check_solutions(robot, problem, qs, dp, dr):
    assert qs.shape[0] >= 1
    assert np.all(dp <= 1e-5) and np.all(dr <= 1e-5)
    assert np.all(qs >= problem.lower) and np.all(qs <= problem.upper)
    for q in qs:  # FK checked independently of the solver's own check
        np.testing.assert_allclose(robot.fk_pinocchio(q), problem.target, atol=1e-9)
    if qs.shape[0] > 1:  # no duplicates modulo 2π
        d = br.branch_distance(qs[:, None], qs[None], br.revolute_mask(robot))
        assert np.min(d[~np.eye(qs.shape[0], dtype=bool)]) > br.BRANCH_TOL


def test_review_target_eaik_gives_only_least_squares_points():
    """What eaik returns at the review's target (the cause): no exact solution at all."""
    robot = swarm_ik.load_robot("ur5")
    problem = swarm_ik.IKProblem.from_q(robot, REVIEW_Q)
    sol = analytic.analytic_chain(robot).solver.calculate_IK(problem.target)
    assert np.all(sol.is_LS)
    dp, dr = analytic.pinocchio_errors(problem, np.asarray(sol.Q))
    assert np.all((dp > 1e-3) | (dr > 1e-3))  # none of them meets the pose


@pytest.mark.parametrize("name", ["ur5", "ur10"])
def test_straight_wrist_solve_succeeds(name):
    robot = swarm_ik.load_robot(name)
    for q in straight_wrist_qs(robot):
        problem = swarm_ik.IKProblem.from_q(robot, q)
        res = swarm_ik.solve(problem, "analytic")
        assert res.success, (q, res.reason)
        assert res.reason == "converged" and res.solver == "analytic"
        np.testing.assert_allclose(robot.fk_pinocchio(res.q), problem.target, atol=1e-9)


@pytest.mark.parametrize("name", ["ur5", "ur10"])
def test_straight_wrist_set_is_verified_and_marked_incomplete(name):
    robot = swarm_ik.load_robot(name)
    for q in straight_wrist_qs(robot):
        problem = swarm_ik.IKProblem.from_q(robot, q)
        ref = 0.5 * (problem.lower + problem.upper)
        cf = analytic.closed_form_set(problem, ref, 1e-5, 1e-5)
        _check_solutions(robot, problem, cf.q, cf.position_error, cf.rotation_error)
        assert cf.incomplete  # a continuum: the set holds representatives of it, no more
        assert 0 < cf.evals <= analytic.POLISH_ITERS * 8
        # a representative of the generating configuration's continuum: its shoulder, wrist
        near = br.branch_distance(cf.q[:, [0, 4]], q[[0, 4]], np.ones(2, dtype=bool))
        assert np.min(near) < 1e-6
        qs, dp, dr = analytic.solve_all(problem)  # the same set
        np.testing.assert_array_equal(qs, cf.q)


def test_solve_at_straight_wrist_counts_the_polish():
    robot = swarm_ik.load_robot("ur5")
    problem = swarm_ik.IKProblem.from_q(robot, REVIEW_Q)
    a = swarm_ik.solve(problem, "analytic")
    assert a.success and a.reason == "converged"
    np.testing.assert_allclose(robot.fk_pinocchio(a.q), problem.target, atol=1e-9)
    assert a.n_evals > 1  # the branch verified and the polish's evaluations


def test_generic_target_is_eaiks_set_unpolished():
    robot = swarm_ik.load_robot("ur5")
    problem = swarm_ik.IKProblem.from_q(robot, [0.3, -1.0, 1.2, -0.5, 1.1, 0.2])
    cf = analytic.closed_form_set(problem, 0.5 * (problem.lower + problem.upper), 1e-5, 1e-5)
    assert cf.q.shape[0] == 8 and not cf.incomplete and cf.evals == 0


@pytest.mark.parametrize(
    "q",
    [[0.3, -1.0, 0.0, -0.5, 1.1, 0.2], [0.3, -1.0, 1e-7, -0.5, 1.1, 0.2]],
    ids=["elbow-straight", "elbow-almost-straight"],
)
def test_straight_elbow_is_no_continuum(q):
    """Two branches merge at a straight elbow (an isolated double root): eaik's exact point is
    kept, and the set is not marked incomplete."""
    robot = swarm_ik.load_robot("ur5")
    problem = swarm_ik.IKProblem.from_q(robot, q)
    cf = analytic.closed_form_set(problem, 0.5 * (problem.lower + problem.upper), 1e-5, 1e-5)
    _check_solutions(robot, problem, cf.q, cf.position_error, cf.rotation_error)
    assert not cf.incomplete
    assert swarm_ik.solve(problem, "analytic").success


def test_unreachable_pose_stays_empty_and_complete():
    robot = swarm_ik.load_robot("ur5")
    target = np.eye(4)
    target[:3, 3] = [0.1, 0.0, 0.05]  # within the reach sphere, out of reach of every branch
    problem = swarm_ik.IKProblem(robot, target)
    cf = analytic.closed_form_set(problem, 0.5 * (problem.lower + problem.upper), 1e-5, 1e-5)
    assert cf.q.shape == (0, 6) and not cf.incomplete
    res = swarm_ik.solve(problem, "analytic")
    assert not res.success


@pytest.mark.parametrize("eps", [1e-12, 1e-9, 1e-7])
def test_nearly_straight_wrist_solve_succeeds(eps):
    """Near the singularity eaik's points are the same least-squares ones, and the polish may
    stall on a valley floor above round-off but within the tolerances: still an answer."""
    robot = swarm_ik.load_robot("ur5")
    rng = np.random.default_rng(5)
    for q in [np.array(REVIEW_Q), *robot.random_q(rng, 2)]:
        q = q.copy()
        q[4] = eps
        problem = swarm_ik.IKProblem.from_q(robot, q)
        res = swarm_ik.solve(problem, "analytic")
        assert res.success and res.reason == "converged", (q, res.reason)
        np.testing.assert_allclose(robot.fk_pinocchio(res.q), problem.target, atol=1e-5)
        qs, dp, dr = analytic.solve_all(problem)
        assert qs.shape[0] >= 1 and np.all(dp <= 1e-5) and np.all(dr <= 1e-5)


def test_a_six_joint_arm_with_a_mimic_follower_takes_the_numerical_path(tmp_path) -> None:
    """UR5 with a counterweight whose joint mimics the shoulder: seven joints in its model,
    so eaik's 6R closed form does not apply; solve_many (auto) takes the numerical path (eaik
    raised 'only 1-6R robots' before) and method='analytic' is refused with the reason."""
    from pathlib import Path

    from swarm_ik.solvers.analytic import AnalyticUnsupportedError

    ur5 = swarm_ik.load_robot("ur5")
    text = Path(ur5.urdf_path).read_text()
    extra = (
        '<link name="counterweight"><inertial><mass value="2"/><origin xyz="-0.2 0 0"/>'
        '<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>'
        '<joint name="cw_joint" type="revolute"><parent link="shoulder_link"/>'
        '<child link="counterweight"/><origin xyz="0 0 0.1"/><axis xyz="0 1 0"/>'
        '<limit lower="-6.28" upper="6.28" effort="1" velocity="1"/>'
        '<mimic joint="shoulder_lift_joint" multiplier="1" offset="0"/></joint>'
    )
    path = tmp_path / "ur5_counterweight.urdf"
    path.write_text(text.replace("</robot>", extra + "</robot>"))
    robot = swarm_ik.load_robot(str(path), "tool0")
    assert robot.nq == 6 and robot.mimic
    q = np.array([0.4, -1.0, 1.2, -0.5, 1.1, 0.2])
    problem = swarm_ik.IKProblem.from_q(robot, q)
    assert "mimic" in analytic.support(problem)
    with pytest.raises(AnalyticUnsupportedError, match="mimic"):
        swarm_ik.solve_many(problem, method="analytic")
    sols = swarm_ik.solve_many(problem, n=8, seed=0, max_starts=256)
    assert sols and all(r.success and r.solver == "swarm" for r in sols)


def test_a_joint_limited_straight_wrist_is_solved_along_its_self_motion():
    """On ``ur5_joint_limited_robot`` (every joint within ±π) eaik's least-squares points at
    this straight wrist polish into no solution within the limits: solver 'analytic' ended
    'local_minima' at q = 0, 1.6 m off.  The polish from points along the self-motion (joints
    4 and 6 turned against each other) reaches the continuum within the limits."""
    robot = swarm_ik.load_robot("ur5_joint_limited_robot")
    q = np.array([1.11, -2.76, 0.349, -1.436, 0.0, -2.738])
    problem = swarm_ik.IKProblem.from_q(robot, q)
    res = swarm_ik.solve(problem, "analytic")
    assert res.success and res.reason == "converged"
    np.testing.assert_allclose(robot.fk_pinocchio(res.q), problem.target, atol=1e-9)
    assert np.all(res.q >= robot.lower) and np.all(res.q <= robot.upper)
    cf = analytic.closed_form_set(problem, 0.5 * (robot.lower + robot.upper), 1e-5, 1e-5)
    assert cf.incomplete  # samples of a continuum, never a complete set
    _check_solutions(robot, problem, cf.q, cf.position_error, cf.rotation_error)
