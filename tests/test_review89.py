"""Review 89 (one vocabulary for the solve calls) and review 90 (whole body, paths): each
defect found, as a behaviour."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from conftest import robot

import swarm_ik
from swarm_ik.errors import InvalidArgumentError
from swarm_ik.problem import IKProblem


def test_solve_many_keeps_max_evals_on_the_closed_form_path() -> None:
    """The closed form's polish of eaik's least-squares points counts against ``max_evals``
    (a near-singular UR5 target spent 245 evaluations of a budget of 50)."""
    pytest.importorskip("eaik")
    r = robot("ur5")
    q = np.array([5.120782496097188, 3.174862367579818, -0.0275060734344965, 4.32012154653, 1e-9,
                  2.085482282412036])  # fmt: skip
    problem = IKProblem(r, r.fk(q))
    for method in ("auto", "analytic"):
        results = swarm_ik.solve_many(problem, 8, max_evals=50, method=method)
        assert results and all(x.n_evals <= 50 for x in results), method
        for x in results:  # (what the budget allowed is still exact)
            assert x.success and r.within_limits(x.q)
    rng = np.random.default_rng(9)
    generic = IKProblem(r, r.fk(r.random_q(rng)))
    assert all(x.n_evals <= 1 for x in swarm_ik.solve_many(generic, 8, max_evals=1))


@pytest.mark.parametrize("value", ["False", "no", 1, 0, None, []])
def test_stop_on_success_is_true_or_false(value) -> None:
    r = robot("panda")
    with pytest.raises(InvalidArgumentError, match="stop_on_success must be True or False"):
        swarm_ik.solve(IKProblem(r, r.fk(r.mid_q())), stop_on_success=value, max_evals=100)


def test_iksolver_takes_prefer_as_solve_does() -> None:
    """``IKSolver(prefer="nearest")`` is solve's ``prefer`` (it was read as a solver parameter
    and ignored for a 4×4 target): it needs ``q0`` and gives solve's answer."""
    r = robot("ur5")
    target = r.fk(r.random_q(np.random.default_rng(1)))
    ik = swarm_ik.IKSolver(r, prefer="nearest")
    with pytest.raises(InvalidArgumentError, match="needs a starting point q0"):
        ik.solve(target)
    q0 = r.mid_q() + 0.3
    a = ik.solve(target, q0, 0)
    b = ik.solve(IKProblem(r, target), q0, 0)
    c = swarm_ik.solve(IKProblem(r, target), prefer="nearest", q0=q0, seed=0)
    assert np.array_equal(a.q, b.q) and np.array_equal(a.q, c.q) and a.success
    assert "prefer='nearest'" in repr(ik)


@pytest.mark.parametrize("i", [8, 11])
def test_nearest_is_no_farther_from_q0_than_best(i) -> None:
    """``prefer="nearest"`` takes each solution's 2π copy within the limits nearest to q0
    (UR5's joints range over 4π): it returned a copy 12.3 rad away where "best" gave 9.0."""
    r = robot("ur5")
    rng = np.random.default_rng(0)
    for k in range(i + 1):
        target = r.fk(r.random_q(rng))
        q0 = r.mid_q() + 0.3 if k % 2 else r.random_q(rng)
    problem = IKProblem(r, target)
    best = swarm_ik.solve(problem, q0=q0, seed=i)
    near = swarm_ik.solve(problem, q0=q0, seed=i, prefer="nearest")
    assert near.success and best.success
    assert np.linalg.norm(near.q - q0) <= np.linalg.norm(best.q - q0) + 1e-9
    assert np.allclose(r.fk_pinocchio(near.q), target, atol=1e-5)


def test_the_q0_clipped_warning_names_the_callers_line() -> None:
    r = robot("panda")
    target = r.fk(r.mid_q())
    q0 = r.mid_q()
    q0[1] = 5.0
    calls = [
        lambda: swarm_ik.solve(IKProblem(r, target), q0=q0),
        lambda: swarm_ik.IKSolver(r).solve(target, q0),
        lambda: swarm_ik.solve_many(IKProblem(r, target), 2, q0=q0),
        lambda: swarm_ik.solve_batch(r, target[None], q0=q0),
    ]
    for call in calls:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            call()
        clipped = [w for w in caught if "clipped into them" in str(w.message)]
        assert clipped and clipped[0].filename == __file__


def test_nearest_keeps_a_solution_whose_2pi_copy_misses_a_joint_goal() -> None:
    """Review 95: a goal on joint values tells 2π copies apart. ``JointValue(pan, 3.0)`` with
    ``q0[0] = -3``: the copy nearest q0 (-3.28) missed it, so the answer stays at 3.0."""
    from swarm_ik.goals import JointValue, Pose

    r = robot("ur5")
    qt = np.array([3.0, -1.2, 1.3, -1.0, 1.2, 0.4])
    problem = IKProblem(r, goals=[Pose(r.frames[0], r.fk(qt)), JointValue(r.joint_names[0], 3.0)])
    q0 = qt.copy()
    q0[0] = -3.0
    res = swarm_ik.solve(problem, q0=q0, seed=1, prefer="nearest", max_evals=5000)
    assert res.success and abs(res.q[0] - 3.0) <= 1e-5


def test_a_target_from_continuous_joints_beyond_pi_does_not_warn() -> None:
    """Any angle is a continuous joint's: only the other joints' limits are checked."""
    r = robot("kinova")
    q = r.mid_q()
    q[np.flatnonzero(r.continuous_mask)[0]] = 4.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        IKProblem.from_q(r, q)


def test_cs_newton_without_a_newton_step_spends_the_papers_count() -> None:
    """No step below ``eps``: m·t_max + m evaluations, no extra one (review 95)."""
    r = robot("panda")
    problem = IKProblem.from_q(r, r.mid_q() + 0.3)
    res = swarm_ik.solve(problem, "cs-newton", seed=0, pop_size=10, iterations=5, eps=1e-12,
                         stop_on_success=False)  # fmt: skip
    assert res.n_evals == 10 + 5 * 2 * 10
