"""``swarm_ik.solve``: run a registered solver on an IK problem and check its answer."""

from __future__ import annotations

import math
import time
import warnings
from typing import Any

import numpy as np

from swarm_ik.errors import InvalidArgumentError, unknown
from swarm_ik.optimize import check_budget, make_rng
from swarm_ik.pose import is_finite_nonneg
from swarm_ik.problem import IKProblem
from swarm_ik.result import Result
from swarm_ik.solvers import base

DEFAULT_SOLVER = "swarm"

PREFER = ("best", "nearest")
"""Answer selection modes of :func:`solve`."""


def verify(problem: IKProblem, q: Any) -> tuple[float, float]:
    """Largest position error [m] and angular error [rad] over the primary goals at ``q``,
    computed with Pinocchio's own FK (0 where no goal has such an error)."""
    if not isinstance(problem, IKProblem):
        raise InvalidArgumentError(f"problem must be an IKProblem, got {type(problem).__name__}")
    errs = problem.verify(q)
    dp = max((e.position_error for e in errs if not math.isnan(e.position_error)), default=0.0)
    dr = max((e.rotation_error for e in errs if not math.isnan(e.rotation_error)), default=0.0)
    return float(dp), float(dr)


def unreachable_goal(problem: IKProblem) -> str | None:
    """A primary goal point beyond its frame's reach (:meth:`RobotModel.reach_radius`), if
    any: no joint vector can meet it.  Returns its label."""
    from swarm_ik.goals import Pose, Position

    for gl in problem.goals:
        if not gl.primary:
            continue
        if isinstance(gl, Pose):
            point = gl.target[:3, 3]
        elif isinstance(gl, Position):
            point = gl.point
        else:
            continue
        if float(np.linalg.norm(point)) > problem.robot.reach_radius(gl.frame) * (1 + 1e-9):
            return gl.describe()
    return None


def end_reason(problem: IKProblem, success: bool, ev: base.Evaluator) -> str:
    """Why a solve ended (see :attr:`swarm_ik.result.Result.reason`)."""
    if success:
        return "converged"
    if unreachable_goal(problem) is not None:
        return "unreachable"
    if ev.max_evals is not None and ev.n_evals >= ev.max_evals:
        return "budget"
    if ev.time_limit is not None and ev.elapsed >= ev.time_limit:
        return "time_limit"
    if ev.max_evals is None and ev.time_limit is None:
        return "local_minima"
    return "stopped"


def prepare_q0(problem: IKProblem, q0: Any) -> np.ndarray | None:
    """Validate ``q0``: right length and finite (refused otherwise); outside the bounds it is
    clipped into them with a warning (continuous joints wrapped first)."""
    if q0 is None:
        return None
    q = problem.robot.wrap(problem.robot.check_q(q0, "q0"))
    fixed = np.clip(q, problem.lower, problem.upper)
    outside = np.flatnonzero(fixed != q)
    if outside.size:
        names = [problem.robot.joint_names[i] for i in outside]
        warnings.warn(
            f"q0 lies outside the joint limits at {names}; clipped into them", stacklevel=3
        )
    return fixed


def solve(
    problem: IKProblem,
    solver: str = DEFAULT_SOLVER,
    *,
    seed: int | np.random.Generator | None = 0,
    max_evals: int | None = None,
    time_limit: float | None = None,
    q0: Any = None,
    tol_pos: float = 1e-5,
    tol_rot: float = 1e-5,
    stop_on_success: bool = True,
    prefer: str = "best",
    **params: Any,
) -> Result:
    """Solve an IK problem with a registered solver.

    Args:
        problem: The problem (robot, target, fitness, bounds).
        solver: Registry name; see :func:`swarm_ik.solvers.names`.
        seed: Non-negative integer seed or a ``numpy.random.Generator``; the same seed gives
            the same result.
        max_evals: Most fitness evaluations (a Jacobian evaluation counts as one); default:
            the solver's own iteration count.
        time_limit: Most wall-clock seconds.
        q0: Optional starting joint vector ``(nq,)``; refused when the length is wrong or
            values are not finite, clipped into the limits (with a warning) when outside.
        tol_pos: Position tolerance for success [m].
        tol_rot: Rotation tolerance for success [rad].
        stop_on_success: Stop as soon as the tolerances are met (False runs the whole budget,
            as the papers' experiments do).
        prefer: ``"best"`` (default: the lowest fitness found) or ``"nearest"``: among the
            solutions found, the one nearest to ``q0`` in joint space (continuous joints
            wrapped), so that successive targets along a Cartesian path give a smooth joint
            path.  ``"nearest"`` needs ``q0`` and a solver with a ``prefer`` parameter
            (``swarm``).
        **params: The solver's own parameters; unknown names are refused with the valid list.

    Returns:
        The frozen :class:`~swarm_ik.result.Result`; ``success`` is checked with Pinocchio's
        FK, never taken from the solver.
    """
    if not isinstance(problem, IKProblem):
        raise InvalidArgumentError(f"problem must be an IKProblem, got {type(problem).__name__}")
    spec = base.get(solver)
    if prefer not in PREFER:
        raise unknown("prefer mode", prefer, PREFER)
    if prefer != "best":
        if q0 is None:
            raise InvalidArgumentError(f"prefer={prefer!r} needs a starting point q0")
        if "prefer" not in spec.params:
            able = [n for n in base.names() if "prefer" in base.get(n).params]
            raise InvalidArgumentError(
                f"solver {solver!r} has no prefer={prefer!r} mode; solvers that have one: "
                + ", ".join(able)
            )
        params = {**params, "prefer": prefer}
    kwargs = spec.resolve(params)
    check_budget(max_evals, time_limit)
    for label, tol in (("tol_pos", tol_pos), ("tol_rot", tol_rot)):
        if not (is_finite_nonneg(tol) and float(tol) > 0):
            raise InvalidArgumentError(f"{label} must be a positive number, got {tol!r}")
    rng = make_rng(seed)
    q_start = prepare_q0(problem, q0)

    def stop(q: np.ndarray) -> bool:
        return problem.is_success(q, tol_pos, tol_rot)

    ev = base.Evaluator(
        problem.fitness,
        problem.lower,
        problem.upper,
        max_evals=max_evals,
        time_limit=time_limit,
        problem=problem,
        q0=q_start,
        stop=stop if stop_on_success else None,
        tolerance=(float(tol_pos), float(tol_rot)),
    )
    t0 = time.perf_counter()
    spec.run(ev, rng, **kwargs)
    elapsed = time.perf_counter() - t0
    q = ev.best_x.copy()
    if not np.isfinite(ev.best_f):  # nothing finite was evaluated: report the start honestly
        fit = float(problem.fitness(q[None])[0])
    else:
        fit = float(ev.best_f)
    goal_errors = problem.verify(q, tol_pos, tol_rot, q0=q_start)
    dp = max(
        (e.position_error for e in goal_errors if not math.isnan(e.position_error)), default=0.0
    )
    dr = max(
        (e.rotation_error for e in goal_errors if not math.isnan(e.rotation_error)), default=0.0
    )
    within = problem.within_bounds(q)
    success = within and all(e.met for e in goal_errors)
    return Result(
        q=q,
        fitness=fit,
        position_error=dp,
        rotation_error=dr,
        n_evals=ev.n_evals,
        time_s=elapsed,
        success=bool(success),
        within_limits=within,
        history=np.asarray(ev.history, dtype=float),
        solver=solver,
        seed=None if isinstance(seed, np.random.Generator) else (0 if seed is None else int(seed)),
        goal_errors=goal_errors,
        reason=end_reason(problem, bool(success), ev),
    )
