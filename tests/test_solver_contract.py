"""One contract, every registered solver (nevergrad's parametrised optimizer test)."""

from __future__ import annotations

import importlib
import time

import numpy as np
import pytest

import swarm_ik
from swarm_ik import solvers

NAMES = solvers.search_names()
Q_STAR = np.array([0.7, 1.1])  # positive angles: even basic FOA (S > 0) can reach them


@pytest.fixture(scope="module")
def planar(planar2_urdf: str) -> swarm_ik.RobotModel:
    return swarm_ik.load_robot(planar2_urdf, ee_frame="tip")


def _problem(planar: swarm_ik.RobotModel) -> swarm_ik.IKProblem:
    return swarm_ik.IKProblem.from_q(planar, Q_STAR)


def test_registry_lists_the_solvers_and_refuses_duplicates() -> None:
    assert "dls" in NAMES
    spec = solvers.get("dls")
    with pytest.raises(swarm_ik.InvalidArgumentError, match="already registered"):
        solvers.register("dls", spec.run)
    with pytest.raises(swarm_ik.UnknownNameError, match="valid solvers: .*dls"):
        solvers.get("nope")


@pytest.mark.parametrize("name", NAMES)
def test_budget_is_respected_exactly(name: str, planar: swarm_ik.RobotModel) -> None:
    res = swarm_ik.solve(_problem(planar), name, seed=1, max_evals=437, stop_on_success=False)
    assert 1 <= res.n_evals <= 437
    assert len(res.history) >= 1


@pytest.mark.parametrize("name", NAMES)
def test_result_within_bounds_and_finite(name: str, get_robot) -> None:
    r = get_robot("loading_manipulator")
    x_star = np.array([np.pi / 4, np.pi / 6, np.pi / 4, 0.8, 1, 1, np.pi / 6, -np.pi / 4])
    target = r.fk(x_star)  # outside this robot's limits: unreachable
    res = swarm_ik.solve(swarm_ik.IKProblem(r, target, "euler-zyz"), name, seed=0, max_evals=600)
    assert res.within_limits
    assert np.all(res.q >= r.lower) and np.all(res.q <= r.upper)
    assert not res.success and np.isfinite(res.fitness) and np.isfinite(res.position_error)


@pytest.mark.parametrize("name", NAMES)
def test_same_seed_same_result_other_seed_other_run(name: str, get_robot) -> None:
    # an unreachable target, so that every solver keeps searching (restarts, swarms)
    r = get_robot("loading_manipulator")
    x_star = np.array([np.pi / 4, np.pi / 6, np.pi / 4, 0.8, 1, 1, np.pi / 6, -np.pi / 4])
    prob = swarm_ik.IKProblem(r, r.fk(x_star), "euler-zyz")
    a = swarm_ik.solve(prob, name, seed=3, max_evals=500, stop_on_success=False)
    b = swarm_ik.solve(prob, name, seed=3, max_evals=500, stop_on_success=False)
    c = swarm_ik.solve(prob, name, seed=4, max_evals=500, stop_on_success=False)
    assert a.q.tobytes() == b.q.tobytes() and a.n_evals == b.n_evals
    np.testing.assert_array_equal(a.history, b.history)
    assert a.q.tobytes() != c.q.tobytes() or not np.array_equal(a.history, c.history)


@pytest.mark.parametrize("name", NAMES)
def test_converges_on_a_two_link_arm(name: str, planar: swarm_ik.RobotModel) -> None:
    prob = _problem(planar)
    res = swarm_ik.solve(prob, name, seed=0, max_evals=20000, tol_pos=1e-4, tol_rot=1e-4)
    assert res.position_error < 1e-2, res
    assert res.rotation_error < 1e-2, res


class _NaNProblem(swarm_ik.IKProblem):
    """Returns NaN fitness wherever q[0] > 1.0 (a third of the first joint's range)."""

    def _poison(self, q: np.ndarray, f: np.ndarray) -> np.ndarray:
        return np.where(np.atleast_2d(q)[:, 0] > 1.0, np.nan, f)

    def fitness(self, q_batch):  # type: ignore[override]
        return self._poison(q_batch, super().fitness(q_batch))

    def residual_jacobian(self, q_batch):  # type: ignore[override]
        f, err, jac = super().residual_jacobian(q_batch)
        return self._poison(q_batch, f), err, jac


@pytest.mark.parametrize("name", NAMES)
def test_survives_nan_fitness(name: str, planar: swarm_ik.RobotModel) -> None:
    prob = _NaNProblem(planar, planar.fk(Q_STAR))
    res = swarm_ik.solve(prob, name, seed=0, max_evals=2000)
    assert res.within_limits and np.all(np.isfinite(res.q))
    assert np.isfinite(res.position_error)


# ------------------------------------------------------------- registry metadata
def test_registered_papers_are_keys_of_the_references() -> None:
    import re
    from pathlib import Path

    refs = (Path(__file__).parents[1] / "docs" / "references.md").read_text()
    keys = set(re.findall(r"^\*\*\[([\w-]+)\]\*\*", refs, flags=re.MULTILINE))
    assert {"HLFOA", "MGWO", "GWO", "DLS"} <= keys
    papers = {n: solvers.get(n).paper for n in solvers.names()}
    assert papers["hlfoa"] == "HLFOA" and papers["mgwo"] == "MGWO" and papers["dls"] == "DLS"
    for name, key in papers.items():
        assert key is None or key in keys, (name, key)


def test_schedule_spends_a_budget_by_the_registered_facts() -> None:
    dls = solvers.get("dls")
    assert dls.evals_per_iteration == 1 and dls.needs_jacobian
    assert dls.schedule(1234) == {"iterations": 1234, "max_evals": 1234}
    gwo = solvers.get("gwo")  # 30 wolves: ceil(1000 / 30) = 34 iterations
    assert gwo.evals_per_iteration is None and not gwo.budget_only
    assert gwo.schedule(1000) == {"iterations": 34, "max_evals": 1000}
    with pytest.raises(swarm_ik.InvalidArgumentError, match="evals_per_iteration"):
        solvers.register("dls-bad-facts", dls.run, evals_per_iteration=0)
    assert "dls-bad-facts" not in solvers.names()


# ------------------------------------------------------------- one budget rule, on_improvement
class _Improvements:
    def __init__(self) -> None:
        self.x: list[np.ndarray] = []
        self.f: list[float] = []

    def __call__(self, x: np.ndarray, f: float) -> None:
        self.x.append(x)
        self.f.append(f)


@pytest.mark.parametrize("name", NAMES)
def test_on_improvement_sees_every_new_best(name: str, planar: swarm_ik.RobotModel) -> None:
    prob = _problem(planar)
    spec = solvers.get(name)
    rec = _Improvements()
    ev = solvers.Evaluator(
        prob.fitness, prob.lower, prob.upper, max_evals=1500, problem=prob, on_improvement=rec
    )
    spec.run(ev, np.random.default_rng(0), **spec.params)
    assert rec.f, name
    assert np.all(np.diff(rec.f) < 0), "each call is a strict improvement"
    assert rec.f[-1] == ev.best_f and np.array_equal(rec.x[-1], ev.best_x)
    # each reported fitness is the problem's own at the reported point (the compiled swarm
    # kernel computes it with its own arithmetic: equal to rounding)
    f_true = prob.fitness(np.array(rec.x))
    np.testing.assert_allclose(rec.f, f_true, rtol=1e-6, atol=1e-12)
    rec.x[-1][0] += 1.0  # the callback gets a copy
    assert not np.array_equal(rec.x[-1], ev.best_x)


def _sphere_ev(max_evals: int, **kw):
    return solvers.Evaluator(
        lambda x: np.sum(x * x, axis=1),
        -np.ones(2),
        np.ones(2),
        max_evals=max_evals,
        **kw,
    )


def test_evaluating_never_overdraws_the_budget(planar: swarm_ik.RobotModel) -> None:
    ev = _sphere_ev(5)
    f = ev(np.full((8, 2), 0.5))
    assert ev.n_evals == 5 and np.all(np.isfinite(f[:5])) and np.all(np.isinf(f[5:]))
    assert np.all(np.isinf(ev(np.zeros((3, 2))))) and ev.n_evals == 5  # spent: none evaluated
    prob = _problem(planar)
    ev = solvers.Evaluator(prob.fitness, prob.lower, prob.upper, max_evals=2, problem=prob)
    f, err, jac = ev.residual_jacobian(np.tile(Q_STAR, (3, 1)))  # the same rule, no raise
    assert ev.n_evals == 2
    assert np.all(np.isfinite(f[:2])) and np.all(np.isfinite(jac[:2])) and np.isinf(f[2])
    assert np.all(np.isnan(err[2])) and np.all(np.isnan(jac[2]))


def test_charging_refuses_an_overdraft_and_counts_work_done_after_the_time_limit() -> None:
    ev = _sphere_ev(4)
    with pytest.raises(swarm_ik.InvalidArgumentError, match="remaining budget is 4"):
        ev.record(np.zeros((5, 2)), np.zeros(5))
    with pytest.raises(swarm_ik.InvalidArgumentError, match="remaining budget is 4"):
        ev.add_evals(5)
    assert ev.n_evals == 0
    late = _sphere_ev(10, time_limit=1e-9)
    assert late.done and np.all(np.isinf(late(np.zeros((2, 2))))) and late.n_evals == 0
    out = late.record(np.array([[0.1, 0.2]]), np.array([np.nan]))  # work started in time
    assert late.n_evals == 1 and np.isinf(out[0])
    late.add_evals(2, np.array([0.3, 0.0]), 0.09)
    assert late.n_evals == 3 and late.best_f == 0.09


def test_no_point_is_taken_after_the_stop_criterion() -> None:
    rec = _Improvements()
    ev = _sphere_ev(100, f_target=0.5, on_improvement=rec)
    ev(np.array([[0.6, 0.6], [0.5, 0.0]]))  # 0.72 then 0.25: the batch's best meets the target
    assert ev.stopped and ev.best_f == 0.25 and rec.f == [0.25]
    ev.add_evals(1, np.zeros(2), 0.0)  # charged, but the answer stays the first success
    ev.record(np.zeros((1, 2)), np.zeros(1))
    assert ev.n_evals == 4 and ev.best_f == 0.25 and rec.f == [0.25]


def test_a_large_population_stops_at_the_time_limit() -> None:
    """Under a time limit a population is evaluated in blocks with the clock read between
    them: rows after the limit are not evaluated (fitness +inf) nor charged."""
    slow_rows: list[int] = []

    def slow(x: np.ndarray) -> np.ndarray:
        slow_rows.append(x.shape[0])
        time.sleep(0.02)
        return np.sum(x * x, axis=1)

    pop = 10 * solvers.base.TIMED_CHUNK
    ev = solvers.Evaluator(slow, np.full(2, -1.0), np.full(2, 1.0), time_limit=0.03)
    f = ev(np.full((pop, 2), 0.5))
    assert 1 <= len(slow_rows) < 10 and ev.n_evals == sum(slow_rows) < pop
    assert np.all(np.isfinite(f[: ev.n_evals])) and np.all(np.isinf(f[ev.n_evals :]))
    whole = solvers.Evaluator(slow, np.full(2, -1.0), np.full(2, 1.0))  # no limit: one call
    slow_rows.clear()
    assert np.all(np.isfinite(whole(np.full((pop, 2), 0.5)))) and slow_rows == [pop]


@pytest.mark.parametrize("name", ["gwo", "mgwo"])
def test_no_move_is_made_after_the_stop(name: str, planar: swarm_ik.RobotModel) -> None:
    """A pack that met the tolerance in its first evaluation ends there (a move after it would
    never be evaluated: with a million wolves it cost seconds past the time limit)."""
    moves: list[int] = []
    module = importlib.import_module(f"swarm_ik.solvers.{name}")
    original = module.gwo_move

    def counted(*args: object, **kwargs: object) -> np.ndarray:
        moves.append(1)
        return original(*args, **kwargs)  # type: ignore[no-any-return]

    module.gwo_move = counted
    try:
        res = swarm_ik.solve(_problem(planar), name, seed=0, q0=Q_STAR, pop_size=8)
    finally:
        module.gwo_move = original
    assert res.success and res.n_evals == 8 and moves == []
