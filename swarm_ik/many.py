"""``solve_many``: several distinct IK solutions of one target.

A 7-joint arm such as YuMi reaches a generic pose along a one-dimensional self-motion, and
even a 6-joint arm has up to 8 wrist/elbow/shoulder branches (more with joint ranges beyond
±π).  A population of starts polished in parallel finds many of them at once; this is where a
swarm of starts naturally beats a single-start Jacobian method.

>>> import swarm_ik
>>> robot = swarm_ik.load_robot("yumi_left")
>>> problem = swarm_ik.IKProblem.from_q(robot, [0.1, -0.5, 0.2, 0.3, -0.2, 0.4, 0.1])
>>> sols = swarm_ik.solve_many(problem, n=4, min_distance=0.2, seed=0)
>>> len(sols), all(s.success for s in sols)
(4, True)
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from swarm_ik.api import prepare_q0, verify
from swarm_ik.errors import InvalidArgumentError
from swarm_ik.optimize import check_budget, make_rng
from swarm_ik.problem import IKProblem
from swarm_ik.result import Result
from swarm_ik.solvers.hybrid import CONVERGED, Polisher, wrapped_distance

SOLVER_NAME = "swarm"
"""Solver name recorded in the results of :func:`solve_many` (its polish is ``swarm``'s)."""


def solve_many(
    problem: IKProblem,
    n: int = 8,
    *,
    min_distance: float = 0.1,
    seed: int | np.random.Generator | None = 0,
    max_evals: int | None = None,
    time_limit: float | None = None,
    q0: Any = None,
    tol_pos: float = 1e-5,
    tol_rot: float = 1e-5,
    batch: int = 16,
    max_starts: int | None = None,
    max_iters: int = 30,
) -> list[Result]:
    """Find up to ``n`` distinct solutions of an IK problem.

    Starts (``q0`` or the middle of the ranges first, then uniform random within the
    limits) are polished in batches by the compiled Levenberg–Marquardt kernel of the
    ``swarm`` solver (:class:`swarm_ik.solvers.hybrid.Polisher`).  A converged point is kept
    when its joint-space distance to every kept solution is at least ``min_distance``
    (Euclidean norm of the differences, continuous joints' differences wrapped to
    ``[-π, π)``).  The search ends at ``n`` solutions or when the budget is spent.

    Args:
        problem: The IK problem.
        n: Number of solutions wanted, ``>= 1``.
        min_distance: Smallest joint-space distance between two kept solutions (rad, m for
            prismatic joints), ``> 0``.
        seed: Seed or Generator for the random starts.
        max_evals: Most FK + Jacobian evaluations in total.
        time_limit: Most wall-clock seconds.
        q0: Optional first start, shape ``(nq,)`` (clipped into the limits with a warning).
        tol_pos: Position tolerance [m] of every solution.
        tol_rot: Rotation tolerance [rad] of every solution.
        batch: Starts polished per compiled call.
        max_starts: Most starts; default ``64 · n`` when neither ``max_evals`` nor
            ``time_limit`` is given, else unlimited.
        max_iters: Evaluations per start before it is abandoned.

    Returns:
        The distinct solutions, sorted by fitness (best first), each checked with Pinocchio's
        FK (``success`` True: within tolerance and limits).  ``n_evals`` and ``time_s`` of each
        are the totals spent when it was found.  Fewer than ``n`` when the budget ran out
        (an empty list when nothing converged).

    Raises:
        InvalidArgumentError: ``n``, ``min_distance``, ``batch``, a tolerance or the budget is
            out of range, or ``problem`` is not an :class:`IKProblem`.
    """
    if not isinstance(problem, IKProblem):
        raise InvalidArgumentError(f"problem must be an IKProblem, got {type(problem).__name__}")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise InvalidArgumentError(f"n must be a positive integer, got {n!r}")
    if not (np.isfinite(min_distance) and min_distance > 0):
        raise InvalidArgumentError(f"min_distance must be a positive number, got {min_distance!r}")
    if batch < 1 or max_iters < 2 or (max_starts is not None and max_starts < 1):
        raise InvalidArgumentError(
            f"need batch >= 1, max_iters >= 2 and max_starts >= 1; got batch={batch}, "
            f"max_iters={max_iters}, max_starts={max_starts}"
        )
    for label, tol in (("tol_pos", tol_pos), ("tol_rot", tol_rot)):
        if not (np.isfinite(tol) and tol > 0):
            raise InvalidArgumentError(f"{label} must be a positive number, got {tol!r}")
    check_budget(max_evals, time_limit)
    if max_starts is None and max_evals is None and time_limit is None:
        max_starts = 64 * int(n)
    rng = make_rng(seed)
    start_q = prepare_q0(problem, q0)
    robot = problem.robot
    lower, upper = problem.lower, problem.upper
    wrap = robot.continuous_mask
    pol = Polisher.from_problem(
        problem, lower, upper, tol_pos, tol_rot, wrap=wrap, max_iters=max_iters
    )
    first = start_q if start_q is not None else 0.5 * (lower + upper)

    t0 = time.perf_counter()
    kept: list[np.ndarray] = []
    found_at: list[tuple[int, float]] = []
    used = 0
    n_starts = 0
    sec_per_eval = 5e-6
    while len(kept) < n:
        if max_evals is not None and used >= max_evals:
            break
        if time_limit is not None and time.perf_counter() - t0 >= time_limit:
            break
        if max_starts is not None and n_starts >= max_starts:
            break
        k = batch if max_starts is None else min(batch, max_starts - n_starts)
        starts = rng.uniform(lower, upper, size=(k, robot.nq))
        if n_starts == 0:
            starts[0] = first
        cap = 2**62 if max_evals is None else max_evals - used
        if time_limit is not None:  # keep each compiled call within the time left
            left = time_limit - (time.perf_counter() - t0)
            cap = min(cap, max(8, int(0.8 * left / sec_per_eval)))
        t1 = time.perf_counter()
        out = pol.polish(starts, cap, stop_first=False)
        if out.used > 0:
            sec_per_eval = 0.5 * sec_per_eval + 0.5 * (time.perf_counter() - t1) / out.used
        used += out.used
        n_starts += int(np.count_nonzero(out.status))
        elapsed = time.perf_counter() - t0
        for q in out.q[out.status == CONVERGED]:
            if kept and np.min(wrapped_distance(np.asarray(kept), q, wrap)) < min_distance:
                continue
            kept.append(q.copy())
            found_at.append((used, elapsed))
            if len(kept) >= n:
                break

    seed_label = (
        None if isinstance(seed, np.random.Generator) else (0 if seed is None else int(seed))
    )
    results = []
    for q, (n_ev, t_found) in zip(kept, found_at, strict=True):
        dp, dr = verify(problem, q)
        within = bool(np.all(q >= lower - 1e-12) and np.all(q <= upper + 1e-12))
        success = within and dp <= tol_pos and (problem.position_only or dr <= tol_rot)
        if not success:  # the kernel's check disagrees with Pinocchio's: never report it
            continue
        fit = float(problem.fitness(q[None])[0])
        results.append(
            Result(
                q=q,
                fitness=fit,
                position_error=dp,
                rotation_error=dr,
                n_evals=int(n_ev),
                time_s=float(t_found),
                success=True,
                within_limits=within,
                history=np.array([fit]),
                solver=SOLVER_NAME,
                seed=seed_label,
            )
        )
    results.sort(key=lambda r: r.fitness)
    return results
