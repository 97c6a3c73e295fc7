"""The compiled swarm search (swarm_ik/kernels/search.py) and the IKSolver fast path."""

from __future__ import annotations

import time

import numpy as np
import pytest
from conftest import timed

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


def test_key_of_seed_is_splitmix64_of_the_seed() -> None:
    """The published SplitMix64 (Vigna), written with Python's integers, over seeds from 0
    to the largest accepted: a key is the same on every platform and numba release."""

    def reference(x: int) -> int:
        m = 2**64 - 1
        z = (x + 0x9E3779B97F4A7C15) & m
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & m
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & m
        return z ^ (z >> 31)

    assert reference(0) == 0xE220A8397B1DCDAF  # (the first output of SplitMix64 from 0)
    for seed in (0, 1, 2, 12345, 2**32 + 7, 2**62, 2**63 - 1):
        key = search.key_of_seed(seed)
        assert type(key) is np.uint64 and int(key) == reference(seed)


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


def test_compiled_route_and_evaluator_path_agree_and_count_exactly() -> None:
    """The route's compiled search and the swarm solver's loop over an Evaluator (taken with
    a callback) give the same answer for the same seed: an integer (both keyed by
    key_of_seed) or a Generator (both keyed by its first draw)."""
    robot = swarm_ik.load_robot("panda")
    rng = np.random.default_rng(3)
    for q in robot.random_q(rng, 15):
        p = swarm_ik.IKProblem(robot, robot.fk(q))
        for make_seed in (lambda: 9, lambda: np.random.default_rng(9)):
            fast = swarm_ik.solve(p, seed=make_seed(), max_evals=2000)
            slow = swarm_ik.solve(
                p, seed=make_seed(), max_evals=2000, on_improvement=lambda q, f: None
            )
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


@timed()
def test_time_limit_is_honoured_inside_the_compiled_loop() -> None:
    robot = swarm_ik.load_robot("panda")
    # unreachable: the search runs until the clock stops it
    target = np.eye(4)
    target[:3, 3] = [3.0, 0.0, 0.5]
    p = swarm_ik.IKProblem(robot, target)
    r = swarm_ik.solve(p, time_limit=0.01)
    assert not r.success and r.reason in ("unreachable", "time_limit")
    assert r.time_s < 0.01 + 0.05  # one polish call of overshoot at most (loaded machine)


def test_first_time_limited_solve_of_a_process_keeps_its_limit() -> None:
    """The first solve of a fresh process with a time limit stays within it: what loads on
    first use (the kernels, the clock's objmode block, 40-80 ms) loads when the IKSolver is
    made, not inside a solve."""
    import subprocess
    import sys

    script = (
        "import numpy as np, swarm_ik\n"
        "robot = swarm_ik.load_robot('panda')\n"
        "ik = swarm_ik.IKSolver(robot, time_limit=0.005)\n"
        "T = np.eye(4); T[:3, 3] = [3.0, 0.0, 0.5]\n"  # (unreachable: runs to its limit)
        "print(ik.solve(T).time_s)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True, timeout=300
    )
    assert float(out.stdout.split()[-1]) < 0.005 + 0.03


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


def test_pose_problem_with_defaults_equals_the_general_constructor() -> None:
    """IKProblem(robot, T) with every default (a retargeted copy of the robot's pose
    problem) has the goals, bounds and results of the constructor's general path (taken here
    by giving the bounds), refuses the same bad targets, and pickles to the same problem."""
    import pickle

    robot = swarm_ik.load_robot("kinova")
    rng = np.random.default_rng(12)
    for i, q in enumerate(robot.random_q(rng, 6)):
        T = robot.fk(q)
        fast = swarm_ik.IKProblem(robot, T)
        general = swarm_ik.IKProblem(robot, T, lower=robot.lower, upper=robot.upper)
        np.testing.assert_array_equal(fast.target, T)
        (g_fast,), (g_general,) = fast.goals, general.goals
        assert fast.target is not T and type(g_fast) is type(g_general) is swarm_ik.goals.Pose
        assert g_fast.frame == g_general.frame and g_fast.tolerance is g_general.tolerance
        np.testing.assert_array_equal(g_fast.target, g_general.target)
        np.testing.assert_array_equal(fast.lower, general.lower)
        np.testing.assert_array_equal(fast.upper, general.upper)
        assert fast.single_pose and not fast.position_only and fast.w_rot == general.w_rot
        a = swarm_ik.solve(fast, seed=i, max_evals=3000)
        _same_result(a, swarm_ik.solve(general, seed=i, max_evals=3000))
        _same_result(a, swarm_ik.solve(pickle.loads(pickle.dumps(fast)), seed=i, max_evals=3000))
        assert a.success
    bad = robot.fk(robot.mid_q())
    bad[0, 0] += 1e-3
    for kwargs in ({}, {"lower": robot.lower}):
        with pytest.raises(swarm_ik.InvalidTargetError, match="orthonormal"):
            swarm_ik.IKProblem(robot, bad, **kwargs)  # type: ignore[arg-type]


def test_default_pose_problems_own_their_bounds_and_retarget_with_the_default_check() -> None:
    """Problems made from the robot's pose problem each own writable bounds (a change to one
    leaves the others alone), and with_target checks a new target's rotation against the
    default orthonormality tolerance, whatever the problem was made with."""
    robot = swarm_ik.load_robot("panda")
    rng = np.random.default_rng(2)
    a = swarm_ik.IKProblem(robot, robot.fk(robot.random_q(rng)))
    b = swarm_ik.IKProblem(robot, robot.fk(robot.random_q(rng)))
    a.lower[0] = a.lower[0] + 0.1
    assert b.lower[0] == robot.lower[0] and a.lower[0] != robot.lower[0]
    assert swarm_ik.IKProblem(robot, robot.fk(robot.mid_q())).lower[0] == robot.lower[0]
    off = robot.fk(robot.mid_q())
    off[:3, :3] *= 1.00002  # max|RᵀR − I| = 4e-5: beyond the default 1e-6
    loose = swarm_ik.IKProblem(robot, robot.fk(robot.mid_q()), orth_tol=1e-3)
    swarm_ik.IKProblem(robot, off, orth_tol=1e-3)  # (accepted when the problem is made)
    with pytest.raises(swarm_ik.InvalidTargetError, match="orthonormal"):
        loose.with_target(off)


def test_solves_of_one_problem_type_keep_each_its_own_settings() -> None:
    """Problems that differ only in their targets share a route per settings: a solve with
    other settings (budget, tolerances, a solver parameter) runs with its own, whatever ran
    before it."""
    robot = swarm_ik.load_robot("panda")
    rng = np.random.default_rng(5)
    for i, q in enumerate(robot.random_q(rng, 4)):
        T = robot.fk(q)
        strict = swarm_ik.solve(swarm_ik.IKProblem(robot, T), seed=i, max_evals=3000)
        short = swarm_ik.solve(swarm_ik.IKProblem(robot, T), seed=i, max_evals=2)
        loose = swarm_ik.solve(
            swarm_ik.IKProblem(robot, T), seed=i, max_evals=3000, tol_pos=1e-2, tol_rot=1e-2
        )
        again = swarm_ik.solve(swarm_ik.IKProblem(robot, T), seed=i, max_evals=3000)
        assert short.n_evals <= 2 and not short.success
        assert loose.success and loose.n_evals <= strict.n_evals
        assert strict.success and strict.position_error <= 1e-5
        assert strict.rotation_error <= 1e-5
        _same_result(again, strict)
        with pytest.raises(swarm_ik.InvalidArgumentError, match="pop_size"):
            swarm_ik.solve(swarm_ik.IKProblem(robot, T), seed=i, max_evals=30, pop_size=0)


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


def test_iksolver_pickles_as_its_arguments() -> None:
    import pickle

    robot = swarm_ik.load_robot("ur5")
    ik = swarm_ik.IKSolver(robot, time_limit=0.01, tol_pos=2e-5, pop_size=8)
    back = pickle.loads(pickle.dumps(ik))
    assert (back.tol_pos, back.time_limit, back.params) == (2e-5, 0.01, {"pop_size": 8})
    T = robot.fk(robot.random_q(np.random.default_rng(3)))
    _same_result(back.solve(T, seed=4), ik.solve(T, seed=4))


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


def test_a_spent_time_limit_stops_the_compiled_search() -> None:
    """A time limit already spent (zero or below: what is left of a budget read a moment
    late) ends the search after its seed's polish; it never means "no limit" (a collision
    solve's try given -2e-5 s of its share searched an unreachable target without end)."""
    from swarm_ik.api import Route

    robot = swarm_ik.load_robot("panda")
    far = np.eye(4)
    far[:3, 3] = [3.0, 0.0, 0.5]  # (beyond the arm's reach: no polish ever stops it)
    route = Route(swarm_ik.IKProblem(robot, far), time_limit=1.0)
    for limit in (0.0, -2e-5, -1.0):
        t0 = time.perf_counter()
        out = route.search(robot.mid_q(), search.key_of_seed(0), None, 2**62, 0, limit, t0)
        assert out.used <= 2 * route.kwargs["max_iters"], (limit, out.used)
