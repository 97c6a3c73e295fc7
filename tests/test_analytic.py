"""Solver 'analytic' (eaik): complete branch sets, verified with Pinocchio; refusals."""

import numpy as np
import pytest

import swarm_ik
from swarm_ik import branches as br
from swarm_ik.solvers import analytic

eaik = pytest.importorskip("eaik")


@pytest.mark.parametrize("name", ["ur5", "ur10", "z1"])
def test_chain_is_decomposed_and_fk_matches(name):
    robot = swarm_ik.load_robot(name)
    chain = analytic.analytic_chain(robot)
    assert chain.supported, chain.reason
    rng = np.random.default_rng(0)
    for q in robot.random_q(rng, 5):
        assert np.allclose(chain.solver.fwdkin(q), robot.fk_pinocchio(q), atol=1e-12)


@pytest.mark.parametrize("name", ["ur5", "ur10", "z1"])
def test_solve_all_contains_generating_branch(name):
    robot = swarm_ik.load_robot(name)
    rng = np.random.default_rng(1)
    periodic = br.periodic_mask(robot) | br.revolute_mask(robot)
    for q in robot.random_q(rng, 10):
        problem = swarm_ik.IKProblem.from_q(robot, q)
        qs, dp, dr = analytic.solve_all(problem)
        assert qs.shape[0] >= 1 and np.all(dp < 1e-9) and np.all(dr < 1e-9)
        assert np.all(qs >= robot.lower) and np.all(qs <= robot.upper)
        assert np.min(br.branch_distance(qs, q, periodic)) < 1e-6
        for qi in qs:  # FK checked independently of pinocchio_errors
            pose = robot.fk_pinocchio(qi)
            assert np.allclose(pose, problem.target, atol=1e-9)
        if qs.shape[0] > 1:  # no duplicates modulo 2π
            d = br.branch_distance(qs[:, None], qs[None], periodic)
            assert np.min(d[~np.eye(qs.shape[0], dtype=bool)]) > br.BRANCH_TOL


@pytest.mark.parametrize(
    "q",
    [np.zeros(6), [0.3, -1.0, 0.0, -0.5, 1.1, 0.2], [0.3, -1.0, 1e-7, -0.5, 1.1, 0.2]],
    ids=["home", "elbow-straight", "elbow-almost-straight"],
)
def test_singular_poses_keep_the_exact_solutions_eaik_calls_least_squares(q):
    """With the elbow straight two branches merge and eaik calls the exact solution least
    squares: the closed form keeps it (it found none of these reachable poses)."""
    robot = swarm_ik.load_robot("ur5")
    problem = swarm_ik.IKProblem.from_q(robot, np.asarray(q, dtype=float))
    qs, dp, dr = analytic.solve_all(problem)
    assert qs.shape[0] >= 1 and np.all(dp <= 1e-5) and np.all(dr <= 1e-5)
    for qi in qs:
        np.testing.assert_allclose(robot.fk_pinocchio(qi), problem.target, atol=1e-5)
    assert len(swarm_ik.solve_many(problem, n=16)) >= 1


def test_representative_nearest_reference():
    robot = swarm_ik.load_robot("ur5")
    q = np.array([0.3, -1.0, 1.2, -0.5, 1.1, 0.2])
    problem = swarm_ik.IKProblem.from_q(robot, q)
    ref = q + 2 * np.pi * np.array([-1, 0, 0, 1, 0, 0])
    qs, _, _ = analytic.solve_all(problem, ref=ref)
    assert np.allclose(qs[0], ref, atol=1e-9)  # the generating branch, as its copy near ref


def test_solver_registered_and_solves():
    robot = swarm_ik.load_robot("ur10")
    problem = swarm_ik.IKProblem.from_q(robot, [0.1, -1.2, 1.0, 0.4, -0.9, 2.0])
    res = swarm_ik.solve(problem, "analytic")
    assert res.success and res.position_error < 1e-9 and res.solver == "analytic"


def test_refusals_name_the_reason():
    panda = swarm_ik.load_robot("panda")
    problem = swarm_ik.IKProblem.from_q(panda, panda.mid_q())
    with pytest.raises(analytic.AnalyticUnsupportedError, match="7 joints"):
        analytic.solve_all(problem)
    with pytest.raises(analytic.AnalyticUnsupportedError, match="7 joints"):
        swarm_ik.solve_many(problem, method="analytic")
    ur5 = swarm_ik.load_robot("ur5")
    pos_only = swarm_ik.IKProblem.from_q(ur5, np.zeros(6), w_rot=0.0)
    with pytest.raises(analytic.AnalyticUnsupportedError, match="position-only"):
        analytic.solve_all(pos_only)


def test_unreachable_pose_gives_empty_set():
    robot = swarm_ik.load_robot("ur5")
    target = np.eye(4)
    target[:3, 3] = [5.0, 0.0, 0.0]
    qs, dp, dr = analytic.solve_all(swarm_ik.IKProblem(robot, target))
    assert qs.shape == (0, 6)


def test_missing_eaik_message(monkeypatch):
    import builtins
    import sys

    robot = swarm_ik.load_robot("ur3")  # not cached by another test
    analytic._CACHE.pop(robot, None)
    real_import = builtins.__import__

    def fake(name, *args, **kwargs):
        if name.startswith("eaik"):
            raise ImportError("no eaik")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", fake)
    for mod in [m for m in sys.modules if m == "eaik" or m.startswith("eaik.")]:
        monkeypatch.delitem(sys.modules, mod)
    assert not analytic.eaik_available()
    problem = swarm_ik.IKProblem.from_q(robot, np.zeros(6))
    with pytest.raises(analytic.AnalyticUnavailableError, match=r"swarm_ik\[analytic\]"):
        swarm_ik.solve_many(problem, method="analytic")
    res = swarm_ik.solve_many(problem, method="auto", n=2)  # auto falls back to numerical
    assert res and res[0].solver == "swarm"


def test_solve_analytic_answers_and_says_unreachable():
    robot = swarm_ik.load_robot("ur10")
    problem = swarm_ik.IKProblem.from_q(robot, [0.1, -1.2, 1.0, 0.4, -0.9, 2.0])
    q0 = np.array([0.0, -1.0, 1.0, 0.0, -1.0, 1.5])
    for start in (None, q0):
        a = swarm_ik.solve(problem, "analytic", q0=start)
        assert a.success and a.reason == "converged"
        np.testing.assert_allclose(robot.fk_pinocchio(a.q), problem.target, atol=1e-9)
    far = np.eye(4)
    far[:3, 3] = [5.0, 0.0, 0.0]
    r = swarm_ik.solve(swarm_ik.IKProblem(robot, far), "analytic")
    assert not r.success and r.reason == "unreachable"
