"""solve_many: each branch once modulo 2π, early stop, windings, spread on redundant arms."""

import time

import numpy as np
import pytest

import swarm_ik
from swarm_ik import branches as br
from swarm_ik.solvers import analytic


def _truth(problem):
    pytest.importorskip("eaik")
    return analytic.solve_all(problem)[0]


@pytest.mark.parametrize("name", ["ur5", "z1"])
def test_numerical_finds_each_branch_once(name):
    robot = swarm_ik.load_robot(name)
    periodic = br.periodic_mask(robot)
    rng = np.random.default_rng(4)
    for q in robot.random_q(rng, 4):
        problem = swarm_ik.IKProblem.from_q(robot, q)
        sols = swarm_ik.solve_many(problem, n=16, method="numerical", seed=1)
        qs = np.array([s.q for s in sols])
        assert all(s.success for s in sols)
        for s in sols:  # verified independently with Pinocchio
            assert np.allclose(robot.fk_pinocchio(s.q), problem.target, atol=1e-8)
        d = br.branch_distance(qs[:, None], qs[None], periodic)
        assert np.min(d[~np.eye(len(sols), dtype=bool)], initial=np.inf) > br.BRANCH_TOL
        assert np.min(br.branch_distance(qs, q, periodic)) < 1e-6  # the generating branch
        truth = _truth(problem)
        assert len(sols) == truth.shape[0]  # recall and no extras against eaik


def test_early_stop_when_n_exceeds_branches():
    robot = swarm_ik.load_robot("z1")  # ~1-2 branches in its limits
    problem = swarm_ik.IKProblem.from_q(robot, robot.mid_q() + 0.1)
    sols = swarm_ik.solve_many(problem, n=64, method="numerical")
    assert len(sols) <= 4
    assert sols[-1].n_evals < 64 * 64 * 30 / 4  # far below the 64·n starts budget


def test_representative_nearest_q0_and_windings():
    robot = swarm_ik.load_robot("ur5")
    q = np.array([0.3, -1.0, 1.2, -0.5, 1.1, 0.2])
    problem = swarm_ik.IKProblem.from_q(robot, q)
    q0 = q - 2 * np.pi * np.array([1, 0, 0, 0, 1, 0]) + 1e-3
    sols = swarm_ik.solve_many(problem, method="numerical", q0=q0)
    assert np.allclose(sols[0].q, q - 2 * np.pi * np.array([1, 0, 0, 0, 1, 0]), atol=1e-8)
    groups = swarm_ik.solve_many(problem, method="numerical", q0=q0, windings=True)
    assert len(groups) == len(sols)
    periodic = br.periodic_mask(robot)
    for g in groups:
        assert len(g) == 32  # every copy of a generic UR5 branch fits the ±2π limits
        assert np.all(br.branch_distance(np.array([r.q for r in g]), g[0].q, periodic) < 1e-9)
        assert all(r.success and r.position_error < 1e-8 for r in g)


def test_min_distance_filter_coarser():
    robot = swarm_ik.load_robot("ur5")
    problem = swarm_ik.IKProblem.from_q(robot, [0.3, -1.0, 1.2, -0.5, 1.1, 0.2])
    all_b = swarm_ik.solve_many(problem, method="numerical")
    coarse = swarm_ik.solve_many(problem, method="numerical", min_distance=4.0)
    assert len(coarse) < len(all_b)
    qs = np.array([r.q for r in coarse])
    d = br.branch_distance(qs[:, None], qs[None], br.periodic_mask(robot))
    assert np.min(d[~np.eye(len(qs), dtype=bool)], initial=np.inf) >= 4.0


def test_time_limit_includes_verification():
    robot = swarm_ik.load_robot("panda")
    problem = swarm_ik.IKProblem.from_q(robot, robot.mid_q() + 0.2)
    t0 = time.perf_counter()
    sols = swarm_ik.solve_many(problem, n=200, method="numerical", time_limit=0.02)
    elapsed = time.perf_counter() - t0
    assert sols and elapsed < 0.02 + 0.015  # one compiled batch of slack


def test_redundant_spread_beats_first_found():
    robot = swarm_ik.load_robot("panda")
    problem = swarm_ik.IKProblem.from_q(robot, [0.2, -0.3, 0.1, -1.8, 0.2, 1.6, 0.5])
    sols = swarm_ik.solve_many(problem, n=8, method="numerical", seed=0)
    assert len(sols) == 8 and all(s.success for s in sols)
    qs = np.array([s.q for s in sols])
    pool = np.array([s.q for s in swarm_ik.solve_many(problem, n=64, method="numerical", seed=5)])
    mask = br.periodic_mask(robot)
    spread = br.covering_radius(qs, pool, mask)
    first = br.covering_radius(pool[:8], pool, mask)
    assert spread < first


def test_auto_uses_analytic_when_available():
    pytest.importorskip("eaik")
    robot = swarm_ik.load_robot("ur10")
    problem = swarm_ik.IKProblem.from_q(robot, [0.1, -1.2, 1.0, 0.4, -0.9, 2.0])
    sols = swarm_ik.solve_many(problem)
    assert sols and all(s.solver == "analytic" for s in sols)
    panda = swarm_ik.load_robot("panda")
    sols = swarm_ik.solve_many(swarm_ik.IKProblem.from_q(panda, panda.mid_q()), n=3)
    assert sols and sols[0].solver == "swarm"


def test_bad_arguments():
    robot = swarm_ik.load_robot("ur5")
    problem = swarm_ik.IKProblem.from_q(robot, np.zeros(6))
    with pytest.raises(swarm_ik.UnknownNameError, match="numerical"):
        swarm_ik.solve_many(problem, method="closed-form")
    with pytest.raises(swarm_ik.InvalidArgumentError, match="min_distance"):
        swarm_ik.solve_many(problem, min_distance=-1.0)
    with pytest.raises(swarm_ik.InvalidArgumentError, match="patience"):
        swarm_ik.solve_many(problem, patience=0)
