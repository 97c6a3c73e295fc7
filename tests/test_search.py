"""The compiled swarm search (swarm_ik/kernels/search.py) and the IKSolver fast path."""

from __future__ import annotations

import time

import numpy as np
import pytest

import swarm_ik
from swarm_ik.kernels import search
from swarm_ik.solvers import base
from swarm_ik.solvers.gwo import gwo_move


class _Replay:
    """A stand-in Generator that hands out pre-drawn arrays, in order."""

    def __init__(self, *arrays: np.ndarray) -> None:
        self.arrays = list(arrays)

    def random(self, shape: tuple[int, ...]) -> np.ndarray:
        a = self.arrays.pop(0)
        assert a.shape == tuple(shape)
        return a


def test_compiled_gwo_move_equals_numpy_twin_on_the_same_numbers() -> None:
    rng = np.random.default_rng(5)
    p, n = 5, 7
    x = rng.uniform(-2, 2, (p, n))
    leaders = rng.uniform(-2, 2, (3, n))
    r1, r2 = rng.random((3, p, n)), rng.random((3, p, n))
    for a in (0.0, 0.7, 2.0):
        ref = gwo_move(x, leaders, a, _Replay(r1, r2))  # type: ignore[arg-type]
        out = np.empty((p, n))
        search.gwo_move_into(x, p, leaders, a, r1, r2, out)
        np.testing.assert_allclose(out, ref, rtol=0, atol=1e-14)


def test_stream_uniforms_are_uniform_and_keyed() -> None:
    u = search.uniforms(np.uint64(12345), 0, 20000)
    assert 0.0 <= u.min() and u.max() < 1.0
    assert abs(u.mean() - 0.5) < 0.01 and abs(u.var() - 1 / 12) < 0.005
    v = search.uniforms(np.uint64(12346), 0, 20000)
    assert not np.array_equal(u, v)
    np.testing.assert_array_equal(search.uniforms(np.uint64(12345), 10, 5), u[10:15])


def test_compiled_clock_is_perf_counter() -> None:
    a = time.perf_counter()
    b = search.now()
    c = time.perf_counter()
    assert a - 1e-3 <= b <= c + 1e-3


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_compiled_search_solves_and_is_deterministic(name: str) -> None:
    robot = swarm_ik.load_robot(name)
    rng = np.random.default_rng(11)
    qs = robot.random_q(rng, 40)
    ok = 0
    for q in qs:
        p = swarm_ik.IKProblem(robot, robot.fk(q))
        r1 = swarm_ik.solve(p, seed=4, max_evals=3000)
        r2 = swarm_ik.solve(p, seed=4, max_evals=3000)
        np.testing.assert_array_equal(r1.q, r2.q)
        assert r1.n_evals == r2.n_evals <= 3000
        assert len(r1.history) >= 1 and np.all(np.diff(r1.history) <= 0)
        ok += r1.success
    assert ok == len(qs)


def test_evaluator_path_and_fast_path_agree_and_count_exactly() -> None:
    """solve() takes the Evaluator-free fast path for an int seed; a Generator seed goes
    through hybrid.run with an Evaluator: same key, so the same answer."""
    robot = swarm_ik.load_robot("panda")
    rng = np.random.default_rng(3)
    for q in robot.random_q(rng, 15):
        p = swarm_ik.IKProblem(robot, robot.fk(q))
        fast = swarm_ik.solve(p, seed=9, max_evals=2000)
        slow = swarm_ik.solve(p, seed=np.random.default_rng(9), max_evals=2000)
        np.testing.assert_array_equal(fast.q, slow.q)
        assert fast.n_evals == slow.n_evals
        np.testing.assert_array_equal(fast.history, slow.history)


def test_budget_never_exceeded_and_history_one_entry_per_generation() -> None:
    robot = swarm_ik.load_robot("panda")
    p = swarm_ik.IKProblem.from_q(robot, robot.random_q(np.random.default_rng(0)))
    for budget in (1, 7, 31, 200, 777):
        r = swarm_ik.solve(p, seed=1, max_evals=budget, stop_on_success=False)
        assert r.n_evals == budget  # the whole budget runs, never more
        # every generation (12 starts, ≤ 30 evaluations each) costs at most 360 evaluations
        assert len(r.history) >= budget // 360
    ev = base.Evaluator(p.fitness, p.lower, p.upper, max_evals=500, problem=p)
    from swarm_ik.solvers.hybrid import run

    run(ev, np.random.default_rng(2))
    assert ev.n_evals == 500 and len(ev.history) >= 1


def test_time_limit_is_honoured_inside_the_compiled_loop() -> None:
    robot = swarm_ik.load_robot("panda")
    # unreachable: the search runs until the clock stops it
    target = np.eye(4)
    target[:3, 3] = [3.0, 0.0, 0.5]
    p = swarm_ik.IKProblem(robot, target)
    r = swarm_ik.solve(p, time_limit=0.01)
    assert not r.success and r.reason in ("unreachable", "time_limit")
    assert r.time_s < 0.01 + 0.05  # one polish call of overshoot at most (loaded machine)


def _same_result(a: swarm_ik.Result, b: swarm_ik.Result) -> None:
    np.testing.assert_array_equal(a.q, b.q)
    assert (a.n_evals, a.success, a.reason, a.fitness) == (
        b.n_evals,
        b.success,
        b.reason,
        b.fitness,
    )
    np.testing.assert_array_equal(a.history, b.history)
    (ga,), (gb,) = a.goal_errors, b.goal_errors
    assert ga.goal == gb.goal and ga.met == gb.met
    assert ga.position_error == pytest.approx(gb.position_error, rel=1e-9, abs=1e-15)
    if np.isnan(gb.rotation_error):
        assert np.isnan(ga.rotation_error)
    else:
        assert ga.rotation_error == pytest.approx(gb.rotation_error, rel=1e-6, abs=1e-15)


@pytest.mark.parametrize("w_rot", [1.0, 0.0])
def test_iksolver_and_solve_equal_the_general_path(w_rot: float) -> None:
    """IKSolver.solve, solve() (its cached IKSolver lane) and the general compiled path of
    solve() (taken with a callback) give the same Result, with and without a start."""
    robot = swarm_ik.load_robot("panda")
    ik = swarm_ik.IKSolver(robot, max_evals=3000, w_rot=w_rot)
    rng = np.random.default_rng(8)
    seen: list[float] = []
    for i, q in enumerate(robot.random_q(rng, 25)):
        T = robot.fk(q)
        q0 = None if i % 2 else robot.random_q(rng)
        p = swarm_ik.IKProblem(robot, T, w_rot=w_rot)
        a = ik.solve(T, q0=q0, seed=2 + i)
        lane = swarm_ik.solve(p, seed=2 + i, max_evals=3000, q0=q0)
        general = swarm_ik.solve(
            p, seed=2 + i, max_evals=3000, q0=q0, on_improvement=lambda q, f: seen.append(f)
        )
        _same_result(a, general)
        _same_result(lane, general)
    assert seen  # the callback ran: the general path was taken


def test_seed_key_is_numpys_first_draw() -> None:
    """The compiled key of an integer seed equals one draw of default_rng(seed) (SeedSequence
    + PCG64 reimplemented), so every solve path keys its stream alike."""
    rng = np.random.default_rng(0)
    seeds = [0, 1, 2, 41, 2**31 - 1, 2**32 - 1, 2**32, 2**32 + 1, 2**62, 2**63 - 1]
    seeds += [int(s) for s in rng.integers(0, 2**63, 300)] + list(range(3, 200))
    for s in seeds:
        assert search.seed_key(s) == search.stream_key(np.random.default_rng(s)), s


def test_iksolver_start_checked_like_solve() -> None:
    """A start is refused, clipped (with a warning) or used as it is, as prepare_q0 does."""
    robot = swarm_ik.load_robot("ur5")  # (continuous-free limits of ±2π)
    ik = swarm_ik.IKSolver(robot, max_evals=2000)
    T = robot.fk(robot.random_q(np.random.default_rng(1)))
    with pytest.raises(swarm_ik.InvalidArgumentError, match="NaN"):
        ik.solve(T, q0=np.full(robot.nq, np.nan))
    with pytest.raises(swarm_ik.InvalidArgumentError, match="6 values"):
        ik.solve(T, q0=np.zeros(robot.nq + 1))
    q0 = robot.mid_q() + 0.2
    ref = ik.solve(T, q0=q0, seed=3)
    _same_result(ik.solve(T, q0=q0.tolist(), seed=3), ref)  # a list: checked in Python
    outside = q0.copy()
    outside[0] = robot.upper[0] + 1.0
    clipped = q0.copy()
    clipped[0] = robot.upper[0]
    with pytest.warns(UserWarning, match="outside the joint limits"):
        a = ik.solve(T, q0=outside, seed=3)
    _same_result(a, ik.solve(T, q0=clipped, seed=3))
    assert not np.array_equal(outside, clipped)  # the caller's start is not written


def test_iksolver_refuses_bad_targets_like_solve() -> None:
    robot = swarm_ik.load_robot("panda")
    ik = swarm_ik.IKSolver(robot, time_limit=0.005)
    bad = robot.fk(robot.mid_q())
    bad[0, 0] += 1e-3  # not a rotation
    with pytest.raises(swarm_ik.InvalidTargetError, match="orthonormal"):
        ik.solve(bad)
    nan = robot.fk(robot.mid_q())
    nan[1, 3] = np.nan
    with pytest.raises(swarm_ik.InvalidTargetError, match="NaN"):
        ik.solve(nan)


@pytest.mark.parametrize("w_rot", [1.0, 0.0])
def test_fast_check_of_the_answer_equals_problem_verify(w_rot: float) -> None:
    from swarm_ik.api import _check_pose_goal

    robot = swarm_ik.load_robot("ur5")
    rng = np.random.default_rng(4)
    for q in robot.random_q(rng, 10):
        p = swarm_ik.IKProblem(robot, robot.fk(robot.random_q(rng)), w_rot=w_rot)
        checked = _check_pose_goal(p, q, 1e-5, 1e-5)
        assert checked is not None
        (fast,), within = checked
        (ref,) = p.verify(q, 1e-5, 1e-5)
        assert within == p.within_bounds(q)
        assert fast.goal == ref.goal and fast.met == ref.met
        assert fast.position_error == pytest.approx(ref.position_error, rel=1e-12)
        if w_rot == 0.0:
            assert np.isnan(fast.rotation_error) and np.isnan(ref.rotation_error)
        else:
            assert fast.rotation_error == pytest.approx(ref.rotation_error, rel=1e-9)


def test_result_of_is_the_dataclass_with_every_field() -> None:
    import dataclasses

    robot = swarm_ik.load_robot("ur5")
    ik = swarm_ik.IKSolver(robot, max_evals=500)
    r = ik.solve(robot.fk(robot.random_q(np.random.default_rng(2))), seed=1)
    fields = {f.name: getattr(r, f.name) for f in dataclasses.fields(r)}
    assert set(vars(r)) == set(fields)  # IKSolver's Result.of gave every field
    again = swarm_ik.Result(**fields)
    assert again == r and swarm_ik.Result.of(**fields) == again
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.success = False  # type: ignore[misc]


def test_solve_lane_keeps_the_problems_own_target_check() -> None:
    """A target accepted by a looser orth_tol is not re-checked at 1e-6 by the lane, also
    when the solve fails (its end reason is read off the user's problem)."""
    robot = swarm_ik.load_robot("panda")
    target = np.eye(4)
    target[:3, 3] = [3.0, 0.0, 0.5]  # out of reach
    target[0, 1] = 2e-4  # not a rotation at 1e-6, accepted at 1e-3
    p = swarm_ik.IKProblem(robot, target, orth_tol=1e-3)
    seen: list[float] = []
    lane = swarm_ik.solve(p, seed=3, max_evals=300)
    general = swarm_ik.solve(p, seed=3, max_evals=300, on_improvement=lambda q, f: seen.append(f))
    assert not lane.success and lane.reason == general.reason == "unreachable"
    _same_result(lane, general)


def test_api_status_codes_are_the_kernels() -> None:
    """IKSolver reads the compiled call's status with copies of the kernel's codes."""
    from swarm_ik import api
    from swarm_ik.kernels import search

    assert (api._RAN, api._CHECK_TARGET) == (search.RAN, search.CHECK_TARGET)


def test_goal_error_of_is_the_dataclass() -> None:
    from swarm_ik.problem import GoalError

    fast = GoalError.of("Pose(tool0)", 1e-6, 2e-6, True)
    assert fast == GoalError("Pose(tool0)", 1e-6, 2e-6, True) and fast.details is None
    assert repr(fast) == repr(GoalError("Pose(tool0)", 1e-6, 2e-6, True))


def test_ik_solver_takes_arrays_whose_float64_dtype_is_an_equal_copy() -> None:
    # (the per-call path tests dtypes by identity; equal copies take the checked path)
    robot = swarm_ik.load_robot("panda")
    ik = swarm_ik.IKSolver(robot, max_evals=2000)
    rng = np.random.default_rng(4)
    target, q0 = robot.fk(robot.random_q(rng)), robot.random_q(rng)
    other = np.dtype("f8").newbyteorder("=")
    ref = ik.solve(target, q0=q0, seed=3)
    got = ik.solve(target.view(other), q0=q0.view(other), seed=3)
    assert ref.success and np.array_equal(got.q, ref.q) and got.n_evals == ref.n_evals


@pytest.mark.parametrize("name", ["panda", "kinova"])
def test_iksolver_returns_a_history_longer_than_its_buffer_whole(name: str) -> None:
    """A search of many generations (an unreachable target) gives IKSolver a history longer
    than its output buffer: it comes back as its own array, equal to the general path's
    (kinova: the buffer holds Pinocchio's configuration between q and the history)."""
    from swarm_ik import api

    robot = swarm_ik.load_robot(name)
    far = np.eye(4)
    far[:3, 3] = (3.0, 0.0, 0.5)  # out of reach
    ik = swarm_ik.IKSolver(robot, max_evals=20_000, pop_size=4)
    a = ik.solve(far, seed=1)
    general = swarm_ik.solve(
        swarm_ik.IKProblem(robot, far), seed=1, max_evals=20_000, pop_size=4,
        on_improvement=lambda q, f: None,
    )  # fmt: skip
    assert not a.success and len(a.history) > api._HISTORY_CAP
    _same_result(a, general)
    short = ik.solve(robot.fk(robot.mid_q()), seed=1)  # a short one: from the output buffer
    assert short.success and 1 <= len(short.history) <= api._HISTORY_CAP
    assert short.q.shape == (robot.nq,)


def test_iksolver_pickles_as_its_arguments() -> None:
    import pickle

    robot = swarm_ik.load_robot("ur5")
    ik = swarm_ik.IKSolver(robot, time_limit=0.01, tol_pos=2e-5, pop_size=8)
    back = pickle.loads(pickle.dumps(ik))
    assert (back.tol_pos, back.time_limit, back.params) == (2e-5, 0.01, {"pop_size": 8})
    T = robot.fk(robot.random_q(np.random.default_rng(3)))
    _same_result(back.solve(T, seed=4), ik.solve(T, seed=4))


def test_pose_solver_rebuilds_the_goal_table_field_by_field() -> None:
    """solve_pose names every GoalTable field (numba cannot slice a mixed NamedTuple)."""
    from swarm_ik.kernels.lm import GoalTable

    assert GoalTable._fields == (
        "code", "frame", "weight", "primary", "par", "jref", "jw", "row0", "nrows",
        "rows_primary", "rows_secondary", "col",
    )  # fmt: skip
    assert search.POSE_SOLVER_FIELDS[:4] == ("tree", "table", "bounds", "cfg")


@pytest.mark.parametrize("name", ["panda", "kinova"])
def test_iksolver_checks_with_pinocchios_pose_of_the_first_goal_frame(name: str) -> None:
    """IKSolver's check reads Pinocchio directly where its configuration is q itself (panda),
    else through a bound conversion (kinova's continuous joints): fk_pinocchio's pose either
    way (a mimic chain: tests/test_fk_tree.py)."""
    robot = swarm_ik.load_robot(name)
    pose = robot.fk_pinocchio_bound()
    assert pose.__name__ == ("pose" if name == "panda" else "pose_converted")
    for q in robot.random_q(np.random.default_rng(5), 5):
        np.testing.assert_array_equal(pose(q), robot.fk_pinocchio(q))


@pytest.mark.parametrize("name", ["panda", "kinova"])
def test_plain_problem_fast_path_equals_the_general_path(name: str) -> None:
    """IKProblem(robot, T) with every option left out shares a per-robot template; its
    attributes equal those the general path makes, its caches are its own, and options
    given (even at their default values) or refused take the general path."""
    from swarm_ik import problem as P

    robot = swarm_ik.load_robot(name)
    T = robot.fk(robot.random_q(np.random.default_rng(2)))
    fast = swarm_ik.IKProblem(robot, T)
    general = swarm_ik.IKProblem.__new__(swarm_ik.IKProblem)
    general._make(robot, T, None, "se3", 1.0, 10.0, 1.0, 1e-6, None, None)
    assert vars(fast).keys() == vars(general).keys()
    for key, value in vars(general).items():
        got = vars(fast)[key]
        if isinstance(value, np.ndarray):
            np.testing.assert_array_equal(got, value)
        elif key == "goals":
            assert [type(g) for g in got] == [type(g) for g in value]
            np.testing.assert_array_equal(got[0].target, value[0].target)
        elif key != "bounds":
            assert got == value, key
    other = swarm_ik.IKProblem(robot, robot.fk(robot.mid_q()))
    assert other._table_cache is not fast._table_cache and other.target is not fast.target
    fast.lower[0] = fast.upper[0]  # one problem's arrays and weights are its own
    fast._weights["w_rot"] = 2.0
    assert other.lower[0] == robot.lower[0] and other._weights["w_rot"] == 1.0
    assert swarm_ik.IKProblem(robot, T).lower[0] == robot.lower[0]
    fast.table(None)
    assert fast._table_cache and not other._table_cache
    assert robot._cache["plain_problem"]["w_rot"] == 1.0 and P._W_ROT == 1.0
    with pytest.raises(swarm_ik.InvalidArgumentError, match="w_rot must be"):
        swarm_ik.IKProblem(robot, T, w_rot=True)  # type: ignore[arg-type]
    with pytest.raises(swarm_ik.InvalidTargetError):
        swarm_ik.IKProblem(robot, np.zeros((4, 4)))


def test_iksolver_scratch_reused_after_a_long_failed_search_gives_a_new_ones_result() -> None:
    """IKSolver keeps its search scratch between calls (its PoseSolver's SearchWork): after a
    failed search that filled the archive and the grey-wolf buffers, a target gives exactly
    the Result of a freshly made IKSolver."""
    robot = swarm_ik.load_robot("panda")
    far = np.eye(4)
    far[:3, 3] = (3.0, 0.0, 0.5)  # out of reach: every generation runs
    T = robot.fk(robot.random_q(np.random.default_rng(4)))
    used = swarm_ik.IKSolver(robot, max_evals=3000, pop_size=6)
    assert not used.solve(far, seed=3).success
    after = used.solve(T, seed=5)
    fresh = swarm_ik.IKSolver(robot, max_evals=3000, pop_size=6).solve(T, seed=5)
    _same_result(after, fresh)
    assert np.array_equal(after.q, fresh.q) and after.n_evals == fresh.n_evals


def test_swarm_search_refuses_scratch_made_for_fewer_starts() -> None:
    from swarm_ik.kernels import lm, search

    robot = swarm_ik.load_robot("panda")
    p = swarm_ik.IKProblem(robot, robot.fk(robot.mid_q()))
    t, g = robot.tree, p.table(None)
    b = lm.Bounds(p.lower, p.upper, robot.continuous_mask, robot.prismatic_mask)
    small = search.make_search_work(t, g, 2)
    seed_q = np.ascontiguousarray(robot.mid_q())
    with pytest.raises(ValueError, match="scratch made for fewer starts"):
        search.swarm_search(
            t, g, b, search.typed_settings(lm.DEFAULT_LM), seed_q, 5e-6, 5e-6, 1e-5, 1e-5, 1.0,
            8, 4, 10, True, 1000, -1, 0, search.NO_LIMIT, 0.0, search.seed_key(0), -1,
            np.empty(robot.nq), small, small.hist, False,
        )  # fmt: skip


def test_swarm_search_keyed_by_a_seed_draws_what_the_seeds_key_draws() -> None:
    """swarm_search given an integer seed makes its key (seed_key) before its first draw: the
    same run as given that key, on a target whose first start does not converge (so the run
    draws); when the first start converges nothing is drawn (the same result as a run given
    another seed's key)."""
    from swarm_ik.kernels import lm, search

    robot = swarm_ik.load_robot("panda")
    far = np.eye(4)
    far[:3, 3] = (3.0, 0.0, 0.5)  # out of reach: every generation draws
    near = robot.fk(robot.mid_q() + 0.05)
    seed_q = np.ascontiguousarray(robot.mid_q())
    for target in (far, near):
        p = swarm_ik.IKProblem(robot, target)
        t, g = robot.tree, p.table(None)
        b = lm.Bounds(p.lower, p.upper, robot.continuous_mask, robot.prismatic_mask)
        runs = []
        given = np.uint64(search.seed_key(11 if target is far else 99))
        for key, seed in ((given, -1), (np.uint64(0), 11)):
            sw = search.make_search_work(t, g, 4)._replace(hist=np.empty(4096))  # never full
            out = np.empty(robot.nq)
            res = search.swarm_search(
                t, g, b, search.typed_settings(lm.DEFAULT_LM), seed_q, 5e-6, 5e-6, 1e-5,
                1e-5, 1.0, 4, 2, 10, False, 3000, 3000, 0, search.NO_LIMIT, 0.0, key, seed, out,
                sw, sw.hist, False,
            )  # fmt: skip
            runs.append((res, out, sw.hist[: res[6]].copy()))
        (ra, qa, ha), (rb, qb, hb) = runs
        assert ra[0] == search.SEARCH_DONE and ra == rb
        np.testing.assert_array_equal(qa, qb)
        np.testing.assert_array_equal(ha, hb)
    assert ra[1] < 50  # (the near target: converged from its first start, nothing drawn)


def test_solve_pose_holds_the_gil_so_threads_take_turns_with_its_scratch() -> None:
    """IKSolver's thread safety rests on the compiled call holding the GIL (its search scratch
    lives in the shared PoseSolver): solve_pose must not be compiled ``nogil``; and threads
    sharing one IKSolver get the sequential results."""
    from concurrent.futures import ThreadPoolExecutor

    from swarm_ik.kernels import search

    assert not search.solve_pose.targetoptions.get("nogil", False)
    robot = swarm_ik.load_robot("ur5")
    ik = swarm_ik.IKSolver(robot, max_evals=2000)
    targets = list(robot.fk(robot.random_q(np.random.default_rng(6), 24)))
    seq = [ik.solve(T, seed=i) for i, T in enumerate(targets)]
    with ThreadPoolExecutor(4) as pool:
        par = list(pool.map(lambda it: ik.solve(it[1], seed=it[0]), enumerate(targets)))
    for a, b in zip(seq, par, strict=True):
        assert np.array_equal(a.q, b.q) and a.n_evals == b.n_evals


def test_search_paused_by_a_full_history_resumes_to_the_same_run() -> None:
    """swarm_search cannot allocate (it is compiled without numba's runtime): a full history
    pauses it and run_search resumes it with a longer buffer.  A buffer of one entry (paused
    at almost every generation) gives exactly the run of a buffer that never fills."""
    from swarm_ik.kernels import lm, search

    robot = swarm_ik.load_robot("panda")
    far = np.eye(4)
    far[:3, 3] = (3.0, 0.0, 0.5)  # out of reach: every generation runs
    p = swarm_ik.IKProblem(robot, far)
    t, g = robot.tree, p.table(None)
    b = lm.Bounds(p.lower, p.upper, robot.continuous_mask, robot.prismatic_mask)
    seed_q = np.ascontiguousarray(robot.mid_q())
    runs = []
    for cap in (1, 4096):
        sw = search.make_search_work(t, g, 4)._replace(hist=np.empty(cap))
        out = np.empty(robot.nq)
        res = search.run_search(
            t, g, b, search.typed_settings(lm.DEFAULT_LM), seed_q, 5e-6, 5e-6, 1e-5, 1e-5,
            1.0, 4, 2, 10, False, 6000, 6000, 0, search.NO_LIMIT, 0.0, search.seed_key(3), out,
            sw,
        )  # fmt: skip
        runs.append((res, out))
    (a, qa), (c, qc) = runs
    assert a[6] > 100  # generations: the one-entry buffer grew many times
    assert a[:5] == c[:5] and a[6] == c[6]
    np.testing.assert_array_equal(a[5][: a[6]], c[5][: c[6]])
    np.testing.assert_array_equal(qa, qc)


def test_packed_structures_are_equal_copies_in_one_buffer_per_dtype() -> None:
    """search.packed (the IKSolver's state) copies every array of nested structures into
    views of one buffer per dtype, keeping values, shapes, layout, writeability and so the
    compiled types."""
    import numba

    from swarm_ik.kernels import lm, search

    robot = swarm_ik.load_robot("panda")
    p = swarm_ik.IKProblem(robot, robot.fk(robot.mid_q()))
    b = lm.Bounds(p.lower, p.upper, robot.continuous_mask, robot.prismatic_mask)
    src = (robot.tree, p.table(None), b)
    out = search.packed(src)

    def leaves(x: object) -> list[np.ndarray]:
        if isinstance(x, np.ndarray):
            return [x]
        return [a for y in x for a in leaves(y)] if isinstance(x, tuple) else []

    a_src, a_out = leaves(src), leaves(out)
    assert len(a_src) == len(a_out) > 20
    for x, y in zip(a_src, a_out, strict=True):
        assert y is not x and y.base is not None and not np.shares_memory(x, y)
        np.testing.assert_array_equal(x, y)
        assert y.shape == x.shape and y.dtype == x.dtype and y.flags.c_contiguous
        assert y.flags.writeable == x.flags.writeable
        assert numba.typeof(y) == numba.typeof(x)
    bases = {id(y.base) for y in a_out}
    assert len(bases) == len({y.dtype for y in a_out})
    assert type(out[1]) is lm.GoalTable and out[1].rows_primary == src[1].rows_primary


@pytest.mark.parametrize("name", ["ur5", "kinova"])
def test_iksolver_common_call_gives_the_result_of_its_general_per_call_path(name: str) -> None:
    """IKSolver.solve answers a C-contiguous float64 4x4 target with an integer seed inline;
    every field of its Result (types included) equals that of the per-call path that takes
    any target form (_solve_pose), for a start given and not.  On kinova (continuous joints)
    the inline check reads the Pinocchio configuration the compiled call wrote, the other
    path converts q in Python: the same errors to the last bit."""
    import dataclasses

    robot = swarm_ik.load_robot(name)
    ik = swarm_ik.IKSolver(robot, time_limit=0.005)
    rng = np.random.default_rng(12)
    for i, q in enumerate(robot.random_q(rng, 6)):
        T = robot.fk(q)
        q0 = None if i % 2 else robot.random_q(rng)
        a, b = ik.solve(T, q0=q0, seed=i), ik._solve_pose(T, q0, i)
        assert a.success and b.success
        for f in dataclasses.fields(swarm_ik.Result):
            x, y = getattr(a, f.name), getattr(b, f.name)
            assert type(x) is type(y), f.name
            if f.name == "time_s":
                continue
            if isinstance(x, np.ndarray):
                np.testing.assert_array_equal(x, y)
            elif f.name == "goal_errors":
                assert [vars(e) for e in x] == [vars(e) for e in y]
            else:
                assert x == y, f.name


def test_problem_records_its_target_check_and_the_lane_uses_it() -> None:
    """IKProblem keeps the orthonormality tolerance its target was checked with (template and
    general constructor alike); solve()'s lane hands a problem checked at as_pose's default
    to IKSolver.solve (which re-checks the target the same way) and the others to the path
    that keeps the problem's own check (test_solve_lane_keeps_the_problems_own_target_check)."""
    from swarm_ik.pose import ORTH_TOL, as_pose

    robot = swarm_ik.load_robot("panda")
    T = robot.fk(robot.mid_q())
    assert as_pose.__kwdefaults__["orth_tol"] == ORTH_TOL
    assert swarm_ik.IKProblem(robot, T).orth_tol == ORTH_TOL  # the template path
    assert swarm_ik.IKProblem(robot, T, w_rot=0.5).orth_tol == ORTH_TOL  # the general one
    assert swarm_ik.IKProblem(robot, T, orth_tol=1e-3).orth_tol == 1e-3
    p = swarm_ik.IKProblem(robot, robot.fk(robot.random_q(np.random.default_rng(2))))
    lane = swarm_ik.solve(p, seed=4, time_limit=0.005)
    assert lane.success
    _same_result(lane, swarm_ik.IKSolver(robot, time_limit=0.005).solve(p.target, seed=4))


def test_borrowed_reads_a_pose_solvers_fields_without_the_runtime() -> None:
    """search.borrowed reads a StructRef's field in code compiled without numba's runtime
    (where numba's own attribute access refuses to compile): the values the structure was
    made with, scalars and arrays alike."""
    import numba

    from swarm_ik.kernels import search

    @numba.njit(_nrt=False)
    def read(s):  # type: ignore[no-untyped-def]
        lower = search.borrowed(s, "bounds").lower
        return search.borrowed(s, "time_limit"), search.borrowed(s, "pop_size"), lower[0]

    robot = swarm_ik.load_robot("panda")
    ik = swarm_ik.IKSolver(robot, time_limit=0.004, pop_size=5)
    state = ik._solver
    assert read(state) == (0.004, 5, robot.lower[0])
    with pytest.raises(numba.TypingError):  # a name that is no field is refused when compiled
        numba.njit(_nrt=False)(lambda s: search.borrowed(s, "no_such_field"))(state)


def test_compiled_pinocchio_configuration_equals_to_pinocchio(tmp_path) -> None:
    """search.pinocchio_config (what IKSolver's compiled call writes after q) equals
    RobotModel.to_pinocchio to the last bit: continuous joints as (cos, sin) (kinova), a mimic
    follower from its driver, and no rows at all where the configuration is q (panda)."""
    from swarm_ik.kernels import search

    urdf = (
        '<robot name="m"><link name="a"/><link name="b"/><link name="c"/><link name="d"/>'
        '<joint name="j1" type="continuous"><parent link="a"/><child link="b"/>'
        '<origin xyz="0 0 0.3"/><axis xyz="0 0 1"/></joint>'
        '<joint name="j2" type="revolute"><parent link="b"/><child link="c"/>'
        '<origin xyz="0 0 0.3"/><axis xyz="0 1 0"/>'
        '<limit lower="-2" upper="2" effort="1" velocity="1"/></joint>'
        '<joint name="j3" type="revolute"><parent link="c"/><child link="d"/>'
        '<origin xyz="0 0 0.3"/><axis xyz="1 0 0"/>'
        '<limit lower="-2" upper="2" effort="1" velocity="1"/>'
        '<mimic joint="j2" multiplier="-0.5" offset="0.2"/></joint></robot>'
    )
    path = tmp_path / "mimic.urdf"
    path.write_text(urdf)
    rng = np.random.default_rng(4)
    for robot in (swarm_ik.load_robot("kinova"), swarm_ik.load_robot(path, "d")):
        index, affine, nq_pin = robot.pinocchio_plan_arrays()
        assert index.shape == (robot.model.njoints - 1, 3) and affine.shape[0] == index.shape[0]
        assert nq_pin == robot.model.nq
        for q in robot.random_q(rng, 20):
            out = np.full(robot.model.nq, np.nan)
            search.pinocchio_config(q, index, affine, out)
            np.testing.assert_array_equal(out, robot.to_pinocchio(q))
    index, affine, nq_pin = swarm_ik.load_robot("panda").pinocchio_plan_arrays()
    assert index.shape == (0, 3) and affine.shape == (0, 2) and nq_pin == 0


def test_borrowed_returns_a_reference_where_the_runtime_counts_them() -> None:
    """Compiled with numba's runtime on (pose_search off Linux), search.borrowed returns its
    value with a reference, as numba's own attribute access does: reading a field many times
    leaves the array's reference count as it was (it would be released once per read, and
    the structure's arrays freed, otherwise)."""
    import numba
    from numba.core.unsafe.refcount import get_refcount

    from swarm_ik.kernels import search

    @numba.njit
    def count(s):  # type: ignore[no-untyped-def]
        return get_refcount(search.borrowed(s, "bounds").lower)

    @numba.njit
    def read_many(s, n):  # type: ignore[no-untyped-def]
        total = 0.0
        for _ in range(n):
            total += search.borrowed(s, "bounds").lower[0]
        return total

    robot = swarm_ik.load_robot("panda")
    ik = swarm_ik.IKSolver(robot, time_limit=0.005)
    before = count(ik._solver)
    assert read_many(ik._solver, 100) == pytest.approx(100 * robot.lower[0])
    assert count(ik._solver) == before
    T = robot.fk(robot.random_q(np.random.default_rng(2)))
    assert ik.solve(T, seed=0).success  # the state intact
