"""The default ``swarm`` solver: its Jacobians, exactness, limits, many solutions, nearest mode,
and the benchmark code path."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from conftest import robot, timed

import swarm_ik
from swarm_ik.kernels.lie import log3_nb as _log3
from swarm_ik.problem import largest_errors
from swarm_ik.solvers import base
from swarm_ik.solvers.hybrid import Polisher, wrapped_distance

ROOT = Path(__file__).resolve().parents[1]
ARMS = ["panda", "ur5", "kinova", "xarm7", "baxter_left"]
BUNDLED = ["yumi_left", "loading_manipulator", "loading_manipulator_long"]


# --------------------------------------------------------------------------- Jacobians
def test_log3_matches_pinocchio_near_zero_generic_and_near_pi() -> None:
    rng = np.random.default_rng(4)
    out = np.empty(3)
    for angle in [
        0.0,
        1e-12,
        1e-7,
        1e-3,
        0.5,
        2.0,
        np.pi - 1e-2,
        np.pi - 1e-4,
        np.pi - 1e-9,
        np.pi,
    ]:
        for _ in range(5):
            axis = rng.normal(size=3)
            axis /= np.linalg.norm(axis)
            m = pin.exp3(angle * axis)
            theta = _log3(m, out)
            assert theta == pytest.approx(angle, abs=1e-9)
            ref = pin.log3(m)
            if angle < np.pi - 1e-6:
                np.testing.assert_allclose(out, ref, atol=1e-9)
            else:  # at π the sign of the axis is arbitrary
                np.testing.assert_allclose(pin.exp3(out), m, atol=1e-9)


@pytest.mark.parametrize(
    "name,position_only",
    [
        ("panda", False),
        ("kinova", False),
        ("loading_manipulator_long", False),
        ("yumi_left", False),
        ("ur5", True),
    ],
)
def test_residual_jacobian_matches_central_differences(name: str, position_only: bool) -> None:
    """The Jacobian the polish uses, ``[J_v; J_r⁻¹(φ) J_ω]`` with ``r(q+δ) ≈ r − J δ``,
    against central differences of the residual itself (rotation errors up to ~2.5 rad)."""
    r = robot(name)
    rng = np.random.default_rng(5)
    h = 1e-6
    checked = 0
    while checked < 6:
        q_t, q = r.random_q(rng), r.random_q(rng)
        prob = swarm_ik.IKProblem(r, r.fk(q_t), w_rot=0.0 if position_only else 1.0)
        pol = Polisher.from_problem(prob, r.lower, r.upper)
        res, jac, _dp, dr = pol.residual(q)
        if dr > 2.5:  # log3 has its branch cut at π; stay clear of it
            continue
        checked += 1
        for j in range(r.nq):
            e = np.zeros(r.nq)
            e[j] = h
            rp, _, _, _ = pol.residual(q + e)
            rm, _, _, _ = pol.residual(q - e)
            np.testing.assert_allclose(-(rp - rm) / (2 * h), jac[:, j], atol=2e-7)
        assert res.shape == ((3,) if position_only else (6,))


# --------------------------------------------------------------------------- solving
@pytest.mark.parametrize("name", BUNDLED + ARMS)
def test_swarm_solves_fk_sampled_targets_within_limits(name: str) -> None:
    r = robot(name)
    rng = np.random.default_rng(11)
    for i in range(15):
        prob = swarm_ik.IKProblem.from_q(r, r.random_q(rng))
        res = swarm_ik.solve(prob, "swarm", seed=i, q0=r.mid_q(), max_evals=20000)
        assert res.success, (name, i, res)
        assert res.within_limits and r.within_limits(res.q, tol=0.0)
        assert res.position_error <= 1e-5 and res.rotation_error <= 1e-5
        assert 1 <= res.n_evals <= 20000


def test_swarm_is_the_default_solver_and_reaches_1e_10() -> None:
    assert swarm_ik.api.DEFAULT_SOLVER == "swarm"
    r = robot("panda")
    rng = np.random.default_rng(12)
    for i in range(10):
        prob = swarm_ik.IKProblem.from_q(r, r.random_q(rng))
        res = swarm_ik.solve(prob, seed=i, tol_pos=1e-10, tol_rot=1e-10, max_evals=50000)
        assert res.success and res.solver == "swarm"
        assert res.position_error <= 1e-10 and res.rotation_error <= 1e-10


def test_continuous_joints_stay_wrapped_and_prismatic_in_metres() -> None:
    kin = robot("kinova")
    rng = np.random.default_rng(13)
    for i in range(8):
        prob = swarm_ik.IKProblem.from_q(kin, kin.random_q(rng))
        res = swarm_ik.solve(prob, seed=i, max_evals=20000)
        assert res.success
        cont = kin.continuous_mask
        assert np.all(res.q[cont] >= -np.pi) and np.all(res.q[cont] <= np.pi)
    lm = robot("loading_manipulator_long")
    q_true = lm.random_q(rng)
    res = swarm_ik.solve(swarm_ik.IKProblem.from_q(lm, q_true), seed=0, max_evals=20000)
    pris = lm.prismatic_mask
    assert res.success and pris.sum() == 3
    assert np.all(res.q[pris] >= 0.0) and np.all(res.q[pris] <= 1.5)  # stroke [0, 1.5] m


def test_position_only_problem() -> None:
    r = robot("ur5")
    prob = swarm_ik.IKProblem.from_q(r, r.random_q(np.random.default_rng(14)), w_rot=0.0)
    res = swarm_ik.solve(prob, seed=0, max_evals=5000)
    assert res.success and res.position_error <= 1e-5


@timed()
def test_budget_time_limit_determinism_and_unreachable_target() -> None:
    r = robot("ur5")
    target = np.eye(4)
    target[:3, 3] = [5.0, 0.0, 0.0]  # beyond the reach
    prob = swarm_ik.IKProblem(r, target)
    a = swarm_ik.solve(prob, seed=3, max_evals=777)
    b = swarm_ik.solve(prob, seed=3, max_evals=777)
    assert not a.success and a.n_evals == 777 and a.within_limits
    assert a.q.tobytes() == b.q.tobytes() and np.array_equal(a.history, b.history)
    assert np.all(np.diff(a.history) <= 0)
    res = swarm_ik.solve(prob, seed=0, time_limit=0.01)
    assert not res.success and res.time_s < 0.01 + 0.02  # one compiled call of slack


def test_paper_fitness_is_reported_in_its_own_units() -> None:
    r = robot("yumi_left")
    q_true = np.array([0.1, -0.5, 0.2, 0.3, -0.2, 0.4, 0.1])
    prob = swarm_ik.IKProblem.from_q(r, q_true, "paper-l1")
    res = swarm_ik.solve(prob, seed=0, max_evals=5000)
    assert res.success
    assert res.fitness == pytest.approx(float(prob.fitness(res.q[None])[0]), abs=1e-15)


def test_evaluator_add_evals_counts_and_refuses_overdraft() -> None:
    lo, hi = np.zeros(2), np.ones(2)
    ev = base.Evaluator(lambda x: x.sum(axis=1), lo, hi, max_evals=10)
    ev.add_evals(4)
    ev.add_evals(3, np.array([0.2, 0.3]), 0.5)
    assert ev.n_evals == 7 and ev.best_f == 0.5
    ev.add_evals(0, np.array([0.9, 0.9]), 1.8)  # worse: not the best
    assert ev.best_f == 0.5
    with pytest.raises(swarm_ik.InvalidArgumentError, match="remaining budget"):
        ev.add_evals(4)
    with pytest.raises(swarm_ik.InvalidArgumentError, match="fitness"):
        ev.add_evals(1, np.array([0.1, 0.1]))


# --------------------------------------------------------------------------- many solutions
@pytest.mark.parametrize("name", ["yumi_left", "kinova"])
def test_solve_many_returns_distinct_verified_solutions(name: str) -> None:
    r = robot(name)
    prob = swarm_ik.IKProblem.from_q(r, r.random_q(np.random.default_rng(21)))
    sols = swarm_ik.solve_many(prob, n=8, min_distance=0.2, seed=0, time_limit=0.5)
    assert len(sols) == 8
    qs = np.array([s.q for s in sols])
    for i in range(len(qs)):
        d = wrapped_distance(np.delete(qs, i, axis=0), qs[i], r.continuous_mask)
        assert np.all(d >= 0.2)
    for s in sols:
        dp, dr = largest_errors(swarm_ik.verify(prob, s.q))
        assert s.success and dp <= 1e-5 and dr <= 1e-5 and r.within_limits(s.q, tol=0.0)
        assert (dp, dr) == (s.position_error, s.rotation_error)


def test_wrapped_distance_treats_continuous_joints_as_circles() -> None:
    wrap = np.array([True, False])
    a = np.array([[np.pi - 0.05, 0.0]])
    b = np.array([-np.pi + 0.05, 0.0])
    assert wrapped_distance(a, b, wrap)[0] == pytest.approx(0.1)
    assert wrapped_distance(a, b, ~wrap)[0] == pytest.approx(2 * np.pi - 0.1)


def test_solve_many_refuses_bad_arguments_and_respects_budget() -> None:
    r = robot("yumi_left")
    prob = swarm_ik.IKProblem.from_q(r, np.zeros(7))
    with pytest.raises(swarm_ik.InvalidArgumentError, match="n must be"):
        swarm_ik.solve_many(prob, n=0)
    with pytest.raises(swarm_ik.InvalidArgumentError, match="min_distance"):
        swarm_ik.solve_many(prob, min_distance=-1.0)
    sols = swarm_ik.solve_many(prob, n=1000, max_evals=300, seed=1)
    assert 1 <= len(sols) and max(s.n_evals for s in sols) <= 300


# --------------------------------------------------------------------------- nearest mode
def _planar_two_solutions(planar2_urdf: str) -> tuple[swarm_ik.IKProblem, np.ndarray, np.ndarray]:
    arm = swarm_ik.load_robot(planar2_urdf, ee_frame="tip")
    qa = np.array([0.7, 1.1])
    p = arm.fk(qa)[:3, 3]
    q2 = -qa[1]  # the elbow-flipped solution of the same position
    qb = np.array([np.arctan2(p[1], p[0]) - np.arctan2(0.8 * np.sin(q2), 1 + 0.8 * np.cos(q2)), q2])
    np.testing.assert_allclose(arm.fk(qb)[:3, 3], p, atol=1e-12)
    return swarm_ik.IKProblem(arm, arm.fk(qa), w_rot=0.0), qa, qb


def test_prefer_nearest_returns_the_known_solution_closest_to_q0(planar2_urdf: str) -> None:
    prob, qa, qb = _planar_two_solutions(planar2_urdf)
    rng = np.random.default_rng(31)
    for i in range(30):
        near, far = (qa, qb) if i % 2 == 0 else (qb, qa)
        q0 = near + rng.uniform(-0.6, 0.6, size=2)
        if np.linalg.norm(q0 - near) >= np.linalg.norm(q0 - far):
            continue
        res = swarm_ik.solve(prob, q0=q0, prefer="nearest", seed=i, max_evals=5000)
        assert res.success
        np.testing.assert_allclose(res.q, near, atol=1e-4)
    # starts from which the plain polish falls into the farther solution's basin
    hard = np.array(
        [
            [1.599, 0.079],
            [2.364, 0.066],
            [0.399, -0.096],
            [2.045, 0.148],
            [0.162, -0.221],
            [2.252, 0.257],
        ]
    )
    plain_farther = 0
    for i, q0 in enumerate(hard):
        near = qa if np.linalg.norm(q0 - qa) < np.linalg.norm(q0 - qb) else qb
        res = swarm_ik.solve(prob, q0=q0, prefer="nearest", seed=i, max_evals=5000)
        assert res.success
        np.testing.assert_allclose(res.q, near, atol=1e-4)
        best = swarm_ik.solve(prob, q0=q0, seed=i, max_evals=5000)
        plain_farther += not np.allclose(best.q, near, atol=1e-4)
    assert plain_farther >= 1  # the test has teeth: prefer="best" does not do this


def test_prefer_nearest_on_a_redundant_arm_is_no_farther_than_best() -> None:
    r = robot("yumi_left")
    rng = np.random.default_rng(32)
    for i in range(6):
        q_true = r.random_q(rng)
        q0 = np.clip(q_true + rng.normal(scale=0.4, size=7), r.lower, r.upper)
        prob = swarm_ik.IKProblem.from_q(r, q_true)
        near = swarm_ik.solve(prob, q0=q0, prefer="nearest", seed=i, max_evals=20000)
        best = swarm_ik.solve(prob, q0=q0, seed=i, max_evals=20000)
        assert near.success and best.success
        assert np.linalg.norm(near.q - q0) <= np.linalg.norm(best.q - q0) + 1e-9


def test_prefer_arguments_are_checked() -> None:
    r = robot("panda")
    prob = swarm_ik.IKProblem.from_q(r, r.mid_q())
    with pytest.raises(swarm_ik.InvalidArgumentError, match="needs a starting point q0"):
        swarm_ik.solve(prob, prefer="nearest")
    with pytest.raises(swarm_ik.InvalidArgumentError, match="solvers that have one: swarm"):
        swarm_ik.solve(prob, "dls", q0=r.mid_q(), prefer="nearest")
    with pytest.raises(swarm_ik.UnknownNameError, match="best, nearest"):
        swarm_ik.solve(prob, q0=r.mid_q(), prefer="closest")


# --------------------------------------------------------------------------- benchmark, example
def test_cartesian_path_example_runs(capsys: pytest.CaptureFixture[str]) -> None:
    path = ROOT / "examples" / "05_cartesian_path.py"
    spec = importlib.util.spec_from_file_location("ex05", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    mod.main()
    out = capsys.readouterr().out
    assert out.count("solved 25/25") == 6  # line and circle, three ways each


@pytest.mark.parametrize("python_twin", [False, True])
def test_secondary_descent_reaches_the_constrained_optimum(python_twin: bool) -> None:
    """The null-space descent of a ``Posture`` secondary beside a position, from an exact
    answer: the primary goal stays within tolerance, the posture cost falls, and in most
    cases the descent ends where SciPy's SLSQP finds the constrained optimum from the same
    point (both local methods: the rest end at other local optima).  The compiled kernel
    and its numpy twin (used for problems with goals written in Python) give the same."""
    from scipy.optimize import minimize

    from swarm_ik.goals import Position, Posture
    from swarm_ik.solvers.python_lm import PythonPolisher

    r = robot("panda")
    rng = np.random.default_rng(11)
    at_optimum = 0
    for _ in range(8):
        q_t, q_ref = r.random_q(rng), r.random_q(rng)
        p = r.fk(q_t)[:3, 3]
        prob = swarm_ik.IKProblem(r, goals=[Position(r.ee_frame, p), Posture(q_ref)])
        pol = Polisher.from_problem(prob)
        if python_twin:
            pol = PythonPolisher(prob, pol.bounds, pol.cfg, pol.kernel_tol_pos, pol.kernel_tol_rot)
        q, used = pol.secondary(q_t, 200)
        assert used <= 200
        assert np.linalg.norm(r.fk_pinocchio(q)[:3, 3] - p) <= 1e-5
        assert np.linalg.norm(q - q_ref) < np.linalg.norm(q_t - q_ref)
        best = minimize(
            lambda x, q_ref=q_ref: 0.5 * np.sum((x - q_ref) ** 2), q_t,
            jac=lambda x, q_ref=q_ref: x - q_ref,
            constraints=[{"type": "eq", "fun": lambda x, p=p: r.fk(x)[:3, 3] - p}],
            bounds=list(zip(r.lower, r.upper, strict=True)), method="SLSQP",
            options={"maxiter": 500, "ftol": 1e-12},
        )  # fmt: skip
        at_optimum += abs(np.linalg.norm(q - q_ref) - np.linalg.norm(best.x - q_ref)) < 1e-3
    assert at_optimum >= 4
