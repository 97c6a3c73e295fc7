"""``Result`` cannot change after it was judged: its arrays (``q``, ``history``) are read-only
copies, whatever route made it (the constructor, ``dataclasses.replace``, ``copy``, pickle,
``solve``, ``IKSolver.solve``, ``solve_many``, ``windings_of``, the analytic solver)."""

from __future__ import annotations

import copy
import dataclasses
import pickle

import numpy as np
import pytest

import swarm_ik
from swarm_ik.result import Result


def _result(q: object = None, history: object = None) -> Result:
    return Result(
        q=np.linspace(0.0, 0.6, 7) if q is None else q,
        fitness=0.5,
        position_error=0.1,
        rotation_error=0.2,
        n_evals=10,
        time_s=0.01,
        success=False,
        within_limits=True,
        history=np.array([2.0, 1.0, 0.5]) if history is None else history,
        solver="swarm",
        seed=0,
    )


def _assert_read_only(r: Result) -> None:
    for name in ("q", "history"):
        arr = getattr(r, name)
        assert isinstance(arr, np.ndarray) and arr.dtype == np.float64
        assert not arr.flags.writeable, name
        if arr.size:
            with pytest.raises(ValueError, match="read-only"):
                arr[0] = 1.0
        with pytest.raises(ValueError, match="read-only"):
            arr[:] = 0.0
        with pytest.raises(ValueError, match="read-only"):
            arr += 1.0
        mine = arr.copy()  # the documented way to a writable array
        assert mine.flags.writeable
        mine[...] = -1.0
        assert not np.any(arr == -1.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.q = np.zeros(3)  # type: ignore[misc]


def test_arrays_are_read_only_and_copies_writable() -> None:
    r = _result()
    _assert_read_only(r)
    with pytest.raises(ValueError):
        r.q[0] = 1.0


def test_the_callers_arrays_are_copied_not_frozen() -> None:
    q, hist = np.linspace(0.0, 0.6, 7), np.array([2.0, 1.0])
    r = _result(q, hist)
    assert q.flags.writeable and hist.flags.writeable  # the caller's arrays untouched
    q[:] = 9.0
    hist[:] = 9.0  # a later change to them does not reach the result
    np.testing.assert_array_equal(r.q, np.linspace(0.0, 0.6, 7))
    np.testing.assert_array_equal(r.history, [2.0, 1.0])


@pytest.mark.parametrize(
    ("q", "history"),
    [
        ([0.1, 0.2, 0.3], [1.0]),  # lists
        (np.arange(3), np.arange(2)),  # integers
        (np.linspace(0, 1, 6)[::2], np.empty(0)),  # a strided view, an empty history
        (np.zeros((4, 3))[1], np.array([1.0], dtype=np.float32)),  # a row, float32
        (np.linspace(0, 1, 3).astype(">f8"), np.ones(2)),  # big-endian float64
    ],
)
def test_any_input_becomes_a_read_only_float_copy(q: object, history: object) -> None:
    r = _result(q, history)
    _assert_read_only(r)
    np.testing.assert_array_equal(r.q, np.asarray(q, dtype=float))
    np.testing.assert_array_equal(r.history, np.asarray(history, dtype=float))


def test_replace_copy_and_pickle_keep_arrays_read_only() -> None:
    r = _result()
    for other in (
        dataclasses.replace(r, time_s=1.0),
        dataclasses.replace(r, q=np.ones(7)),
        copy.copy(r),
        copy.deepcopy(r),
        pickle.loads(pickle.dumps(r)),
    ):
        _assert_read_only(other)
        np.testing.assert_array_equal(other.history, r.history)
    assert dataclasses.replace(r, time_s=1.0).q is r.q  # (already immutable: shared)
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(r)).q, r.q)


def test_to_dict_and_repr_unchanged() -> None:
    r = _result()
    d = r.to_dict()
    assert d["q"] == pytest.approx(np.linspace(0.0, 0.6, 7).tolist())
    assert d["history"] == [2.0, 1.0, 0.5] and d["solver"] == "swarm"
    assert "q=[0.0, 0.1," in repr(r)


# ----------------------------------------------------------------------- the API's results
@pytest.fixture(scope="module")
def panda() -> swarm_ik.RobotModel:
    return swarm_ik.load_robot("panda")


def test_solve_result_is_read_only(panda: swarm_ik.RobotModel) -> None:
    problem = swarm_ik.IKProblem.from_q(panda, panda.mid_q() + 0.1)
    r = swarm_ik.solve(problem, seed=0)
    assert r.success
    _assert_read_only(r)
    # a Python solver (the Evaluator route) too
    r = swarm_ik.solve(problem, "dls", seed=0, max_evals=200)
    _assert_read_only(r)
    # a read-only q can seed the next solve
    again = swarm_ik.solve(problem, seed=1, q0=r.q)
    _assert_read_only(again)


def test_ik_solver_result_is_read_only(panda: swarm_ik.RobotModel) -> None:
    ik = swarm_ik.IKSolver(panda, time_limit=0.05)
    target = panda.fk(panda.mid_q() + 0.2)
    r1 = ik.solve(target, seed=0)
    q1 = r1.q.copy()
    _assert_read_only(r1)
    r2 = ik.solve(panda.fk(panda.mid_q() - 0.2), q0=r1.q, seed=1)
    _assert_read_only(r2)
    np.testing.assert_array_equal(r1.q, q1)  # the next solve on the same route left it alone


def test_solve_many_results_are_read_only() -> None:
    ur5 = swarm_ik.load_robot("ur5")
    problem = swarm_ik.IKProblem.from_q(ur5, np.array([0.3, -1.0, 1.2, -0.5, 1.1, 0.2]))
    sols = swarm_ik.solve_many(problem, n=4, method="numerical")
    assert sols
    for r in sols:
        _assert_read_only(r)
    for group in swarm_ik.windings_of(problem, sols[:1]):
        for r in group[:3]:
            _assert_read_only(r)


def test_analytic_result_is_read_only() -> None:
    pytest.importorskip("eaik")
    ur5 = swarm_ik.load_robot("ur5")
    problem = swarm_ik.IKProblem.from_q(ur5, np.array([0.3, -1.0, 1.2, -0.5, 1.1, 0.2]))
    _assert_read_only(swarm_ik.solve(problem, "analytic"))


def test_a_results_q_feeds_the_problems_batched_functions() -> None:
    """``problem.fitness(r.q[None])`` takes the read-only ``q`` as any other array (the
    compiled kernels need a writable one: :meth:`IKProblem._errors_and_cost2` copies)."""
    ur5 = swarm_ik.load_robot("ur5")
    problem = swarm_ik.IKProblem.from_q(ur5, np.array([0.3, -1.0, 1.2, -0.5, 1.1, 0.2]))
    r = swarm_ik.solve(problem, seed=0)
    assert float(problem.fitness(r.q[None])[0]) == pytest.approx(r.fitness, abs=1e-12)
    assert problem.goal_errors(r.q[None]).shape == (1, 1, 2)


def test_batch_and_path_results_are_read_only_too() -> None:
    """The rows of a BatchResult and the path of a PathResult cannot change after their
    check (frozen dataclasses whose arrays were writable)."""
    robot = swarm_ik.load_robot("panda")
    rng = np.random.default_rng(3)
    q = robot.random_q(rng, 4)
    batch = swarm_ik.solve_batch(robot, robot.fk(q))
    for arr in (batch.q, batch.success, batch.position_error, batch.n_evals):
        with pytest.raises(ValueError):
            arr[0] = arr[1]
    poses = [robot.fk(q[0]), robot.fk(q[0])]
    path = swarm_ik.solve_path(robot, poses, q0=q[0])
    with pytest.raises(ValueError):
        path.q[0, 0] = 1.0
    with pytest.raises(ValueError):
        path.reached[0] = False
    assert path.q.copy().flags.writeable


def test_results_compare_by_identity_and_hash() -> None:
    """``r1 == r2`` raised numpy's ambiguous truth value and ``hash(r)`` a TypeError (the
    generated dataclass equality over array fields)."""
    robot = swarm_ik.load_robot("panda")
    problem = swarm_ik.IKProblem.from_q(robot, robot.mid_q())
    a, b = swarm_ik.solve(problem, seed=0), swarm_ik.solve(problem, seed=0)
    assert a == a and a != b and len({a, b}) == 2
    batch = swarm_ik.solve_batch(robot, robot.fk(robot.mid_q())[None])
    assert batch == batch and hash(batch) == hash(batch)


def test_a_dataclass_subclass_of_result_keeps_read_only_arrays() -> None:
    @dataclasses.dataclass(frozen=True, eq=False)
    class Tagged(Result):
        tag: str = ""

    q = np.zeros(3)
    r = Tagged(q, 0.0, 0.0, 0.0, 1, 0.0, True, True, np.zeros(2), tag="x")
    assert not r.q.flags.writeable and not r.history.flags.writeable
    q[0] = 1.0
    assert r.q[0] == 0.0 and r.tag == "x"
