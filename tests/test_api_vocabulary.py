"""The public API's shared vocabulary and its refusals (a held-out fuzz of every public call):
the five solve calls take and refuse the same values, a value is never read by its
truthiness, a bad value is a SwarmIKError whatever was called before, ``verify`` is
``IKProblem.verify``, and each batch row says why it ended."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import pytest
from conftest import robot

import swarm_ik
from swarm_ik import errors
from swarm_ik.goals import AvoidCollisions, MinimalDisplacement, Orientation, Pose, Position
from swarm_ik.scene import Box, Scene

HUGE = 10**30


@pytest.fixture(scope="module")
def panda() -> swarm_ik.RobotModel:
    return robot("panda")


@pytest.fixture(scope="module")
def target(panda: swarm_ik.RobotModel) -> np.ndarray:
    return panda.fk(panda.random_q(np.random.default_rng(0)))


def _five(panda: swarm_ik.RobotModel, target: np.ndarray) -> dict[str, Any]:
    """The five solve calls on one target, each taking keyword overrides."""
    problem = swarm_ik.IKProblem(panda, target)

    def solve(**kw: Any) -> Any:
        return swarm_ik.solve(problem, **{"max_evals": 2000, **kw})

    def ik_solver(**kw: Any) -> Any:
        seed = kw.pop("seed", 0)
        return swarm_ik.IKSolver(panda, **{"max_evals": 2000, **kw}).solve(target, seed=seed)

    def many(**kw: Any) -> Any:
        return swarm_ik.solve_many(problem, n=2, **{"max_evals": 2000, **kw})

    def batch(**kw: Any) -> Any:
        return swarm_ik.solve_batch(panda, target[None], **kw)

    def path(**kw: Any) -> Any:
        return swarm_ik.solve_path(panda, [target, target], **kw)

    return {"solve": solve, "IKSolver": ik_solver, "solve_many": many, "solve_batch": batch,
            "solve_path": path}  # fmt: skip


@pytest.mark.parametrize(
    "kw",
    [dict(tol_pos=True), dict(tol_rot=True), dict(time_limit=True), dict(tol_pos="1e-5"),
     dict(max_evals=0), dict(max_evals=True), dict(max_evals=2.5)],
    ids=str,
)  # fmt: skip
def test_the_five_solve_calls_refuse_the_same_values(panda, target, kw) -> None:
    for name, call in _five(panda, target).items():
        with pytest.raises(errors.InvalidArgumentError):
            call(**kw)
        assert name  # (each refused)


@pytest.mark.parametrize(
    "kw",
    [dict(tol_pos=np.array(1e-5)), dict(time_limit=np.array(2.0)), dict(seed=None),
     dict(max_evals=np.array(3000))],
    ids=str,
)  # fmt: skip
def test_the_five_solve_calls_take_the_same_values(panda, target, kw) -> None:
    for call in _five(panda, target).values():
        call(**kw)


def test_iteration_counts_beyond_an_int_are_refused_not_sent_to_numba(panda, target) -> None:
    problem = swarm_ik.IKProblem(panda, target)
    for call in (
        lambda: swarm_ik.solve(problem, max_iters=HUGE),
        lambda: swarm_ik.solve_many(problem, max_iters=HUGE),
        lambda: swarm_ik.solve_batch(panda, target[None], max_iters=HUGE),
        lambda: swarm_ik.solve_batch(panda, target[None], max_starts=HUGE),
    ):
        with pytest.raises(errors.InvalidArgumentError, match="max_(iters|starts)"):
            call()


@pytest.mark.parametrize(
    "kw",
    [dict(batch=None), dict(batch=2.0), dict(batch=HUGE), dict(max_starts=2.0),
     dict(max_starts=float("inf")), dict(max_iters="30"), dict(patience=None),
     dict(patience=float("nan")), dict(min_distance="0.1"), dict(min_distance=[0.1])],
    ids=str,
)  # fmt: skip
def test_solve_many_refuses_its_own_bad_parameters(panda, target, kw) -> None:
    name = next(iter(kw))
    with pytest.raises(errors.InvalidArgumentError, match=name):
        swarm_ik.solve_many(swarm_ik.IKProblem(panda, target), n=2, max_evals=500, **kw)


@pytest.mark.parametrize(
    "kw",
    [dict(position_only="False"), dict(progress="yes"), dict(keep_on_interrupt=float("nan")),
     dict(position_only=1)],
    ids=str,
)  # fmt: skip
def test_a_batch_switch_is_true_or_false_never_a_truthy_object(panda, target, kw) -> None:
    with pytest.raises(errors.InvalidArgumentError, match="True or False"):
        swarm_ik.solve_batch(panda, target[None], **kw)


def test_a_refused_value_stays_refused_after_an_accepted_one(panda, target) -> None:
    """The route cache is keyed by value and type: ``True == 1`` and ``2000.0 == 2000``."""
    problem = swarm_ik.IKProblem(panda, target)
    swarm_ik.solve(problem, max_evals=2000, time_limit=1.0)
    with pytest.raises(errors.InvalidArgumentError, match="time_limit"):
        swarm_ik.solve(problem, max_evals=2000, time_limit=True)
    swarm_ik.solve(problem, max_evals=2000)
    with pytest.raises(errors.InvalidArgumentError, match="max_evals"):
        swarm_ik.solve(problem, max_evals=2000.0)
    swarm_ik.solve(problem, pop_size=8, max_evals=2000)
    with pytest.raises(errors.InvalidArgumentError, match="pop_size"):
        swarm_ik.solve(problem, pop_size=8.0, max_evals=2000)


def test_verify_takes_q0_and_agrees_with_the_result_and_the_method(panda) -> None:
    q0 = panda.mid_q()
    q0[0] += 0.5
    problem = swarm_ik.IKProblem(
        panda,
        goals=[Position(panda.ee_frame, panda.fk(q0)[:3, 3]), MinimalDisplacement(primary=True)],
    )
    res = swarm_ik.solve(problem, q0=q0, seed=0)
    assert res.success
    assert swarm_ik.verify(problem, res.q, q0=q0) == problem.verify(res.q, q0=q0)
    assert swarm_ik.verify(problem, res.q, q0=q0) == res.goal_errors
    assert not swarm_ik.verify(problem, res.q)[1].met  # (held near the middle: not q0)
    with pytest.raises(errors.InvalidArgumentError, match="tol"):
        swarm_ik.verify(problem, res.q, tol=1e-5)  # type: ignore[call-arg]
    with pytest.raises(errors.InvalidArgumentError, match="q0"):
        swarm_ik.verify(problem, res.q, q0=[0.0, 1.0])


def test_two_checks_of_one_answer_are_equal(panda, target) -> None:
    """NaN errors (a goal without such an error) and a collision report computed on demand
    compare equal between two checks."""
    problem = swarm_ik.IKProblem(panda, goals=[Position(panda.ee_frame, target[:3, 3])])
    q = panda.mid_q()
    assert problem.verify(q) == problem.verify(q) == swarm_ik.verify(problem, q)
    scene = Scene([Box([0.1, 0.1, 0.1], [2.0, 2.0, 2.0])])
    col = swarm_ik.IKProblem(panda, target, goals=[AvoidCollisions(scene)])
    assert col.verify(q) == col.verify(q)


@pytest.mark.parametrize(
    "make",
    [
        lambda f, t: Position(f, ["0.4", "0", "0.4"]),
        lambda f, t: Position(f, [True, False, True]),
        lambda f, t: Position(f, [0.4, "0", 0.4]),
        lambda f, t: Orientation(np.array([1, 0, 0]), t[:3, :3]),
        lambda f, t: Pose(np.array([f, "x"]), t),
        lambda f, t: AvoidCollisions(np.array(1.0)),
        lambda f, t: AvoidCollisions(np.array([])),
        lambda f, t: Scene(np.array(1.0)),
    ],
)
def test_goal_fields_of_the_wrong_kind_are_refused(panda, target, make) -> None:
    with pytest.raises(errors.InvalidArgumentError):
        make(panda.ee_frame, target)


def test_a_target_of_text_or_booleans_is_refused(panda) -> None:
    with pytest.raises(errors.SwarmIKError, match="text"):
        swarm_ik.IKProblem(panda, (["0.4", "0", "0.4"], [0, 0, 0, 1]))
    with pytest.raises(errors.SwarmIKError, match="text"):
        swarm_ik.make_pose(["1", "2", "3"], [0, 0, 0, 1])
    with pytest.raises(errors.SwarmIKError, match="booleans"):
        swarm_ik.solve_batch(panda, np.ones((2, 7), dtype=bool))


@pytest.mark.parametrize(
    "call",
    [
        lambda r: r.fk_pinocchio(np.zeros(6)),
        lambda r: r.jacobian_pinocchio(np.zeros(6)),
        lambda r: r.to_pinocchio(None),
        lambda r: r.within_limits(np.zeros(6)),
        lambda r: r.within_limits("abc"),
        lambda r: r.random_q(0),
        lambda r: r.random_q(np.random.default_rng(0), 2.5),
        lambda r: r.wrap(None),
        lambda r: swarm_ik.load_robot("panda", srdf=1),
        lambda r: swarm_ik.windings_of(swarm_ik.IKProblem(r, r.fk(r.mid_q())), None),
        lambda r: swarm_ik.solve_batch(r, r.fk(r.mid_q())[None], q0={}),
        lambda r: swarm_ik.solve_batch(r, r.fk(r.mid_q())[None], q0=1j),
    ],
)
def test_robot_methods_refuse_bad_joint_vectors_with_a_swarm_ik_error(panda, call) -> None:
    with pytest.raises(errors.SwarmIKError):
        call(panda)


def test_each_batch_row_says_why_it_ended(panda) -> None:
    q = panda.random_q(np.random.default_rng(3), 40)
    targets = panda.fk(q)
    targets[:4, 0, 3] += 5.0  # beyond reach
    res = swarm_ik.solve_batch(panda, targets, max_starts=4)
    assert (res.reason[:4] == "unreachable").all()  # (as solve says: proven, whatever the budget)
    assert (res.reason[res.success] == "converged").all()
    assert set(res.reason[4:][~res.success[4:]]) <= {"local_minima"}
    cut = swarm_ik.solve_batch(panda, targets, max_evals=3)
    assert (cut.reason[:4] == "unreachable").all()
    assert set(cut.reason[4:][~cut.success[4:]]) == {"budget"}
    for i in (0, 5):  # (the reasons of solve for the same targets)
        one = swarm_ik.solve(swarm_ik.IKProblem(panda, targets[i]), max_evals=3)
        assert one.reason == ("unreachable" if i < 4 else "budget") or one.success


def test_a_batch_seed_of_none_is_seed_zero_and_a_generator_is_refused(panda, target) -> None:
    a = swarm_ik.solve_batch(panda, target[None], seed=None)
    b = swarm_ik.solve_batch(panda, target[None], seed=0)
    np.testing.assert_array_equal(a.q, b.q)
    with pytest.raises(errors.InvalidArgumentError, match="keys each target"):
        swarm_ik.solve_batch(panda, target[None], seed=np.random.default_rng(0))


def test_primary_weights_far_apart_warn(panda, target) -> None:
    f = panda.ee_frame

    def goals(w: float) -> list[Any]:
        return [Orientation(f, target[:3, :3]), Position(f, target[:3, 3], weight=w)]

    with pytest.warns(UserWarning, match="weights 1e\\+04 apart"):
        swarm_ik.IKProblem(panda, goals=goals(1e-4))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        swarm_ik.IKProblem(panda, goals=goals(1e-2))


@pytest.mark.parametrize("name", ["tiago", "panda_collision", "romeo", "a1"])
def test_a_floating_base_keeps_the_fixed_base_tool_frame(name: str) -> None:
    fixed = swarm_ik.load_robot(name)
    floating = swarm_ik.load_robot(name, floating_base=True)
    assert floating.frames == fixed.frames


def test_what_the_checks_still_take(panda, target) -> None:
    """Values refused by no check before them stay taken (a diff review): a legacy
    RandomState, rows of joint vectors, an object array of shapes, progress=None, and a 0-d
    time limit that keys the same shared route as its number."""
    assert panda.random_q(np.random.RandomState(0), 2).shape == (2, panda.nq)
    assert panda.within_limits(panda.random_q(np.random.default_rng(0), 3))
    box = Box([0.1, 0.1, 0.1], [2.0, 2.0, 2.0])
    assert len(Scene(np.array([box], dtype=object)).obstacles) == 1
    swarm_ik.solve_batch(panda, target[None], progress=None)
    problem = swarm_ik.IKProblem(panda, target)
    routes = panda._cache.setdefault("routes", {})
    swarm_ik.solve(problem, time_limit=1.5)
    n = len(routes)
    swarm_ik.solve(problem, time_limit=np.array(1.5))
    assert len(routes) == n


def test_goal_errors_with_array_or_nan_details_equal_themselves() -> None:
    from swarm_ik.problem import GoalError

    arr = GoalError("g", 0.0, float("nan"), True, np.array([1.0, 2.0]))
    nan = GoalError("g", 0.0, 0.0, True, float("nan"))
    assert arr == arr and nan == nan
    assert arr == GoalError("g", 0.0, float("nan"), True, np.array([1.0, 2.0]))
    assert arr != GoalError("g", 0.0, float("nan"), True, np.array([1.0, 3.0]))
