"""Algorithm-specific tests of gwo, mgwo, cs and cs-newton."""

from __future__ import annotations

import numpy as np
import pytest

import swarm_ik
from swarm_ik.errors import InvalidArgumentError
from swarm_ik.optimize import minimize
from swarm_ik.solvers import cs, gwo, mgwo
from swarm_ik.solvers.base import Evaluator
from swarm_ik.testfunctions import FUNCTIONS

PAPER_X_STAR = np.array([np.pi / 4, np.pi / 6, np.pi / 4, 0.8, 1.0, 1.0, np.pi / 6, -np.pi / 4])
"""[MGWO]'s IK experiment: the target is the FK of this joint vector."""


def mean_fun(key: str, solver: str, seeds, **params) -> float:
    tf = FUNCTIONS[key]
    lower, upper = tf.bounds
    return float(np.mean([minimize(tf, lower, upper, solver, seed=s, **params).fun for s in seeds]))


class CountingEvaluator(Evaluator):
    """An Evaluator that counts the calls of ``uniform`` (initial population, re-inits)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.uniform_calls: list[int] = []

    def uniform(self, rng, n):
        self.uniform_calls.append(n)
        return super().uniform(rng, n)


# ---------------------------------------------------------------------------- GWO update
def test_gwo_move_with_a_zero_puts_every_wolf_at_the_leaders_mean():
    rng = np.random.default_rng(0)
    x = rng.uniform(-5, 5, size=(12, 4))
    leaders = rng.uniform(-1, 1, size=(3, 4))
    out = gwo.gwo_move(x, leaders, 0.0, rng)  # A = 0: X_l' = X_l for each leader
    np.testing.assert_allclose(out, np.broadcast_to(leaders.mean(axis=0), x.shape), atol=1e-15)
    per_wolf = np.repeat(leaders[None], 12, axis=0) + np.arange(12)[:, None, None]
    out = gwo.gwo_move(x, per_wolf, 0.0, rng)  # one set of leaders per wolf (MGWO)
    np.testing.assert_allclose(out, per_wolf.mean(axis=1), atol=1e-13)


def test_gwo_move_is_unbiased_around_a_single_leader():
    # With alpha = beta = delta = L, each X_l' = L - A|C L - X| and E[A] = 0: mean is L.
    rng = np.random.default_rng(1)
    x = rng.uniform(-1, 1, size=(20000, 2))
    leader = np.array([0.3, -0.2])
    out = gwo.gwo_move(x, np.tile(leader, (3, 1)), 1.5, rng)
    np.testing.assert_allclose(out.mean(axis=0), leader, atol=0.02)
    assert out.std(axis=0).min() > 0.2  # a = 1.5: |A| up to 1.5, a real exploration step


def test_reference_leader_rule_does_not_demote_alpha():
    x = np.arange(4.0)[:, None] * np.ones((4, 2))  # wolf i sits at (i, i)
    f = np.array([5.0, 3.0, 4.0, 1.0])
    lx, lf = gwo.init_leaders(np.array([9.0, 9.0]))
    # GWO.m of [GWO]: 5 -> alpha; 3 -> alpha; 4 -> beta; 1 -> alpha, and 3 is forgotten.
    rx, rf = gwo.update_leaders(lx, lf, x, f)
    np.testing.assert_array_equal(rf, [1.0, 4.0, np.inf])
    np.testing.assert_array_equal(rx, [[3, 3], [2, 2], [9, 9]])  # empty delta keeps its seat
    dx, df = gwo.update_leaders(lx, lf, x, f, demote=True)  # the true three best
    np.testing.assert_array_equal(df, [1.0, 3.0, 4.0])
    np.testing.assert_array_equal(dx, [[3, 3], [1, 1], [2, 2]])
    # Unevaluated rows (+inf) never become leaders; leaders only ever improve.
    rx2, rf2 = gwo.update_leaders(rx, rf, x + 10, np.array([np.inf, 2.0, np.inf, 0.5]))
    np.testing.assert_array_equal(rf2, [0.5, 2.0, np.inf])
    np.testing.assert_array_equal(rx2[:2], [[13, 13], [11, 11]])


def test_gwo_costs_pop_times_iterations_and_shortens_its_schedule_to_the_budget():
    tf = FUNCTIONS["F1"]
    lower, upper = tf.bounds
    res = minimize(tf, lower, upper, "gwo", seed=0, pop_size=20, iterations=50)
    assert res.n_evals == 20 * 50 and res.history.shape == (50,)
    ev = Evaluator(tf, lower, upper, max_evals=2990)
    assert gwo.schedule_length(ev, 30, 200) == 100  # 99 full batches and a partial one
    assert gwo.schedule_length(Evaluator(tf, lower, upper), 30, 200) == 200


# ------------------------------------------------------------- GWO against [MGWO]
def test_gwo_reproduces_paper_003_on_f1_and_f4():
    # [MGWO], Table 3 (30 wolves, 200 iterations): F1 9.38e-9, F4 -3.8609.
    f1 = mean_fun("F1", "gwo", range(5))
    assert 1e-10 < f1 < 1e-6
    f4 = mean_fun("F4", "gwo", range(5))
    assert abs(f4 - FUNCTIONS["F4"].f_min) < 1e-2


def niapy_problem(tf):
    """A benchmark function of :mod:`swarm_ik.testfunctions` as a niapy ``Problem``."""
    from niapy.problems import Problem

    class Wrapped(Problem):
        def __init__(self):
            super().__init__(dimension=tf.dim, lower=tf.lower, upper=tf.upper)

        def _evaluate(self, x):
            return float(tf(np.asarray(x)[None])[0])

    return Wrapped()


def test_gwo_matches_niapy_grey_wolf_optimizer():
    niapy = pytest.importorskip("niapy", reason="cross-check needs niapy (pip install niapy)")
    from niapy.algorithms.basic import GreyWolfOptimizer
    from niapy.task import Task

    assert niapy is not None
    for key in ("F1", "F3"):
        tf = FUNCTIONS[key]
        theirs = np.mean(
            [
                GreyWolfOptimizer(population_size=30, seed=s).run(
                    Task(problem=niapy_problem(tf), max_evals=30 * 200)
                )[1]
                for s in range(3)
            ]
        )
        ours = mean_fun(key, "gwo", range(3))
        if key == "F1":  # both ~1e-8: same order of magnitude
            assert abs(np.log10(ours) - np.log10(theirs)) < 1.0
        else:  # Rastrigin, both ~15
            assert 0.5 < ours / theirs < 2.0


# ------------------------------------------------------------------------------ MGWO
def test_mgwo_on_benchmarks():
    # F4: MGWO's sub-packs find the global minimum more reliably than GWO ([MGWO] Table 3:
    # -3.8628 vs -3.8609); F1: right order of magnitude for 3 sub-packs of 10 wolves.
    f4_m = mean_fun("F4", "mgwo", range(20))
    f4_g = mean_fun("F4", "gwo", range(20))
    assert f4_m < f4_g
    assert abs(f4_m - FUNCTIONS["F4"].f_min) < 1e-3
    assert mean_fun("F1", "mgwo", range(5)) < 1e-2


def test_mgwo_beats_gwo_on_paper_003_ik_problem(get_robot):
    robot = get_robot("loading_manipulator_long")
    problem = swarm_ik.IKProblem(robot, robot.fk(PAPER_X_STAR[None])[0], fitness="euler-zyz")

    def fits(solver):
        return np.array(
            [
                swarm_ik.solve(problem, solver, seed=s, stop_on_success=False).fitness
                for s in range(20)
            ]
        )

    g, m = fits("gwo"), fits("mgwo")
    # Measured on seeds 0-19: mean 0.056 vs 0.081, worst 0.149 vs 0.427 (on seeds 20-39:
    # 0.065 vs 0.210, worst 0.135 vs 0.874).  [MGWO], Table 4: 0.0122 vs 0.4292.
    assert m.mean() < 0.8 * g.mean()
    assert m.max() < 0.5 * g.max()


def test_mgwo_reinitialises_a_subpack_after_gamma_times_t_stagnant_iterations():
    def flat(x):
        return np.zeros(x.shape[0])  # the king never improves after the first iteration

    lower, upper = -np.ones(2), np.ones(2)
    rng = np.random.default_rng(0)
    ev = CountingEvaluator(flat, lower, upper)
    mgwo.run(ev, rng, pop_size=30, iterations=100, subpops=3, gamma=0.1)
    # The initial population, then a re-init each time the count exceeds r = 10: at
    # t = 11, 22, ..., 88 (no move after the last evaluation, t = 99).
    assert ev.uniform_calls == [30] + [10] * 8
    ev = CountingEvaluator(flat, lower, upper)
    mgwo.run(ev, np.random.default_rng(0), pop_size=30, iterations=100, gamma=0.99)
    assert ev.uniform_calls == [30]
    # An objective that keeps improving never triggers it.
    ev = CountingEvaluator(FUNCTIONS["F1"], *FUNCTIONS["F1"].bounds)
    mgwo.run(ev, np.random.default_rng(0), pop_size=30, iterations=100, gamma=0.1)
    assert ev.uniform_calls == [30]


def test_mgwo_with_one_subpack_and_no_pso_pull_is_gwo():
    # m = 1 and c1 = c2 = ω = 0: the worst wolf stands still for one iteration instead of
    # moving; the result is close to GWO's, not identical (different draws).
    f = mean_fun("F1", "mgwo", range(5), subpops=1, omega=0.0, c1=0.0, c2=0.0)
    assert 1e-10 < f < 1e-6


def test_mgwo_and_gwo_validate_parameters():
    tf = FUNCTIONS["F4"]
    lower, upper = tf.bounds
    with pytest.raises(InvalidArgumentError, match="subpops"):
        minimize(tf, lower, upper, "mgwo", pop_size=4, subpops=5)
    with pytest.raises(InvalidArgumentError, match="gamma"):
        minimize(tf, lower, upper, "mgwo", gamma=1.0)
    with pytest.raises(InvalidArgumentError, match="v_max"):
        minimize(tf, lower, upper, "mgwo", v_max=0.0)
    with pytest.raises(InvalidArgumentError, match="pop_size"):
        minimize(tf, lower, upper, "gwo", pop_size=0)


# -------------------------------------------------------------------------------- CS
def test_mantegna_sigma_and_levy_steps():
    assert cs.mantegna_sigma(1.5) == pytest.approx(
        0.6965745, rel=1e-6
    )  # the value of [CS]'s reference code
    a = cs.levy_steps(np.random.default_rng(3), (200_000,), 1.5)
    b = cs.levy_steps(np.random.default_rng(3), (200_000,), 1.5)
    np.testing.assert_array_equal(a, b)
    assert np.all(np.isfinite(a))
    assert abs(np.median(a)) < 0.01  # symmetric
    # Power-law tail P(|L| > s) ~ s^-beta: the slope between s = 10 and s = 100 is about -1.5
    # (a Gaussian of the same scale would have no sample at all beyond 10).
    s = np.array([10.0, 100.0])
    surv = np.array([(np.abs(a) > v).mean() for v in s])
    slope = np.diff(np.log(surv))[0] / np.diff(np.log(s))[0]
    assert -1.7 < slope < -1.3
    assert surv[0] > 0.01


def test_cs_finds_the_hartmann3_minimum():
    tf = FUNCTIONS["F4"]
    lower, upper = tf.bounds
    for seed in range(3):
        res = minimize(tf, lower, upper, "cs", seed=seed, iterations=100)
        assert res.n_evals == 50 * (2 * 100 + 1)
        assert res.fun - tf.f_min < 1e-3
        assert np.all(res.x >= lower) and np.all(res.x <= upper)


def test_cs_matches_niapy_cuckoo_search():
    pytest.importorskip("niapy", reason="cross-check needs niapy (pip install niapy)")
    from niapy.algorithms.basic import CuckooSearch
    from niapy.task import Task

    tf = FUNCTIONS["F1"]
    theirs = np.mean(
        [
            CuckooSearch(population_size=50, pa=0.25, seed=s).run(
                Task(problem=niapy_problem(tf), max_evals=5000)
            )[1]
            for s in range(3)
        ]
    )
    ours = mean_fun("F1", "cs", range(3), max_evals=5000)
    assert 0.8 < ours / theirs < 1.25


def test_newton_rate_decays_from_eta0_to_eta_t():
    rates = [cs.newton_rate(n, 1.0, 0.001, 100.0) for n in (0, 10, 100, 10_000)]
    assert rates[0] == 1.0
    assert rates[1] == pytest.approx(0.001 + 0.999 * np.exp(-0.1))
    assert rates[0] > rates[1] > rates[2] > rates[3] == pytest.approx(0.001)


def test_cs_newton_polishes_what_cs_alone_cannot(get_robot):
    robot = get_robot("loading_manipulator_long")
    q = robot.random_q(np.random.default_rng(11))
    problem = swarm_ik.IKProblem.from_q(robot, q)
    kw = {"seed": 1, "max_evals": 20_000}
    plain = swarm_ik.solve(problem, "cs", **kw)
    polished = swarm_ik.solve(problem, "cs-newton", **kw)
    assert not plain.success and plain.fitness > 1e-3
    assert polished.success and polished.within_limits
    # The search ran until the fitness first dropped below eps = 0.2, then Newton took over.
    h = polished.history
    switch = int(np.argmax(h < 0.2))
    assert 0 < switch < len(h) - 1
    assert h[-1] < 1e-4 * h[switch]
    # A threshold that is never reached: no Newton step, the run is exactly cs's.
    never = swarm_ik.solve(problem, "cs-newton", eps=1e-12, **kw)
    np.testing.assert_array_equal(never.q, plain.q)
    assert never.n_evals == plain.n_evals


def test_cs_newton_needs_an_ik_problem_and_cs_validates():
    tf = FUNCTIONS["F4"]
    lower, upper = tf.bounds
    with pytest.raises(InvalidArgumentError, match="IK problem"):
        minimize(tf, lower, upper, "cs-newton")
    with pytest.raises(InvalidArgumentError, match="beta"):
        minimize(tf, lower, upper, "cs", beta=2.0)
    with pytest.raises(InvalidArgumentError, match="pa"):
        minimize(tf, lower, upper, "cs", pa=1.5)


def _reference_leaders(lx, lf, x, f):  # type: ignore[no-untyped-def]
    """GWO.m's leader rule as written there: the wolves visited one by one."""
    lx, lf = lx.copy(), lf.copy()
    fa, fb, fd = (float(v) for v in lf)
    for i, fi in enumerate(f.tolist()):
        if fi < fa:
            fa = fi
            lx[0] = x[i]
        if fa < fi < fb:
            fb = fi
            lx[1] = x[i]
        if fi > fa and fi > fb and fi < fd:
            fd = fi
            lx[2] = x[i]
    lf[:] = (fa, fb, fd)
    return lx, lf


def test_the_leader_rule_computed_whole_is_the_reference_loop() -> None:
    """update_leaders computes the reference rule with running minima (a Python loop over
    10^6 wolves took 0.5 s past a time limit): the same leaders as GWO.m's loop on random
    batches with ties, +inf and NaN, from empty and from earlier leaders."""
    rng = np.random.default_rng(0)
    for trial in range(2000):
        p = int(rng.integers(1, 12))
        f = rng.integers(0, 6, size=p).astype(float)
        f[rng.random(p) < 0.15] = np.inf
        f[rng.random(p) < 0.1] = np.nan
        x = rng.normal(size=(p, 3))
        lx, lf = gwo.init_leaders(rng.normal(size=3))
        if trial % 2:  # (earlier leaders, in any order, +inf and NaN among them)
            lx = rng.normal(size=(3, 3))
            lf = rng.integers(0, 6, size=3).astype(float)
            lf[rng.random(3) < 0.2] = np.inf
            lf[rng.random(3) < 0.1] = np.nan
        got = gwo.update_leaders(lx, lf, x, f)
        want = _reference_leaders(lx, lf, x, f)
        np.testing.assert_array_equal(got[1], want[1])  # (NaN equal to NaN here)
        np.testing.assert_array_equal(got[0], want[0])
