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
    from swarm_ik._validate import joint_vector

    errs = problem.verify(joint_vector(problem.robot, q))
    dp = max((e.position_error for e in errs if not math.isnan(e.position_error)), default=0.0)
    dr = max((e.rotation_error for e in errs if not math.isnan(e.rotation_error)), default=0.0)
    return float(dp), float(dr)


def unreachable_goal(problem: IKProblem) -> str | None:
    """A primary goal point beyond its frame's reach (:meth:`RobotModel.reach_radius`), if
    any: no joint vector can meet it.  Returns its label."""
    from swarm_ik.goals import AvoidCollisions, Pose, Position

    avoid = [gl for gl in problem.goals if isinstance(gl, AvoidCollisions) and gl.primary]
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
        for av in avoid:  # a goal point inside an obstacle: the robot would be in contact
            inside = av.obstacle_containing(point)
            if inside is not None:
                return f"{gl.describe()} inside obstacle {inside!r}"
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


def _fast_path(
    problem: IKProblem,
    solver: str,
    kwargs: dict[str, Any],
    q_start: np.ndarray | None,
    tol_pos: float,
    tol_rot: float,
    max_evals: int | None,
    time_limit: float | None,
    stop_on_success: bool,
    prefer: str,
    seed: int | None,
) -> Result | None:
    """The ``swarm`` solver's first step without its Python loop: polish the seed once in
    the compiled kernel; when it converges the answer is exactly the one the full run would
    return (its first start is this seed polish), else ``None`` and the full run follows."""
    if not (
        solver == "swarm"
        and stop_on_success
        and prefer == "best"
        and not problem.has_secondary
        and problem.fitness_name == "se3"
        and len(problem.goals) == 1
        and type(problem).fitness is IKProblem.fitness
        and not ({"fitness", "is_success", "residual_jacobian"} & set(vars(problem)))
    ):  # (a problem whose methods are wrapped, e.g. to record a trace, takes the full run)
        return None
    from swarm_ik.solvers.hybrid import CONVERGED, Polisher

    t0 = time.perf_counter()
    key = (float(tol_pos), float(tol_rot), tuple(sorted(kwargs.items())))
    pol = problem._table_cache.get(key)  # type: ignore[call-overload]
    if pol is None:
        lm_keys = ("max_iters", "lam0", "max_step", "stall_rel", "stall_iters", "tol_margin")
        pol = Polisher.from_problem(
            problem, tol_pos=tol_pos, tol_rot=tol_rot, **{k: kwargs[k] for k in lm_keys}
        )
        problem._table_cache[key] = pol  # type: ignore[index]
    seed_q = q_start if q_start is not None else 0.5 * (problem.lower + problem.upper)
    cap = pol.cfg.max_iters if max_evals is None else min(pol.cfg.max_iters, int(max_evals))
    if time_limit is not None and time_limit <= 0:
        return None
    out = pol.polish(seed_q[None], cap, True)
    if out.status[0] != CONVERGED:
        return None
    q = out.q[0].copy()
    fit = float(
        out.position_error[0]
        + (0.0 if problem.position_only else problem.w_rot) * out.rotation_error[0]
    )
    goal_errors = problem.verify(q, tol_pos, tol_rot)
    dp = goal_errors[0].position_error
    dr = goal_errors[0].rotation_error
    success = problem.within_bounds(q) and goal_errors[0].met
    return Result(
        q=q,
        fitness=fit,
        position_error=float(dp),
        rotation_error=0.0 if math.isnan(dr) else float(dr),
        n_evals=out.used,
        time_s=time.perf_counter() - t0,
        success=bool(success),
        within_limits=problem.within_bounds(q),
        history=np.array([fit]),
        solver=solver,
        seed=seed,
        goal_errors=goal_errors,
        reason="converged" if success else "stopped",
    )


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
    kwargs = spec.resolve(params, dim=problem.nq)
    check_budget(max_evals, time_limit)
    for label, tol in (("tol_pos", tol_pos), ("tol_rot", tol_rot)):
        if not (is_finite_nonneg(tol) and float(tol) > 0):
            raise InvalidArgumentError(f"{label} must be a positive number, got {tol!r}")
    rng = make_rng(seed)
    q_start = prepare_q0(problem, q0)
    problem.robot.warm_up()  # compiled kernels loaded before the clock starts
    seed_val = None if isinstance(seed, np.random.Generator) else (0 if seed is None else int(seed))
    fast = _fast_path(
        problem, solver, kwargs, q_start, tol_pos, tol_rot, max_evals, time_limit,
        stop_on_success, prefer, seed_val,
    )  # fmt: skip
    if fast is not None:
        return fast

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


class IKSolver:
    """A solver bound to one robot: validate once, solve many targets.

    Like roboticstoolbox's ``IKSolver`` or TRAC-IK's solver object: the settings are checked
    and the compiled kernels loaded when it is made, so each :meth:`solve` spends its time
    in the search, not in set-up.  Its results are exactly those of :func:`solve` with the
    same arguments.

    Args:
        robot: The robot (its first goal frame is the one a 4×4 target is for).
        solver: Registry name (default ``"swarm"``).
        tol_pos: Position tolerance [m].
        tol_rot: Angular tolerance [rad].
        time_limit: Most seconds per solve (None: the solver's own iteration count).
        max_evals: Most evaluations per solve.
        w_rot: Weight of the rotation error; 0 makes 4×4 targets position-only.
        **params: The solver's parameters (unknown names refused with the valid list).

    >>> import numpy as np, swarm_ik
    >>> robot = swarm_ik.load_robot("panda")
    >>> ik = swarm_ik.IKSolver(robot, time_limit=0.005)
    >>> ik.solve(robot.fk(robot.random_q(np.random.default_rng(0)))).success
    True
    """

    def __init__(
        self,
        robot: Any,
        solver: str = DEFAULT_SOLVER,
        *,
        tol_pos: float = 1e-5,
        tol_rot: float = 1e-5,
        time_limit: float | None = None,
        max_evals: int | None = None,
        w_rot: float = 1.0,
        **params: Any,
    ) -> None:
        from swarm_ik.robot import RobotModel

        if not isinstance(robot, RobotModel):
            raise InvalidArgumentError(
                f"robot must be a RobotModel (see swarm_ik.load_robot), got {type(robot).__name__}"
            )
        self.robot = robot
        self.solver = solver
        self.spec = base.get(solver)
        self.params = dict(params)
        self.spec.resolve(self.params)  # refuse unknown / bad parameters now
        check_budget(max_evals, time_limit)
        for label, tol in (("tol_pos", tol_pos), ("tol_rot", tol_rot)):
            if not (is_finite_nonneg(tol) and float(tol) > 0):
                raise InvalidArgumentError(f"{label} must be a positive number, got {tol!r}")
        self.tol_pos, self.tol_rot = float(tol_pos), float(tol_rot)
        self.time_limit, self.max_evals = time_limit, max_evals
        self._template = IKProblem(robot, robot.fk(robot.mid_q()), w_rot=w_rot)
        robot.warm_up()
        self.solve(self._template)  # the first solve's Python paths warmed too

    def solve(
        self, target: Any, q0: Any = None, seed: int | np.random.Generator | None = 0
    ) -> Result:
        """Solve one target.

        Args:
            target: A pose for the robot's first goal frame (4×4, ``(position, quaternion
                xyzw)``, 7 numbers, SE3) or an :class:`~swarm_ik.problem.IKProblem`.
            q0: Optional start ``(nq,)``.
            seed: Seed or Generator.

        Returns:
            The :class:`~swarm_ik.result.Result`, checked with Pinocchio.
        """
        problem = target if isinstance(target, IKProblem) else self._template.with_target(target)
        return solve(
            problem, self.solver, seed=seed, max_evals=self.max_evals,
            time_limit=self.time_limit, q0=q0, tol_pos=self.tol_pos, tol_rot=self.tol_rot,
            **self.params,
        )  # fmt: skip

    def __repr__(self) -> str:
        return (
            f"IKSolver(robot={self.robot.name!r}, solver={self.solver!r}, "
            f"tol_pos={self.tol_pos:g}, tol_rot={self.tol_rot:g}, time_limit={self.time_limit})"
        )
