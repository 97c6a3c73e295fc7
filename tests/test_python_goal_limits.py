"""Every budget covers the whole call, with goals written in Python too: a slow Python goal
(25 ms a call, the target out of reach) is never called before the clock starts (the warm-up
runs stand-ins), the searches read the clock between its evaluations, and the answer is judged
from the values the search computed, so ``solve`` and ``solve_many`` end within their
``time_limit`` and a few goal calls; a fast goal is still met, each of its values computed
once per point."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest
from conftest import robot

import swarm_ik
from swarm_ik import api, solvers
from swarm_ik.goals import Goal

CALL_S = 0.025
"""Seconds one call of the slow goal's residual or Jacobian takes."""
LIMIT = 0.1
SLACK = 4 * CALL_S
"""What a call may take past its limit: the evaluation running when the time ran out and
the judge (a few goal calls)."""


@dataclass(frozen=True)
class Height(Goal):
    """The tool at height ``z`` (one row), each call sleeping ``delay`` seconds and counted."""

    z: float = 5.0
    delay: float = CALL_S
    frame: str = "panda_hand_tcp"
    calls: ClassVar[dict[str, int]] = {"residual": 0, "jacobian": 0}

    def residual(self, state: swarm_ik.goals.State) -> np.ndarray:
        self.calls["residual"] += 1
        time.sleep(self.delay)
        return np.array([state.pose(self.frame)[2, 3] - self.z])

    def jacobian(self, state: swarm_ik.goals.State) -> np.ndarray:
        self.calls["jacobian"] += 1
        time.sleep(self.delay)
        return state.jacobian(self.frame)[2:3]


@pytest.fixture()
def calls() -> dict[str, int]:
    Height.calls.update(residual=0, jacobian=0)
    return Height.calls


def _slow_problem() -> swarm_ik.IKProblem:
    return swarm_ik.IKProblem(robot("panda"), goals=[Height()])  # (5 m up: out of reach)


def _timed(func, *args, **kwargs):  # type: ignore[no-untyped-def]
    t0 = time.perf_counter()
    out = func(*args, **kwargs)
    return out, time.perf_counter() - t0


def test_the_warm_up_never_calls_a_python_goal(
    monkeypatch: pytest.MonkeyPatch, calls: dict[str, int]
) -> None:
    """A new route loads its kernels on stand-ins of the Python goals: the first solve of a
    slow goal (a warm-up of 200 evaluations of it took 25 s at 50 ms a call) stays bounded."""
    p = _slow_problem()
    calls.update(residual=0, jacobian=0)  # (making the problem checked its Jacobian once)
    monkeypatch.setattr(api, "_COMPILED", set())  # (as in a fresh process: a new route)
    monkeypatch.setitem(p.robot._cache, "routes", {})
    res, took = _timed(swarm_ik.solve, p, time_limit=LIMIT, seed=11)
    assert not res.success and res.reason == "time_limit"
    assert took < 1.0
    assert calls["residual"] <= 3 and calls["jacobian"] <= 3


@pytest.mark.parametrize("solver", ["swarm", "gwo"])
def test_solve_with_a_slow_python_goal_keeps_its_time_limit(
    solver: str, calls: dict[str, int]
) -> None:
    """The default solver's numpy polish starts no evaluation after the deadline and its
    answer is judged from the values it computed (5 polish evaluations and 4 more residuals
    took 0.71 s of a 0.1 s limit at 50 ms a call); a population solver's evaluator reads the
    clock after each row of a slow objective (a population of 30 took 1.6 s)."""
    p = _slow_problem()
    swarm_ik.solve(p, solver, time_limit=LIMIT, seed=1)  # (the route made, its kernels loaded)
    calls.update(residual=0, jacobian=0)
    res, took = _timed(swarm_ik.solve, p, solver, time_limit=LIMIT)
    assert not res.success and res.reason == "time_limit"
    assert took < LIMIT + SLACK, took
    assert calls["residual"] + calls["jacobian"] <= 6


def test_solve_many_with_a_slow_python_goal_keeps_its_time_limit(calls: dict[str, int]) -> None:
    """The numerical search of ``solve_many`` hands its deadline to the numpy polish (a round
    of 16 starts polished to their end took 11 s of a 0.1 s limit at 50 ms a call)."""
    p = _slow_problem()
    swarm_ik.solve_many(p, n=2, time_limit=LIMIT, method="numerical")  # (kernels loaded)
    calls.update(residual=0, jacobian=0)
    sols, took = _timed(swarm_ik.solve_many, p, n=2, time_limit=LIMIT, method="numerical")
    assert sols == []  # (out of reach: no solution)
    assert took < LIMIT + SLACK, took
    assert calls["residual"] + calls["jacobian"] <= 6


def test_a_slow_objective_is_evaluated_in_blocks_that_follow_its_cost() -> None:
    """Under a time limit an evaluator's first block is one row and the next ones follow the
    cost per row measured (a block of 4096 rows of a 20 ms objective would take 80 s)."""
    rows: list[int] = []

    def slow(x: np.ndarray) -> np.ndarray:
        rows.append(x.shape[0])
        time.sleep(0.02 * x.shape[0])
        return np.sum(x * x, axis=1)

    ev = solvers.Evaluator(slow, np.full(2, -1.0), np.full(2, 1.0), time_limit=0.05)
    f, took = _timed(ev, np.full((100, 2), 0.5))
    assert took < 0.05 + 0.05 and ev.n_evals == sum(rows) <= 4 and max(rows) == 1
    assert np.all(np.isfinite(f[: ev.n_evals])) and np.all(np.isinf(f[ev.n_evals :]))


def test_blocks_change_no_result_where_the_limit_does_not_bite() -> None:
    """The rows of a request are offered for the best together, whatever its blocks: a stop
    criterion met in its first rows ends no request early, so under a time limit that does
    not bite the answer and the count are those without one (blocks of 4096 rows once ended
    a population of 5000 at its first block, at a worse point)."""

    def sphere(x: np.ndarray) -> np.ndarray:
        return np.sum(x * x, axis=1)

    pop = np.random.default_rng(0).uniform(0.5, 1.0, (5000, 3))
    pop[0] = 0.01  # (meets the target in the first row; a later row is better still)
    pop[4500] = 0.0
    out = []
    for limit in (None, 100.0):
        ev = solvers.Evaluator(
            sphere, np.full(3, -1.0), np.full(3, 1.0), time_limit=limit, f_target=1e-3
        )
        ev(pop)
        out.append((ev.n_evals, ev.best_f, ev.best_x.tolist(), ev.stopped))
    assert out[0] == (5000, 0.0, [0.0] * 3, True)
    assert out[1] == out[0]


def test_a_fast_python_goal_is_met_and_each_value_computed_once(
    monkeypatch: pytest.MonkeyPatch, calls: dict[str, int]
) -> None:
    """A fast reachable goal is still met, on a new route too; its residual is computed once
    per point evaluated (the polish's rows and errors, the stop test and the judge read one
    evaluation: before, the errors, the stop test and the judge each called it again, and a
    new route's warm-up ran hundreds of evaluations of it)."""
    p = swarm_ik.IKProblem(robot("panda"), goals=[Height(z=0.5, delay=0.0)])
    monkeypatch.setattr(api, "_COMPILED", set())
    monkeypatch.setitem(p.robot._cache, "routes", {})
    res = swarm_ik.solve(p, time_limit=1.0, seed=3)
    assert res.success and res.reason == "converged"
    assert calls["residual"] <= res.n_evals
    sols = swarm_ik.solve_many(p, n=2, seed=3, max_evals=400, method="numerical")
    assert len(sols) == 2 and all(s.success for s in sols)
