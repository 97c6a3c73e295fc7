"""``swarm_ik.solve``: run a registered solver on an IK problem and check its answer."""

from __future__ import annotations

import dataclasses
import math
import time
import warnings
import weakref
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from swarm_ik.errors import InvalidArgumentError, unknown
from swarm_ik.optimize import check_budget, make_rng
from swarm_ik.pose import FLOAT64, ORTH_TOL, as_pose, is_finite_nonneg
from swarm_ik.problem import REPLACEABLE, GoalError, IKProblem, largest_errors
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

    return largest_errors(problem.verify(joint_vector(problem.robot, q)))


def unreachable_goal(problem: IKProblem) -> str | None:
    """A primary goal point beyond its frame's reach (:meth:`RobotModel.reach_radius`), if
    any: no joint vector can meet it.  Returns its label."""
    from swarm_ik.goals import AvoidCollisions, Pose, Position

    avoid = [gl for gl in problem.goals if isinstance(gl, AvoidCollisions) and gl.is_primary]
    for gl in problem.goals:
        if not gl.is_primary:
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


_LM_KEYS = ("max_iters", "lam0", "max_step", "stall_rel", "stall_iters", "tol_margin")


class _Compiled(NamedTuple):
    """A robot's compiled search state for one set of bounds, tolerances and parameters
    (cached per robot; see :func:`_compiled`)."""

    pol: Any  # swarm_ik.solvers.hybrid.Polisher (its table: the first problem's)
    head: list[Any]  # flat kernel arguments before the goal table (the tree)
    tail: list[Any]  # flat kernel arguments after it (bounds, settings)
    pop_size: int
    n_swarm: int
    iterations: int

    def static(self, table: Any) -> list[Any]:
        """The flat kernel arguments with this goal table."""
        return [*self.head, *table, *self.tail]


_STATE: weakref.WeakKeyDictionary[Any, dict[Any, _Compiled]] = weakref.WeakKeyDictionary()
"""Per robot (dropped with it): compiled search states by (tree, bounds, tolerances,
parameters)."""


def _compiled(
    problem: IKProblem, kwargs: dict[str, Any], tol_pos: float, tol_rot: float
) -> _Compiled:
    """The compiled search state for ``problem``'s robot, tree and bounds with these
    parameters, built once per robot and cached (a new ``IKProblem`` of the same robot
    reuses it; only its goal table is its own)."""
    per_robot = _STATE.get(problem.robot)
    if per_robot is None:
        per_robot = _STATE.setdefault(problem.robot, {})
    b = problem.bounds
    key = (
        id(problem.tree), b.lower.tobytes(), b.upper.tobytes(), b.wrap.tobytes(),
        float(tol_pos), float(tol_rot), tuple(sorted(kwargs.items())),
    )  # fmt: skip
    st = per_robot.get(key)
    if st is None or st.head[0] is not problem.tree[0]:
        from swarm_ik.kernels import search
        from swarm_ik.solvers.hybrid import Polisher, _check_params

        _check_params(
            kwargs["pop_size"], kwargs["iterations"], kwargs["swarm_fraction"],
            kwargs["max_iters"], "best", kwargs["nearest_starts"], kwargs["tol_margin"],
        )  # fmt: skip
        pol = Polisher.from_problem(
            problem, tol_pos=tol_pos, tol_rot=tol_rot, **{k: kwargs[k] for k in _LM_KEYS}
        )
        flat = search.flat_args(pol.tree, pol.table, pol.bounds, pol.cfg)
        n_tree, n_table = search.N_TREE, search.N_TABLE
        st = _Compiled(
            pol,
            flat[:n_tree],
            flat[n_tree + n_table :],
            int(kwargs["pop_size"]),
            int(round(kwargs["swarm_fraction"] * kwargs["pop_size"])),
            int(kwargs["iterations"]),
        )
        if len(per_robot) > 64:
            per_robot.clear()
        per_robot[key] = st
    return st


def _check_pose_goal(
    problem: IKProblem, q: np.ndarray, tol_pos: float, tol_rot: float
) -> tuple[tuple[Any, ...], bool] | None:
    """The Pinocchio check of a one-goal ``Pose`` / ``Position`` problem without
    :meth:`IKProblem.verify`'s general machinery: the goal frame's pose from Pinocchio
    (:meth:`RobotModel.fk_pinocchio`), its errors by the formulas of ``Pose.errors`` /
    ``Position.errors`` (compiled: equal to them to round-off), and whether ``q`` lies within
    the bounds.  ``None`` for any other problem (then ``verify`` runs)."""
    from swarm_ik.goals import Pose, Position

    if len(problem.goals) != 1:
        return None
    gl = problem.goals[0]
    if type(gl) is Pose:
        target = np.ascontiguousarray(gl.target, dtype=float)
        position_only = False
    elif type(gl) is Position:
        target = np.eye(4)
        target[:3, 3] = gl.point
        position_only = True
    else:
        return None
    return _pose_check(
        problem.robot.fk_pinocchio(q, gl.frame), gl.describe(), target, position_only, q,
        problem.lower, problem.upper, tol_pos, tol_rot,
    )  # fmt: skip


def _pose_check(
    reached: np.ndarray,
    label: str,
    target: np.ndarray,
    position_only: bool,
    q: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    tol_pos: float,
    tol_rot: float,
) -> tuple[tuple[Any, ...], bool]:
    """The independent check of one pose (``position_only``: position) goal: the errors of
    ``reached`` ``(4, 4)``, Pinocchio's pose of the goal frame at ``q``, against ``target``
    ``(4, 4)`` (the compiled twin of ``Pose.errors``) and whether ``q`` lies within
    ``[lower, upper]``; returns ``((GoalError,), within)``."""
    if not _ERRORS_ONE:  # (the kernel loads on first use: not on import)
        from swarm_ik.kernels.search import pose_errors_one

        _ERRORS_ONE.append(pose_errors_one)
    dp, dr, within = _ERRORS_ONE[0](reached, target, q, lower, upper)
    if position_only:
        dr = math.nan
    met = not (dp > tol_pos) and not (dr > tol_rot)
    return (GoalError.of(label, dp, dr, met),), within


_ERRORS_ONE: list[Any] = []


def _compiled_ok(problem: IKProblem, prefer: str) -> bool:
    """:func:`swarm_ik.solvers.hybrid.compiled_ok` (that module loads the search kernels'
    module: imported on first use, then looked up once)."""
    if not _COMPILED_OK:
        from swarm_ik.solvers import hybrid

        _COMPILED_OK.append(hybrid.compiled_ok)
    return bool(_COMPILED_OK[0](problem, prefer))


_COMPILED_OK: list[Any] = []


def _result(
    problem: IKProblem,
    q: np.ndarray,
    fit: float,
    goal_errors: tuple[Any, ...],
    within: bool,
    spent: Any,
    elapsed: float,
    history: np.ndarray,
    solver: str,
    seed: int | None,
) -> Result:
    """The :class:`Result` of a solve from its answer and its Pinocchio check (``spent``: the
    evaluator, or what :func:`end_reason` reads of one)."""
    dp, dr = largest_errors(goal_errors)
    if len(goal_errors) == 1:  # (the common case: no generator on every solve's path)
        success = bool(within and goal_errors[0].met)
    else:
        success = bool(within and all(e.met for e in goal_errors))
    return Result.of(
        q=q,
        fitness=fit,
        position_error=dp,
        rotation_error=dr,
        n_evals=int(spent.n_evals),
        time_s=elapsed,
        success=success,
        within_limits=bool(within),
        history=history,
        solver=solver,
        seed=seed,
        goal_errors=goal_errors,
        reason=end_reason(problem, success, spent),
    )


class _Call(NamedTuple):
    """One solve's settings, as :func:`solve` checked them (passed to its shortcuts)."""

    solver: str
    kwargs: dict[str, Any]
    q_start: np.ndarray | None
    tol_pos: float
    tol_rot: float
    max_evals: int | None
    time_limit: float | None
    stop_on_success: bool
    prefer: str
    seed: int | None


def _fast_path(problem: IKProblem, call: _Call) -> Result | None:
    """The ``swarm`` solver without an ``Evaluator``: the whole search in one compiled call
    (:func:`swarm_ik.kernels.search.swarm_search`), then the Pinocchio check.

    Taken for an integer seed, ``prefer="best"``, ``stop_on_success`` and a problem that
    :func:`swarm_ik.solvers.hybrid.compiled_ok` accepts (one primary goal, ``"se3"``, no
    secondary goal); its answer is bit-identical to the one :func:`swarm_ik.solvers.hybrid.run`
    returns through the ``Evaluator`` (same compiled search, same random key: the first draw
    of ``default_rng(seed)``).  Otherwise ``None`` and :func:`solve` runs the solver."""
    (
        solver,
        kwargs,
        q_start,
        tol_pos,
        tol_rot,
        max_evals,
        time_limit,
        stop_on_success,
        prefer,
        seed,
    ) = call
    if solver != "swarm" or not stop_on_success or prefer != "best" or seed is None:
        return None
    from swarm_ik.solvers import hybrid

    if not hybrid.compiled_ok(problem, prefer):
        return None
    st = _compiled(problem, kwargs, tol_pos, tol_rot)
    seed_q = q_start if q_start is not None else 0.5 * (problem.lower + problem.upper)
    t0 = time.perf_counter()
    out = hybrid.compiled_search(
        st.static(problem.table(None)), st.pol, np.ascontiguousarray(seed_q, dtype=float),
        hybrid.search_key(seed), stop=True, tol_pos=tol_pos, tol_rot=tol_rot,
        w_rot=0.0 if problem.position_only else float(problem.w_rot), pop_size=st.pop_size,
        n_swarm=st.n_swarm, iterations=st.iterations, max_evals=max_evals,
        remaining=max_evals if max_evals is not None else 2**62, evals_before=0,
        time_limit=time_limit, t0=t0,
    )  # fmt: skip
    elapsed = time.perf_counter() - t0
    q = out.q
    fit = out.fitness if math.isfinite(out.fitness) else float(problem.fitness(q[None])[0])
    checked = _check_pose_goal(problem, q, tol_pos, tol_rot)
    if checked is not None:
        goal_errors, within = checked
    else:
        goal_errors = problem.verify(q, tol_pos, tol_rot, q0=q_start)
        within = problem.within_bounds(q)
    spent = _Spent(max_evals, out.used, time_limit, elapsed)
    return _result(problem, q, fit, goal_errors, within, spent, elapsed, out.history, solver, seed)


class _Spent(NamedTuple):
    """What :func:`end_reason` reads of an evaluator, for the compiled path."""

    max_evals: int | None
    n_evals: int
    time_limit: float | None
    elapsed: float


def _collision_first_try(problem: IKProblem, call: _Call) -> Result | None:
    """A pose goal with a collision goal: first the compiled search for the pose alone; when
    its answer is collision-free by the exact check, that is the answer (most targets of an
    uncluttered scene), else ``None`` and the full search with the sphere rows follows."""
    if problem.has_secondary or not call.stop_on_success or call.prefer != "best":
        return None
    free = problem.without_collisions()
    if free is None or len(free.goals) != 1:
        return None
    t0 = time.perf_counter()
    first = _fast_path(free, call)
    if first is None or not first.success:
        return None
    col = problem.collision_goal
    if problem.robot.collision_model().collides(
        first.q, col.scene, col.margin, bool(col.self_collision)
    ):
        return None
    goal_errors = problem.verify(first.q, call.tol_pos, call.tol_rot, q0=call.q_start)
    if not all(e.met for e in goal_errors):
        return None
    return dataclasses.replace(
        first, goal_errors=goal_errors, time_s=time.perf_counter() - t0, reason="converged"
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
    on_improvement: Callable[[np.ndarray, float], Any] | None = None,
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
        on_improvement: Optional callback ``(q (nq,), fitness)`` called each time the best
            point found improves (e.g. to record a trace, :func:`swarm_ik.viz.solve_traced`).
        **params: The solver's own parameters; unknown names are refused with the valid list.

    Returns:
        The frozen :class:`~swarm_ik.result.Result`; ``success`` is checked with Pinocchio's
        FK, never taken from the solver.
    """
    if not isinstance(problem, IKProblem):
        raise InvalidArgumentError(f"problem must be an IKProblem, got {type(problem).__name__}")
    if (
        problem.plain_pose
        and solver == DEFAULT_SOLVER
        and not params
        and stop_on_success
        and prefer == "best"
        and on_improvement is None
        and type(seed) is int
        and 0 <= seed < 2**63
    ):
        ik = _lane(problem, tol_pos, tol_rot, time_limit, max_evals)
        if ik is not None:
            if problem.orth_tol == ORTH_TOL:  # (IKSolver re-checks a target at as_pose's)
                return ik.solve(problem.target, q0, seed)
            return ik._solve_pose(problem.target, q0, seed, problem=problem)
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
    plain_seed = isinstance(seed, (int, np.integer)) and not isinstance(seed, bool) and seed >= 0
    rng = None if plain_seed else make_rng(seed)  # (the fast path needs only the integer)
    q_start = prepare_q0(problem, q0)
    problem.robot.warm_up()  # compiled kernels loaded before the clock starts
    seed_val = None if isinstance(seed, np.random.Generator) else (0 if seed is None else int(seed))
    call = _Call(
        solver, kwargs, q_start, tol_pos, tol_rot, max_evals, time_limit, stop_on_success,
        prefer, seed_val,
    )  # fmt: skip
    fast = _fast_path(problem, call)
    if fast is None and solver == "analytic" and on_improvement is None:
        from swarm_ik.solvers import analytic  # closed form: no search loop to run

        fast = analytic.solve_result(problem, q_start, tol_pos, tol_rot, seed_val)
    if fast is None and problem.collision_goal is not None:
        fast = _collision_first_try(problem, call)
    if fast is not None:
        if on_improvement is not None:
            on_improvement(fast.q.copy(), fast.fitness)
        return fast
    if rng is None:
        rng = make_rng(seed)

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
        on_improvement=on_improvement,
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
    return _result(
        problem, q, fit, goal_errors, problem.within_bounds(q), ev, elapsed,
        np.asarray(ev.history, dtype=float), solver, seed_val,
    )  # fmt: skip


def _lane(
    problem: IKProblem,
    tol_pos: float,
    tol_rot: float,
    time_limit: float | None,
    max_evals: int | None,
) -> IKSolver | None:
    """The cached :class:`IKSolver` that answers ``solve(problem, …)`` for a plain pose
    problem (:attr:`IKProblem.plain_pose`) of the default solver with default parameters: the
    same compiled search with the same key, so the same :class:`Result` as the general path,
    without rebuilding the goal table and the search state on every call.  One per robot and
    settings (made on first use: it validates the settings, raising what ``solve`` raises);
    ``None`` when the problem's methods were replaced (then the general path runs)."""
    if type(problem) is IKProblem:  # (a plain pose problem: one primary goal, "se3")
        if not REPLACEABLE.isdisjoint(vars(problem)):
            return None
    elif not _compiled_ok(problem, "best"):
        return None
    lanes = problem.robot._cache.get("solve_lanes")
    if lanes is None:
        lanes = problem.robot._cache["solve_lanes"] = {}
    key = (tol_pos, tol_rot, time_limit, max_evals, problem.w_rot)
    try:
        ik: IKSolver | None = lanes.get(key)
    except TypeError:  # an unhashable setting: the general path checks and refuses it
        return None
    if ik is None:
        if len(lanes) > 64:
            lanes.clear()
        ik = IKSolver(
            problem.robot, tol_pos=tol_pos, tol_rot=tol_rot, time_limit=time_limit,
            max_evals=max_evals, w_rot=problem.w_rot,
        )  # fmt: skip
        lanes[key] = ik
    return ik if ik._state is not None else None


_HISTORY_CAP = 62
"""History entries an :class:`IKSolver` call receives in its output buffer (a longer history
comes back as its own array)."""

_RAN, _CHECK_TARGET = 0, 1
"""``swarm_ik.kernels.search.RAN`` and ``CHECK_TARGET`` (that module loads numba; a test checks
they are equal)."""


def _rebuild_ik_solver(robot: Any, solver: str, kwargs: dict[str, Any]) -> IKSolver:
    return IKSolver(robot, solver, **kwargs)


class IKSolver:
    """A solver bound to one robot: validate once, solve many targets.

    Like roboticstoolbox's ``IKSolver`` or TRAC-IK's solver object: the settings are checked,
    the compiled kernels loaded and the compiled search state (tree, goal table, bounds,
    settings: one :class:`swarm_ik.kernels.search.PoseSolver`) built when it is made, so each
    :meth:`solve` of a 4×4 target spends its Python time on checking the arguments, one
    compiled call (:func:`swarm_ik.kernels.search.solve_pose`), the Pinocchio check and the
    :class:`~swarm_ik.result.Result`.  Its results are exactly those of :func:`solve` with the
    same arguments.  Safe to share between threads: the compiled call holds the GIL (it is
    not ``nogil``), so the search scratch kept in its ``PoseSolver`` serves one call at a
    time, and each call has its own output buffer and Pinocchio data.  Pickled as its
    arguments.

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
        self._kwargs = self.spec.resolve(self.params)  # refuse unknown / bad parameters now
        check_budget(max_evals, time_limit)
        for label, tol in (("tol_pos", tol_pos), ("tol_rot", tol_rot)):
            if not (is_finite_nonneg(tol) and float(tol) > 0):
                raise InvalidArgumentError(f"{label} must be a positive number, got {tol!r}")
        self.tol_pos, self.tol_rot = float(tol_pos), float(tol_rot)
        self.time_limit, self.max_evals = time_limit, max_evals
        self._template = IKProblem(robot, robot.fk_pinocchio(robot.mid_q()), w_rot=w_rot)
        self._state = None
        self._fast: tuple[Any, ...] | None = None
        if solver == "swarm":
            from swarm_ik.solvers import hybrid

            if hybrid.compiled_ok(self._template, "best"):
                self._state = _compiled(self._template, self._kwargs, self.tol_pos, self.tol_rot)
        tpl = self._template
        self._w_rot = 0.0 if tpl.position_only else float(tpl.w_rot)
        self._mid = np.ascontiguousarray(0.5 * (tpl.lower + tpl.upper))
        self._label = tpl.goals[0].describe()
        self._nq = tpl.nq
        self._pinocchio_pose = robot.fk_pinocchio_bound()
        self._position_only = tpl.position_only
        # Pinocchio's configuration of the answer, written by the compiled call after q where
        # it is not q itself (continuous joints, mimic followers): the check's conversion
        # in compiled code (kinova: 11.6 -> 6.9 µs per check with cold caches, staged)
        pin_plan = robot.pinocchio_plan_arrays()
        self._nq_pin = pin_plan[2]
        self._out_len = tpl.nq + self._nq_pin + _HISTORY_CAP
        if self._state is not None:  # the compiled state and the kernel's entry point
            from swarm_ik.kernels import search

            st = self._state
            lim = self.time_limit
            search_args = (
                st.pol.kernel_tol_pos, st.pol.kernel_tol_rot, self.tol_pos, self.tol_rot,
                self._w_rot, st.pop_size, st.n_swarm, st.iterations,
                self.max_evals is None and lim is None,
                int(self.max_evals) if self.max_evals is not None else 2**62,
                -1 if self.max_evals is None else int(self.max_evals), 0,
                search.NO_LIMIT if lim is None else float(lim),
            )  # fmt: skip
            self._solver = search.pose_solver(
                st.pol.tree, tpl.table(None), st.pol.bounds, st.pol.cfg, search_args,
                self._position_only, pin_plan,
            )  # fmt: skip
            # the template's target (Pinocchio's FK: no FK kernel to load), as calls pass it
            reached = np.ascontiguousarray(robot.fk_pinocchio(self._mid))
            self._kernel = search.entry_point(
                search.solve_pose,
                (self._solver, reached, self._mid, True, True, 0.0, 0, np.empty(self._out_len)),
            )
            self._errors = search.entry_point(
                search.pose_errors_one, (reached, reached, self._mid, tpl.lower, tpl.upper)
            )
            self._fast = (  # what the common call reads, in one tuple
                self._kernel, self._solver, self._nq, self._out_len, self._mid,
                robot.fk_pinocchio_bound(configuration=True), self._nq_pin, self._errors,
                tpl.lower, tpl.upper, (self.tol_pos, self.tol_rot, self._position_only),
                time.perf_counter,
            )  # fmt: skip
        self.solve(self._template.target)  # the first solve's Python paths warmed too

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickled as its arguments (the compiled state is rebuilt where it is unpickled)."""
        kwargs = dict(
            tol_pos=self.tol_pos, tol_rot=self.tol_rot, time_limit=self.time_limit,
            max_evals=self.max_evals, w_rot=self._template.w_rot, **self.params,
        )  # fmt: skip
        return (_rebuild_ik_solver, (self.robot, self.solver, kwargs))

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
        fast = self._fast
        if (  # the common call, inline (with cold caches each Python call level costs µs)
            fast is not None
            and type(target) is np.ndarray
            and target.dtype is FLOAT64
            and target.shape == (4, 4)
            and target.flags.c_contiguous
            and type(seed) is int
            and 0 <= seed < 2**63
            and (q0 is None or (type(q0) is np.ndarray and q0.dtype is FLOAT64))
        ):
            kernel, state, nq, out_len, mid, pin_pose, nq_pin, errors, lower, upper, tols, clock = (
                fast
            )
            if q0 is None:
                q_start, start_checked = mid, True
            elif q0.shape == mid.shape and q0.flags.c_contiguous:
                q_start, start_checked = q0, False  # read, never written
            else:
                return self._solve_pose(target, q0, seed)
            out = np.empty(out_len)
            t0 = clock()
            status, used, fit, n_hist, history = kernel(
                state, target, q_start, False, start_checked, t0, seed, out
            )
            elapsed = clock() - t0
            if status != _RAN:  # (a target or start to check in Python: nothing ran)
                return self._solve_pose(target, q0, seed)
            q = out[:nq]
            if history is None:  # (it fit in out)
                history = out[nq + nq_pin : nq + nq_pin + n_hist]
            # the independent check: Pinocchio's pose of q (of its configuration, where that
            # is not q itself: written by the compiled call after q)
            reached = pin_pose(out[nq : nq + nq_pin] if nq_pin else q)
            if reached.flags.c_contiguous:
                dp, dr, within = errors(reached, target, q, lower, upper)
                tol_pos, tol_rot, position_only = tols
                if position_only:
                    dr = math.nan
                if within and not (dp > tol_pos) and not (dr > tol_rot) and fit < math.inf:
                    # converged and checked: the Result _finish would give, from dict displays
                    # (Result.of's thirteen keywords build and copy a dict: ≈ 4 µs cold)
                    goal_error = object.__new__(GoalError)
                    object.__setattr__(
                        goal_error, "__dict__",
                        {"goal": self._label, "position_error": dp, "rotation_error": dr,
                         "met": True, "details": None},
                    )  # fmt: skip
                    result = object.__new__(Result)
                    object.__setattr__(
                        result, "__dict__",
                        {"q": q, "fitness": fit, "position_error": dp,
                         "rotation_error": 0.0 if dr != dr else dr, "n_evals": used,
                         "time_s": elapsed, "success": True, "within_limits": True,
                         "history": history, "solver": self.solver, "seed": seed,
                         "goal_errors": (goal_error,), "reason": "converged"},
                    )  # fmt: skip
                    return result
            return self._finish(target, q, fit, used, elapsed, history, seed, None)
        if (
            self._state is None
            or isinstance(target, IKProblem)
            or not (type(seed) is int and 0 <= seed < 2**63)
        ):
            problem = (
                target if isinstance(target, IKProblem) else self._template.with_target(target)
            )
            return solve(
                problem, self.solver, seed=seed, max_evals=self.max_evals,
                time_limit=self.time_limit, q0=q0, tol_pos=self.tol_pos, tol_rot=self.tol_rot,
                **self.params,
            )  # fmt: skip
        return self._solve_pose(target, q0, seed)

    def _solve_pose(
        self, target: Any, q0: Any, seed: int, problem: IKProblem | None = None
    ) -> Result:
        """The per-call path of a pose target in any form: one compiled call (checks,
        search), then :meth:`_finish`.  A target or start the compiled checks do not pass is
        checked in Python (:func:`~swarm_ik.pose.as_pose`, :func:`prepare_q0`: refused, or
        fixed and marked checked) and the call repeated.  ``problem``: the plain pose problem
        whose (already validated) target this is, when :func:`solve` calls (its lane)."""
        target_checked = problem is not None
        tpl = self._template
        if type(target) is np.ndarray and target.dtype is FLOAT64 and target.shape == (4, 4):
            pose = np.ascontiguousarray(target)
            pose_checked = target_checked  # else checked when compiled
        else:
            pose, pose_checked = np.ascontiguousarray(as_pose(target), dtype=float), True
        q_start: Any
        if q0 is None:
            q_start, start_checked = self._mid, True
        elif (
            type(q0) is np.ndarray
            and q0.dtype is FLOAT64
            and q0.shape == self._mid.shape
            and q0.flags.c_contiguous
        ):
            q_start, start_checked = q0, False  # read, never written
        else:
            q_start, start_checked = prepare_q0(tpl, q0), True
        out = np.empty(self._out_len)
        kernel, state = self._kernel, self._solver
        while True:
            t0 = time.perf_counter()
            status, used, fit, n_hist, history = kernel(
                state, pose, q_start, pose_checked, start_checked, t0, seed, out
            )
            if status == _RAN:
                break
            if status == _CHECK_TARGET:
                pose, pose_checked = np.ascontiguousarray(as_pose(pose), dtype=float), True
            else:
                q_start, start_checked = prepare_q0(tpl, q0), True
        elapsed = time.perf_counter() - t0
        nq, nq_pin = self._nq, self._nq_pin
        q = out[:nq]
        if history is None:  # (it fit in out)
            history = out[nq + nq_pin : nq + nq_pin + n_hist]
        return self._finish(pose, q, fit, used, elapsed, history, seed, problem)

    def _finish(
        self,
        pose: np.ndarray,
        q: np.ndarray,
        fit: float,
        used: int,
        elapsed: float,
        history: np.ndarray,
        seed: int,
        problem: IKProblem | None,
    ) -> Result:
        """The Pinocchio check of the answer ``q`` to ``pose`` and its :class:`Result` (the
        reason of a failed solve read off ``problem``, or off the template with this
        target)."""
        tpl = self._template
        goal_errors, within = _pose_check(  # the independent check
            self._pinocchio_pose(q), self._label, pose, self._position_only, q, tpl.lower,
            tpl.upper, self.tol_pos, self.tol_rot,
        )  # fmt: skip
        (ge,) = goal_errors
        if not math.isfinite(fit):
            fit = ge.position_error + (
                0.0 if math.isnan(ge.rotation_error) else self._w_rot * ge.rotation_error
            )
        if problem is None:  # end_reason reads its target when the solve failed
            problem = tpl if within and ge.met else tpl.with_target(pose)
        spent = _Spent(self.max_evals, used, self.time_limit, elapsed)
        return _result(
            problem, q, float(fit), goal_errors, within, spent, elapsed, history, self.solver,
            seed,
        )  # fmt: skip

    def __repr__(self) -> str:
        return (
            f"IKSolver(robot={self.robot.name!r}, solver={self.solver!r}, "
            f"tol_pos={self.tol_pos:g}, tol_rot={self.tol_rot:g}, time_limit={self.time_limit})"
        )
