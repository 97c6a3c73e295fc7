"""The papers' rules, checked by behaviour: basic FOA's candidates on continuous joints
([HLFOA] eqs. 5-6), [PSO-IK]'s local search (eq. 13) and stopping rule (section 3.1, step 6),
and the ``pso-adaptive`` variant that keeps the earlier local search."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from test_solvers_foa_pso import Recorder

import swarm_ik
from swarm_ik import solvers
from swarm_ik.optimize import minimize
from swarm_ik.solvers import foa
from swarm_ik.solvers.base import Evaluator
from swarm_ik.testfunctions import FUNCTIONS


# ------------------------------------------------------------------ FOA, continuous joints
@pytest.fixture(scope="module")
def kinova() -> swarm_ik.RobotModel:
    r = swarm_ik.load_robot("kinova")
    assert r.continuous_mask.tolist() == [True, False, False, True, False, True]
    return r


def test_foa_candidates_on_continuous_joints_are_clipped_not_wrapped(kinova) -> None:
    prob = swarm_ik.IKProblem.from_q(kinova, kinova.mid_q())
    ev = Evaluator(prob.fitness, kinova.lower, kinova.upper, problem=prob)
    x = np.array([[0.5] * 6, [0.0] * 6])  # Dist = 0.707 and Dist = 0 in every dimension
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # (a wrap of +inf warned "invalid value")
        s = foa.smell_candidates(x, x.copy(), foa._axis_unit(ev), ev)
    assert np.all(np.isfinite(s))
    assert np.all((s >= kinova.lower) & (s <= kinova.upper))
    assert np.all(s >= 0.0)  # S = 1/Dist > 0 (a wrap gave -1.84 on the continuous joints)
    np.testing.assert_array_equal(s[1], kinova.upper)  # Dist = 0: the upper bound
    # S = s_j/0.707 > pi on the continuous joints: held at the upper bound pi
    np.testing.assert_array_equal(
        s[0, kinova.continuous_mask], kinova.upper[kinova.continuous_mask]
    )


def test_foa_never_evaluates_a_negative_value_on_kinova(kinova) -> None:
    prob = swarm_ik.IKProblem.from_q(kinova, kinova.mid_q())
    rec = Recorder(prob.fitness)
    ev = Evaluator(rec, kinova.lower, kinova.upper, problem=prob)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        # init_range 0.5: flies near the origin, Dist < 1, so S = pi/Dist > pi on the
        # continuous joints (which a wrap would have turned negative)
        foa.run(ev, np.random.default_rng(0), pop_size=30, iterations=30, init_range=0.5)
    rows = rec.rows
    assert rows.shape == (30 * 30 + 1, 6)
    assert np.all(np.isfinite(rows))
    assert np.all((rows >= kinova.lower) & (rows <= kinova.upper))
    assert np.all(rows >= 0.0)  # the weakness [HLFOA] describes, on continuous joints too
    cont = rows[:, kinova.continuous_mask]
    assert np.any(cont == np.pi)  # some S > pi were held at the bound, none wrapped


# ------------------------------------------------------------- PSO-IK local search, eq. 13
def hartmann3_gradient(x: np.ndarray) -> np.ndarray:
    """Analytic gradient of F4 (Hartmann-3) at one point, shape (3,)."""
    from swarm_ik import testfunctions as tf

    d = x[None, :] - tf._H3_P  # (4, 3)
    e = tf._H3_C * np.exp(-np.sum(tf._H3_A * d * d, axis=1))  # (4,)
    return np.sum(e[:, None] * 2.0 * tf._H3_A * d, axis=0)


def sphere_gradient(x: np.ndarray) -> np.ndarray:
    return 2.0 * x


def _split_paper(batches: list[np.ndarray], pop: int, n: int, steps: int):
    """Batches of ``pso-improved``: the initial swarm, then per iteration the swarm and
    ``steps`` pairs (2n gradient probes, one step)."""
    assert batches[0].shape[0] == pop
    out = []
    k = 1
    while k < len(batches):
        swarm = batches[k]
        assert swarm.shape[0] == pop
        pairs = batches[k + 1 : k + 1 + 2 * steps]
        assert [b.shape[0] for b in pairs] == [2 * n, 1] * steps
        out.append((swarm, [pairs[2 * j + 1][0] for j in range(steps)]))
        k += 1 + 2 * steps
    return out


@pytest.mark.parametrize(
    ("key", "grad", "seed"), [("F1", sphere_gradient, 0), ("F4", hartmann3_gradient, 2)]
)
def test_pso_improved_local_search_is_theta_minus_0_2_grad_from_the_generations_best(
    key: str, grad, seed: int
) -> None:
    fn = FUNCTIONS[key]
    lo, hi = fn.bounds
    n = 3
    lo, hi = np.asarray(lo, dtype=float)[:n], np.asarray(hi, dtype=float)[:n]
    rec = Recorder(fn.function)
    spec = solvers.get("pso-improved")
    assert spec.params["ls_step"] == 0.2 and spec.params["ls_steps"] == 4
    assert spec.params["ls_rule"] == "paper"
    minimize(rec, lo, hi, "pso-improved", seed=seed, pop_size=10, iterations=6)
    its = _split_paper(rec.batches, 10, n, 4)
    assert len(its) == 6
    best_before = float(np.min(fn.function(rec.batches[0])))
    not_gbest = worse = 0
    for swarm, steps in its:
        f = fn.function(swarm)
        theta = swarm[int(np.argmin(f))]  # the generation's best particle, not gbest
        not_gbest += bool(f.min() > best_before)
        for row in steps:  # a fresh gradient at each step, fixed lambda = 0.2
            expected = np.clip(theta - 0.2 * grad(theta), lo, hi)
            # (finite differences: one-sided at a bound, O(h f'') there)
            np.testing.assert_allclose(row, expected, rtol=1e-6, atol=1e-5)
            worse += bool(fn.function(row[None])[0] > fn.function(theta[None])[0])
            theta = row  # the next step starts there, improving or not
        best_before = min(best_before, float(np.min(fn.function(np.vstack([swarm, steps])))))
    if key == "F4":  # (meaningful: a generation's best that was not the global best, and
        assert not_gbest > 0  # a step that made things worse and was still followed)
        assert worse > 0


def test_pso_improved_on_the_sphere_steps_are_exactly_0_6_theta() -> None:
    # f = |x|^2: theta - 0.2 * 2 theta = 0.6 theta, improving at every step
    rec = Recorder(FUNCTIONS["F1"].function)
    lo, hi = -100.0 * np.ones(4), 100.0 * np.ones(4)
    res = minimize(rec, lo, hi, "pso-improved", seed=1, pop_size=8, iterations=3)
    for swarm, steps in _split_paper(rec.batches, 8, 4, 4):
        theta = swarm[int(np.argmin(FUNCTIONS["F1"].function(swarm)))]
        for k, row in enumerate(steps, start=1):
            np.testing.assert_allclose(row, 0.6**k * theta, rtol=1e-7, atol=1e-9)
    assert res.n_evals == 8 + 3 * (8 + 4 * (2 * 4 + 1))


def test_paper_local_search_moves_the_particle_to_its_improved_pbest() -> None:
    # w = c1 = c2 = 0: particles move only by the local search ("the better position
    # replaces the current one", [PSO-IK] 3.2.1)
    f = FUNCTIONS["F1"].function
    rec = Recorder(f)
    lo, hi = -5.0 * np.ones(2), 5.0 * np.ones(2)
    minimize(
        rec, lo, hi, "pso", seed=0, pop_size=6, iterations=2, w=0.0, c1=0.0, c2=0.0,
        local_search=True,
    )  # fmt: skip
    (s1, steps1), (s2, _) = _split_paper(rec.batches, 6, 2, 4)
    i = int(np.argmin(f(s1)))
    moved = np.flatnonzero(np.any(s2 != s1, axis=1))
    assert moved.tolist() == [i]
    np.testing.assert_array_equal(s2[i], steps1[-1])  # (the sphere: every step improves)


def test_paper_local_search_costs_ms_gradients_and_steps_per_iteration() -> None:
    lo, hi = -5.0 * np.ones(3), 5.0 * np.ones(3)
    res = minimize(
        FUNCTIONS["F1"].function, lo, hi, "pso", seed=0, pop_size=10, iterations=20,
        local_search=True,
    )  # fmt: skip
    assert res.n_evals == 10 + 20 * (10 + 4 * (2 * 3 + 1))


# ----------------------------------------------------------- the adaptive variant, named
def test_adaptive_variant_is_registered_and_searches_from_gbest() -> None:
    assert {"pso-improved", "pso-adaptive"} <= set(solvers.search_names())
    spec = solvers.get("pso-adaptive")
    assert spec.paper == "PSO-IK" and spec.params["ls_rule"] == "adaptive"
    assert spec.params["w"] == 0.9 and spec.params["local_search"] and spec.params["escape"]
    fn = FUNCTIONS["F4"].function
    rec = Recorder(fn)
    lo, hi = np.zeros(3), np.ones(3)
    minimize(rec, lo, hi, "pso-adaptive", seed=2, pop_size=10, iterations=6)
    b = rec.batches
    assert [x.shape[0] for x in b] == [10] + [10, 6, 1, 1, 1, 1] * 6  # one gradient/iteration
    seen = [b[0]]
    for t in range(6):
        swarm, probes, steps = b[1 + 6 * t], b[2 + 6 * t], b[3 + 6 * t : 7 + 6 * t]
        seen.append(swarm)
        centre = probes[0].copy()  # probe j moves coordinate j only
        centre[0] = probes[1][0]
        pool = np.vstack(seen)
        np.testing.assert_array_equal(centre, pool[int(np.argmin(fn(pool)))])  # gbest
        seen.extend(steps)


# ----------------------------------------------------------------- PSO-IK stop, step 6
def test_paper_stop_ends_at_the_first_iteration_whose_gbest_meets_min_error() -> None:
    f = FUNCTIONS["F1"].function
    lo, hi = -5.0 * np.ones(3), 5.0 * np.ones(3)
    spec = solvers.get("pso")
    assert spec.params["paper_stop"] is False and spec.params["min_error"] == 0.02
    full = minimize(f, lo, hi, "pso", seed=0, pop_size=10, iterations=200)
    res = minimize(f, lo, hi, "pso", seed=0, pop_size=10, iterations=200, paper_stop=True)
    h = res.history
    assert h[-1] <= 0.02 < h[-2]  # (plain PSO: the history is gbest's fitness)
    assert res.n_evals == 10 * (len(h) + 1) < full.n_evals
    np.testing.assert_array_equal(h, full.history[: len(h)])  # the same run, cut at step 6


def test_paper_stop_on_the_papers_fitness_stops_before_the_library_tolerance(kinova) -> None:
    q = kinova.mid_q() + 0.3
    prob = swarm_ik.IKProblem.from_q(kinova, q, "paper-pso")
    res = swarm_ik.solve(prob, "pso-improved", seed=0, paper_stop=True)
    assert res.fitness <= 0.02 and not res.success
    assert res.n_evals < 40 * 101 + 100 * 4 * 13  # before the last of the 100 iterations
