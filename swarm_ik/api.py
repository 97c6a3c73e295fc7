"""The one solve route: validate once, search, judge with Pinocchio, one frozen Result.

:class:`Route` binds a problem, a registered solver and the settings (everything validated
once); :meth:`Route.run` searches from a start and a seed and judges the answer with
Pinocchio.  :func:`solve` is a route made and run once; :class:`IKSolver` binds one per robot
and runs it for each target; :func:`swarm_ik.solve_many`, :func:`swarm_ik.solve_batch` and
:func:`swarm_ik.path.solve_path` speak the same vocabulary (``seed``, ``max_evals``,
``time_limit``, ``tol_pos``, ``tol_rot``, goals).

The default solver (``"swarm"``) runs its whole search in one compiled call
(:func:`swarm_ik.kernels.search.swarm_search`) when every goal is compiled, the answer is
``prefer="best"`` and no secondary goal needs the null-space descent; otherwise the route
runs the solver's own loop over an :class:`~swarm_ik.solvers.base.Evaluator` (paper solvers,
Python goals, secondary goals).  Both paths end in the same judge.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import threading
import time
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from swarm_ik import collision, kernels
from swarm_ik._validate import (
    check_seed,
    degrees_hint,
    flag,
    keywords_checked,
    plain_number,
    user_stacklevel,
)
from swarm_ik.argtypes import SEED_LIMIT
from swarm_ik.errors import InvalidArgumentError, UnknownNameError, unknown
from swarm_ik.goals import base as goals_base
from swarm_ik.goals.axis import angle_between
from swarm_ik.kernels import search
from swarm_ik.kernels.lie import exp3, log3, relative_angles
from swarm_ik.optimize import check_budget, make_rng, rising_estimate
from swarm_ik.pose import check_tolerances
from swarm_ik.problem import GoalError, IKProblem
from swarm_ik.result import Result
from swarm_ik.robot import RobotModel
from swarm_ik.scene import Scene, Sphere
from swarm_ik.solvers import base, hybrid

DEFAULT_SOLVER = "swarm"

PREFER = ("best", "nearest")
"""Answer selection modes of :func:`solve`."""

_LM_KEYS = ("max_iters", "lam0", "max_step", "stall_rel", "stall_iters", "tol_margin")


@keywords_checked
def verify(
    problem: IKProblem,
    q: Any,
    tol_pos: float = 1e-5,
    tol_rot: float = 1e-5,
    q0: Any = None,
) -> tuple[GoalError, ...]:
    """The independent check of ``q``: every primary goal's errors computed with Pinocchio's
    own kinematics (coal for collisions) and whether each is met (the same as
    :meth:`IKProblem.verify`).

    Args:
        problem: The problem.
        q: The joint vector ``(nq,)`` to check.
        tol_pos: Position tolerance [m].
        tol_rot: Angular tolerance [rad].
        q0: The solve's start ``(nq,)``, for goals that read it (``MinimalDisplacement``); a
            solve's ``Result`` was judged with its ``q0``.

    Raises:
        InvalidArgumentError: not a problem, ``q`` or ``q0`` of the wrong length or not
            finite, or a tolerance that is not a positive number.
    """
    if not isinstance(problem, IKProblem):
        raise InvalidArgumentError(f"problem must be an IKProblem, got {type(problem).__name__}")
    return problem.verify(q, tol_pos, tol_rot, q0=q0)


UNREACHABLE_BUDGET = (0.05, 3000)
"""``(seconds, evaluations)`` a solve spends at most on a problem :func:`unreachable_goal`
proves unreachable or :func:`conflicting_goals` proves contradictory, whatever budget it was
given (the seconds where it was given a time limit: without one, the evaluations alone bound
it, so that its result does not depend on the machine's speed): the best point found is still
returned (``reason="unreachable"`` or ``"conflicting_goals"``), and ``time_limit=1e9`` on a
target beyond reach returns at once."""


UNREACHABLE_PYTHON_EVALS = 300
"""The evaluations of :data:`UNREACHABLE_BUDGET` for a problem with goals written in Python
(each may take milliseconds: with a 10 ms goal and no time limit, 3,000 evaluations took 35 s
on a target 3 m beyond a UR5's reach; the best point is found in far fewer)."""


def unreachable_goal(
    problem: IKProblem, tol_pos: float = 1e-5, tol_rot: float = 1e-5
) -> str | None:
    """A primary goal point beyond its frame's reach (:meth:`RobotModel.reach_radius`), or
    inside an obstacle of a collision goal, or a primary goal that says it cannot be met
    within the tolerances (:meth:`swarm_ik.goals.Goal.infeasible`), if any: no joint vector
    can meet it.  Returns one line saying which goal and why (the goal's own reason where it
    gave one)."""
    for gl in problem.goals:
        if gl.is_primary:
            why = goal_unreachable(problem, gl, tol_pos, tol_rot)
            if why is not None:
                return why
    return None


def goal_unreachable(problem: IKProblem, gl: Any, tol_pos: float, tol_rot: float) -> str | None:
    """Why no joint vector can meet the goal ``gl`` of ``problem`` (:func:`unreachable_goal`'s
    test of one goal), or None when that is not known."""
    why = goals_base.infeasible_of(gl, problem.robot, tol_pos, tol_rot)
    if why is not None:
        return why
    held = goals_base.pin_of(gl, problem.robot)
    if held is None or held.point is None:
        return None
    point, slack = held.point, held.point_slack  # (a region reaches this much nearer)
    far = math.hypot(*(float(v) for v in point)) - slack  # (no overflow at 1e300 m)
    own_tol = gl.own_tolerance()  # (a Python goal's own position tolerance, if it has one)
    tol = tol_pos if own_tol is None else own_tol
    try:
        radius = problem.robot.reach_radius(held.frame)
    except UnknownNameError:  # (a frame of the model that no goal frame's path holds: a
        return None  # Python goal's; no bound on its reach is known here)
    if far > reach_limit(radius, tol):
        return (
            f"{gl.describe()} beyond its frame's reach (its point {far:.4g} m from the "
            f"world origin, the frame reaches {radius:.4g} m at most)"
        )
    if problem.robot.floating_base:
        off = float(_from_base_box(problem, np.asarray(point, dtype=float)[None])[0]) - slack
        own = problem.robot.reach_radius(held.frame, base=False)
        if off > reach_limit(own, tol):
            return (
                f"{gl.describe()} beyond its frame's reach (its point {off:.4g} m from the "
                f"floating base's box, the frame reaches {own:.4g} m from the base at most)"
            )
    avoid = problem.collision_goal
    if slack > 0.0 or avoid is None:
        return None  # (a region, not a point: it may reach out of an obstacle)
    if not _origin_in_body(problem.robot, held.frame):
        return None  # (a frame off the robot's bodies, a grasp point, may lie in an obstacle)
    inside = avoid.obstacle_containing(point, ORIGIN_REACH)  # (the robot in contact)
    if inside is not None:
        return f"{gl.describe()} inside obstacle {inside!r}"
    return None


def unreachable_targets(
    problem: IKProblem,
    points: Any,
    tol_pos: float = 1e-5,
    tol_rot: float = 1e-5,
    deadline: float | None = None,
) -> np.ndarray:
    """:func:`unreachable_goal` of each target of a batch, ``(N,)`` bool: ``problem``'s first
    goal is the target's own (its point rewritten per target: ``points`` ``(N, 3)`` [m]), its
    other goals are every target's.  The points are judged at once against the frame's reach;
    with a collision goal, those within it whose point lies in an obstacle's bounding box get
    coal's obstacle test (about 13 µs each), until ``deadline`` (``time.perf_counter()``
    seconds; None: none): a point not tested by then is not called unreachable."""
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    n = pts.shape[0]
    if n == 0 or any(
        goal_unreachable(problem, gl, tol_pos, tol_rot) is not None
        for gl in problem.goals[1:]
        if gl.is_primary
    ):
        return np.full(n, n > 0)
    frame = str(problem.goals[0].frame_name())
    far = np.hypot(np.hypot(pts[:, 0], pts[:, 1]), pts[:, 2])  # (no overflow at 1e300 m)
    out = far > reach_limit(problem.robot.reach_radius(frame), tol_pos)
    if problem.robot.floating_base:
        own = problem.robot.reach_radius(frame, base=False)
        out |= _from_base_box(problem, pts) > reach_limit(own, tol_pos)
    avoid = problem.collision_goal
    if avoid is not None and len(avoid.scene) and _origin_in_body(problem.robot, frame):
        lo, hi = avoid.scene.boxes()
        within = np.flatnonzero(~out)
        boxed = np.zeros(within.size, dtype=bool)
        for a in range(0, within.size, 4096):  # (points × boxes, a block of points at a time)
            p = pts[within[a : a + 4096], None, :]
            boxed[a : a + 4096] = np.any(np.all((lo <= p) & (p <= hi), axis=2), axis=1)
        for i in within[boxed].tolist():  # (coal's probe only in an obstacle's box)
            if deadline is not None and time.perf_counter() >= deadline:
                break
            out[i] = avoid.obstacle_containing(pts[i], ORIGIN_REACH) is not None
    return out


def _from_base_box(problem: IKProblem, points: np.ndarray) -> np.ndarray:
    """Distances [m] of ``points`` ``(N, 3)`` from the box a floating base's position keeps
    to (the problem's bounds on ``root_joint.x``, ``.y``, ``.z``, the first entries of ``q``:
    :data:`swarm_ik.robot.FREE_FLYER_ENTRIES`), ``(N,)``: the frame reaches
    :meth:`RobotModel.reach_radius` ``(base=False)`` at most from there."""
    gap = points - np.clip(points, problem.lower[:3], problem.upper[:3])  # (q's head: x y z)
    return np.hypot(np.hypot(gap[:, 0], gap[:, 1]), gap[:, 2])


def reach_limit(radius: float, tol_pos: float) -> float:
    """The distance from the world origin [m] past which a point is out of a frame's reach of
    ``radius`` (:meth:`RobotModel.reach_radius`, with room for its round-off), for a goal met
    within ``tol_pos`` [m] of its point: a point ``tol_pos`` beyond the reach is met at full
    stretch (review 134: a planar arm's point 9 µm beyond its 1 m reach was called unreachable
    at ``tol_pos=1e-5``, and a larger budget met it)."""
    return radius * (1 + 1e-9) + tol_pos


ORIGIN_REACH = 1e-3
"""[m] How near its frame's origin the robot's own geometry must come (:func:`_origin_in_body`)
and how deep inside an obstacle the goal point must lie for :func:`unreachable_goal` to call
the point unreachable: then the body is in contact wherever the frame meets it."""


def _origin_in_body(robot: RobotModel, frame: str) -> bool:
    """Whether the robot's own collision geometry comes within :data:`ORIGIN_REACH` of the
    origin of ``frame`` (coal's check of a sphere of that radius there, at mid-range: the
    frame is fixed to its link), so that the origin deep inside an obstacle means contact (a
    grasp point off the bodies does not).  Cached per robot and frame."""
    cache = robot._cache.setdefault("origin_in_body", {})
    if frame not in cache:
        q = robot.mid_q()
        probe = Scene([Sphere(ORIGIN_REACH, tuple(robot.fk(q, frame)[:3, 3]))])
        cache[frame] = robot.collision_model().collides(q, probe, 0.0, False)
    return bool(cache[frame])


def conflicting_goals(problem: IKProblem, tol_pos: float, tol_rot: float) -> str | None:
    """Two primary goals on one frame that no pose can meet together, if any: their labels.

    Found from what each goal holds its frame to (:meth:`swarm_ik.goals.Goal.pin`) alone,
    before any search, without knowing the goals' types:

    * two points farther apart than ``2·tol_pos`` plus their regions' reach;
    * two rotations further apart than ``2·tol_rot`` plus their regions' reach;
    * a rotation ``R`` and a frame axis ``a`` held along a world direction ``d`` (or towards
      a world point ``t`` when a point goal holds the frame's origin ``p``: ``d`` the unit
      vector from ``p`` to ``t``) with ``∠(R·a, d) > 2·tol_rot``;
    * two such axes, ``(a₁, d₁)`` and ``(a₂, d₂)``: a rotation keeps angles, so
      ``|∠(a₁, a₂) − ∠(d₁, d₂)| > 2·tol_rot`` cannot be met (the same axis along two
      directions, say).

    The angular allowances also hold the regions' reach (a bounded pose's rotation bounds, a
    point's ball seen from the point looked at)."""
    if sum(1 for gl in problem.goals if gl.is_primary) < 2:
        return None  # (one goal alone conflicts with nothing)
    points: dict[str, list[tuple[Any, Any, float]]] = {}
    rots: dict[str, list[tuple[Any, Any, float]]] = {}
    axes: dict[str, list[tuple[Any, Any, Any, float]]] = {}
    looks: list[tuple[Any, Any]] = []
    seen: set[tuple[Any, ...]] = set()  # (a goal given twice holds nothing new)
    for gl in problem.goals:
        held = goals_base.pin_of(gl, problem.robot) if gl.is_primary else None
        if held is None:
            continue
        same = tuple(v.tobytes() if isinstance(v, np.ndarray) else v for v in held)
        if same in seen:
            continue
        seen.add(same)
        if held.point is not None:
            points.setdefault(held.frame, []).append((gl, held.point, held.point_slack))
        if held.rotation is not None:
            rots.setdefault(held.frame, []).append((gl, held.rotation, held.rotation_slack))
        if held.axis is not None and held.direction is not None:
            axes.setdefault(held.frame, []).append((gl, held.axis, held.direction, 0.0))
        elif held.axis is not None and held.look_at is not None:
            looks.append((gl, held))
    for items in points.values():  # (each point against the later ones at once)
        pts = np.array([p for _, p, _ in items], dtype=float).reshape(-1, 3)
        slack = np.array([sp for _, _, sp in items], dtype=float)
        for i in range(len(items) - 1):
            far = (
                np.linalg.norm(pts[i + 1 :] - pts[i], axis=1)
                > 2 * tol_pos + slack[i] + slack[i + 1 :]
            )
            if far.any():
                return _pair(items, i, far)
    for gl, held in looks:  # (an axis towards a point is one along a known direction where
        # the frame's origin is held)
        for _, p, s in points.get(held.frame, [])[:1]:
            e = np.asarray(held.look_at, dtype=float) - p
            dist = float(np.linalg.norm(e))
            if dist > 2 * (s + tol_pos):  # (the direction known to within asin((s+tol)/dist))
                wobble = float(np.arcsin(min((s + tol_pos) / dist, 1.0)))
                axes.setdefault(held.frame, []).append((gl, held.axis, e / dist, wobble))
    allow = 2 * tol_rot
    for frame, items in rots.items():
        mats = np.array([r for _, r, _ in items], dtype=float).reshape(-1, 3, 3)
        slack = np.array([sr for _, _, sr in items], dtype=float)
        for i, (a, ra, sa) in enumerate(items):
            far = relative_angles(ra, mats[i + 1 :]) > allow + sa + slack[i + 1 :]
            if far.any():
                return _pair(items, i, far)
            for b, ax, d, sb in axes.get(frame, []):
                if angle_between(ra @ ax, d) > allow + sa + sb:
                    return f"{a.describe()} and {b.describe()}"
    for held_axes in axes.values():
        for i, (a, a1, d1, sa) in enumerate(held_axes):
            for b, a2, d2, sb in held_axes[i + 1 :]:
                if abs(angle_between(a1, a2) - angle_between(d1, d2)) > allow + sa + sb:
                    return f"{a.describe()} and {b.describe()}"
    return None


def _pair(items: list[Any], i: int, far: np.ndarray) -> str:
    """The labels of goal ``i`` of ``items`` and of the first later one ``far`` marks."""
    return f"{items[i][0].describe()} and {items[i + 1 + int(np.argmax(far))][0].describe()}"


def proven_failure(problem: IKProblem, tol_pos: float, tol_rot: float) -> str | None:
    """``"unreachable"`` where :func:`unreachable_goal` proves a goal unreachable,
    ``"conflicting_goals"`` where :func:`conflicting_goals` proves two goals contradictory,
    else None (nothing proven)."""
    if unreachable_goal(problem, tol_pos, tol_rot) is not None:
        return "unreachable"
    if conflicting_goals(problem, tol_pos, tol_rot) is not None:
        return "conflicting_goals"
    return None


def end_reason(
    problem: IKProblem,
    success: bool,
    n_evals: int,
    max_evals: int | None,
    elapsed: float,
    time_limit: float | None,
    tol_pos: float = 1e-5,
    tol_rot: float = 1e-5,
    q: Any = None,
) -> str:
    """Why a solve ended (see :attr:`swarm_ik.result.Result.reason`); ``q``: the answer, where
    goals pulling against each other (:meth:`IKProblem.opposing_goals`) are looked for."""
    if success:
        return "converged"
    proven = proven_failure(problem, tol_pos, tol_rot)
    if proven is not None:
        return proven
    if q is not None and problem.opposing_goals(q):
        return "conflicting_goals"
    if max_evals is not None and n_evals >= max_evals:
        return "budget"
    if time_limit is not None and elapsed >= time_limit:
        return "time_limit"
    if max_evals is None and time_limit is None:
        return "local_minima"
    return "stopped"


def prepare_q0(problem: IKProblem, q0: Any) -> np.ndarray | None:
    """Validate ``q0``: right length and finite (refused otherwise); outside the bounds it is
    clipped into them with a warning (continuous joints wrapped first, and a floating base's
    rotation vector to the same rotation of norm at most π)."""
    if q0 is None:
        return None
    robot = problem.robot
    q = robot.check_q(q0, "q0")  # (a copy)
    if robot.wrapped_mask() is not None:
        q = robot.wrap(q)
    # a floating base's rotation vector (entries 3-5, after its position) beyond π: the same
    # rotation, of norm ≤ π (clipped per component, [0, 0, 4] became [0, 0, π]: another heading)
    if robot.floating_base and float(np.linalg.norm(q[3:6])) > np.pi:
        q[3:6] = log3(exp3(q[3:6]))
    if problem.within_bounds(q, 0.0):
        return q
    fixed = np.clip(q, problem.lower, problem.upper)
    off = np.flatnonzero(fixed != q)
    names = [problem.robot.joint_names[i] for i in off]
    warnings.warn(  # (an angle beyond a full turn: most likely degrees)
        f"q0 lies outside the joint limits at {names}{degrees_hint(q[off])}; clipped into them",
        stacklevel=user_stacklevel(),
    )
    return fixed


_COMPILED: set[Any] = set()


def warm_up(route: Route) -> None:
    """Load the route's compiled kernels (numba's cache, or a compile on the first run)
    before any clock starts; a line on stderr says so when it takes longer than a second."""
    key = (
        route.compiled,
        route.solver,
        route.problem.has_secondary,
        bool(route.problem.python_goals),
        route.problem.collision_goal is not None,
    )
    if key in _COMPILED:
        return
    with kernels.announced():
        problem = route.problem
        q = np.ascontiguousarray(problem.robot.mid_q()).clip(problem.lower, problem.upper)
        problem.within_bounds(q)  # (the bounds test of a start, compiled)
        frozen = q.copy()
        frozen.setflags(write=False)  # (the judge's: the search's answer is read-only, another
        problem.within_bounds(frozen)  # type to numba, loaded at a first judge: 3-5 ms)
        # the search's clock: its objmode block compiles at its first call in each process
        # (40-80 ms), here rather than inside a solve's time limit
        search.now()
        search.key_of_seed(0)  # (every run keys its stream so: Route.run)
        if route.compiled:  # the one compiled call of the route (with a clock: its first
            # read is slow); a cache damaged inside its files is removed and compiled again
            kernels.loaded_despite_damage(
                lambda: route._search(q, np.uint64(1), 1, 60.0), mark=True
            )
        else:  # what the solvers' loops call, on a plain problem of the same goals (the
            # methods of a subclass or of the instance are the caller's: not run here), each
            # Python goal replaced by a stand-in: a user's goal may take milliseconds a call,
            # and the code around it, what loads kernels, is the same for any Python goal
            goals = goals_base.stand_ins(problem.goals, problem.lower, problem.upper)
            plain = IKProblem(problem.robot, goals=goals)
            plain.goal_errors(q)
            plain.residual_jacobian(q)
            if route.solver == "swarm":  # its loop: the compiled polish, null-space descent…
                ev = base.Evaluator(
                    plain.fitness, plain.lower, plain.upper, max_evals=200, problem=plain,
                    tolerance=(route.tol_pos, route.tol_rot),
                )  # fmt: skip
                route.spec.run(ev, make_rng(0), **route.kwargs)
            problem = plain
        if route.problem.collision_goal is not None:  # (the exact check's own kernel)
            collision.load_kernels()
        # the judge's first call (Pinocchio's check, the reasons' proofs: tens of ms once)
        route.judge(problem, q, 0.0, 0, 0.0, np.zeros(0), None)
    _COMPILED.add(key)


class Route:
    """The solve route bound to one problem: the solver, its parameters, the budgets and the
    tolerances validated once.

    Args:
        problem: The problem (its goals may change target between runs: see :meth:`run`).
        solver: Registry name; see :func:`swarm_ik.solvers.names`.
        max_evals: Most evaluations per run (a Jacobian evaluation counts as one).
        time_limit: Most wall-clock seconds per run.
        tol_pos: Position tolerance for success [m].
        tol_rot: Rotation tolerance for success [rad].
        stop_on_success: Stop as soon as the tolerances are met.
        prefer: ``"best"`` or ``"nearest"`` (nearest to ``q0``).
        params: The solver's own parameters.

    Raises:
        InvalidArgumentError, UnknownNameError: a bad setting (named, with the valid values).
    """

    def __init__(
        self,
        problem: IKProblem,
        solver: str = DEFAULT_SOLVER,
        *,
        max_evals: int | None = None,
        time_limit: float | None = None,
        tol_pos: float = 1e-5,
        tol_rot: float = 1e-5,
        stop_on_success: bool = True,
        prefer: str = "best",
        params: dict[str, Any] | None = None,
    ) -> None:
        if not isinstance(problem, IKProblem):
            raise InvalidArgumentError(
                f"problem must be an IKProblem, got {type(problem).__name__}"
            )
        params = dict(params or {})
        self.params = dict(params)  # (as given: the key of the routes this one borrows)
        self.spec = base.get(solver)
        if prefer not in PREFER:
            raise unknown("prefer mode", prefer, PREFER)
        if prefer != "best":
            if "prefer" not in self.spec.params:
                able = [n for n in base.names() if "prefer" in base.get(n).params]
                raise InvalidArgumentError(
                    f"solver {solver!r} has no prefer={prefer!r} mode; solvers that have one: "
                    + ", ".join(able)
                )
            params["prefer"] = prefer
        self.kwargs = self.spec.resolve(params, dim=problem.nq)
        check_budget(max_evals, time_limit)
        check_tolerances(tol_pos, tol_rot)
        self.problem = problem
        self.solver = solver
        self.max_evals = None if max_evals is None else int(max_evals)
        self.time_limit = None if time_limit is None else float(time_limit)
        self.tol_pos, self.tol_rot = float(tol_pos), float(tol_rot)
        self.stop_on_success = flag(stop_on_success, "stop_on_success")
        self.prefer = prefer
        self._lock = threading.Lock()
        self._warm = False  # (warm_up ran for this route)
        # (seconds a judge takes on this route: see _search_limit; a new route starts from
        # its robot's last one for problems of the same kind: a new scene's route overran a
        # 20 ms limit by its first judge, coal's check, 1-1.5 ms)
        self._judge_kind = (problem.collision_goal is not None, bool(problem.python_goals))
        self._judge_s = problem.robot._cache.get("judge_s", {}).get(self._judge_kind, 0.0)
        self._eval_s = 0.0  # (seconds per evaluation of the compiled search: _time_cap)
        # the first start without q0 when no goal names one (the middle of the ranges), found
        # at the first run without q0 (a goal's preferred_start is not asked when q0 is given)
        self._mid: Any = _NOT_YET
        self.compiled = (
            solver == "swarm" and self.stop_on_success and hybrid.compiled_ok(problem, prefer)
        )
        if self.compiled:
            kw = self.kwargs
            hybrid.check_params(
                kw["pop_size"], kw["iterations"], kw["swarm_fraction"], kw["max_iters"], prefer,
                kw["nearest_starts"], kw["tol_margin"],
            )  # fmt: skip
            self.pol = hybrid.Polisher.from_problem(
                problem, tol_pos=self.tol_pos, tol_rot=self.tol_rot,
                **{k: kw[k] for k in _LM_KEYS},
            )  # fmt: skip
            self._bound_goals = problem.compiled_goals
            p0 = self.pol.table.p0.tolist()  # each goal's block of the table's floats
            self._blocks = [(p0[i], p0[i + 1]) for i in range(len(p0) - 1)]
            self.search = hybrid.BoundSearch(
                self.pol, pop_size=kw["pop_size"],
                n_swarm=int(round(kw["swarm_fraction"] * kw["pop_size"])),
                iterations=kw["iterations"], stop=True, tol_pos=self.tol_pos,
                tol_rot=self.tol_rot, w_rot=0.0 if problem.position_only else problem.w_rot,
            )  # fmt: skip

    def _search(
        self,
        q_start: np.ndarray,
        key: np.uint64,
        max_evals: int | None,
        time_limit: float | None,
        cap: int | None = None,
    ) -> hybrid.SearchOutcome:
        """The compiled search from ``q_start`` on the route's state (``cap``: the most
        evaluations this run may spend besides its budget, see :meth:`_time_cap`)."""
        remaining = 2**62 if max_evals is None else max_evals
        if cap is not None:
            remaining = min(remaining, cap)
        return self.search(q_start, key, max_evals, remaining, 0, time_limit, time.perf_counter())

    def _time_cap(self, search_limit: float | None) -> int | None:
        """The evaluations a run under ``search_limit`` seconds may spend where one evaluation
        is slow (thousands of obstacles: about 1.5 ms each among 3,000 spheres), from the
        seconds per evaluation of this route's earlier runs; None where evaluations are fast.
        The search reads the clock between its polish calls (its first, of the seed alone,
        up to ``max_iters`` evaluations, the others at least 8): with slow evaluations a
        10 ms limit took 43 ms.  Only where ``max_iters`` evaluations would take more than a
        quarter of the limit, so that the cap never cuts a search its clock would have kept
        going (a 1 ms Panda solve: 30 evaluations take 45 µs)."""
        if search_limit is None or self._eval_s <= 0.0:
            return None
        if self.kwargs["max_iters"] * self._eval_s <= 0.25 * search_limit:
            return None
        return max(1, int(search_limit / self._eval_s))

    def _rebind(self, problem: IKProblem, q_start: np.ndarray | None) -> None:
        """Write the parameter blocks of ``problem``'s goals that differ from the bound ones
        (a new target) into the bound goal table."""
        goals = problem.compiled_goals
        bound = self._bound_goals
        if len(goals) != len(bound):
            raise InvalidArgumentError("a route runs problems of the goal types it was made for")
        floats = self.pol.table.par
        for i, (gl, old) in enumerate(zip(goals, bound, strict=True)):
            if gl is old and not getattr(gl, "uses_start", False):
                continue
            if type(gl) is not type(old) or gl.exact != old.exact:
                raise InvalidArgumentError(
                    "a route runs problems of the goal types it was made for"
                )
            par = problem.encode(i, q_start).par
            a, b = self._blocks[i]
            if par.shape[0] != b - a:
                raise InvalidArgumentError(
                    "a route runs problems of the goal types it was made for"
                )
            floats[a:b] = par
        self._bound_goals = goals

    def run(
        self,
        problem: IKProblem | None = None,
        q0: Any = None,
        seed: int | np.random.Generator | None = 0,
        on_improvement: Callable[[np.ndarray, float], Any] | None = None,
        spent: float = 0.0,
        budget: tuple[int | None, float | None] | None = None,
    ) -> Result:
        """Search and judge.

        Args:
            problem: The bound problem, or one of the same goal types with other targets
                (default: the bound one).
            q0: Optional start ``(nq,)`` (clipped into the bounds with a warning).
            seed: Integer seed in ``[0, 2**63)``, None or a Generator.
            on_improvement: Optional callback ``(q (nq,), fitness)`` at each improvement.
            spent: Seconds the call spent before this run (the route made, its kernels
                loaded), charged to ``time_limit`` with the run's own up to half of it.
            budget: ``(max_evals, time_limit)`` of this run in place of the route's (a
                route shared by runs of different budgets, each checked by the caller).

        Returns:
            The frozen :class:`~swarm_ik.result.Result`, judged with Pinocchio.
        """
        t_run = time.perf_counter()
        problem = self.problem if problem is None else problem
        if self.prefer == "nearest" and q0 is None:
            raise InvalidArgumentError("prefer='nearest' needs a starting point q0")
        seed = check_seed(seed)
        q_start = prepare_q0(problem, q0)
        if budget is None:
            budget = (self.max_evals, self.time_limit)
        max_evals, time_limit = budget
        if not self._warm:  # (the first run of a route: its kernels loaded, or compiled)
            warm_up(self)
            self._warm = True
        if time_limit is not None:  # what the call spent so far, charged to its budget up to
            # half of it (the search keeps the other half: a first call whose limit is shorter
            # than loading the kernels overruns by the loading, and still gets its answer)
            spent += time.perf_counter() - t_run
            time_limit = max(time_limit - spent, 0.5 * time_limit)
        seed_val = None if isinstance(seed, np.random.Generator) else (0 if seed is None else seed)
        cap_s, cap_evals = UNREACHABLE_BUDGET
        if problem.python_goals:
            cap_evals = min(cap_evals, UNREACHABLE_PYTHON_EVALS)
        over = (  # a budget beyond the cap (the solver's default one included)
            (time_limit or 0.0) > cap_s
            or (max_evals or 0) > cap_evals
            or (time_limit is None and max_evals is None)
        )
        if over and (
            unreachable_goal(problem, self.tol_pos, self.tol_rot) is not None
            or conflicting_goals(problem, self.tol_pos, self.tol_rot) is not None
        ):  # proven unreachable or contradictory: a large budget would buy nothing (no time
            # limit where none was given: a budget of evaluations stays deterministic)
            time_limit = None if time_limit is None else min(time_limit, cap_s)
            max_evals = cap_evals if max_evals is None else min(max_evals, cap_evals)
        if (
            problem.collision_goal is not None
            and self.solver == DEFAULT_SOLVER
            and self.stop_on_success
            and self.prefer == "best"
            and on_improvement is None
            and not problem.has_secondary
            and (max_evals is None or max_evals >= 2)  # (one evaluation: the search alone)
        ):
            t_first = time.perf_counter()
            # (the tries' seeds: the integer seed, or one draw of the Generator, so that a
            # Generator in one state gives one answer as an integer seed does)
            first_seed = seed_val
            if isinstance(seed, np.random.Generator):
                first_seed = int(seed.integers(0, SEED_LIMIT))
            assert first_seed is not None
            # (the tries get half of what the judge leaves: a try that passes is judged too)
            first, first_evals = self._collision_free_first(
                problem, q_start, first_seed, self._search_limit(time_limit), max_evals
            )
            if first is not None:  # (its seed as the caller gave it: None for a Generator)
                return dataclasses.replace(first, seed=seed_val)
            first_s = time.perf_counter() - t_first
            if time_limit is not None:  # (the rest of the budget for the search with rows)
                time_limit = max(time_limit - first_s, 1e-4)
            if max_evals is not None:  # (at least one left: the tries take at most half)
                max_evals = max(max_evals - first_evals, 1)
        else:
            first_s, first_evals = 0.0, 0
        search_limit = self._search_limit(time_limit)
        # an integer seed keys the compiled search itself (one SplitMix64 step); a Generator
        # gives its first draw
        key = None if seed_val is None else search.key_of_seed(seed_val)
        if self.compiled and on_improvement is None:
            if key is None:
                key = search.stream_key(seed)  # type: ignore[arg-type]
            seed_q = q_start  # (prepare_q0's copy: float64, contiguous)
            if seed_q is None:
                if self._mid is _NOT_YET:
                    named = goals_base.preferred_start_of(self.problem.goals, self.problem.robot)
                    self._mid = None if named is not None else hybrid.default_seed(self.problem)
                mid, bound = self._mid, self.problem
                # (one Bounds per robot for its own limits: see IKProblem)
                same_box = problem.bounds is bound.bounds
                seed_q = mid if mid is not None and same_box else hybrid.default_seed(problem)
                seed_q = np.ascontiguousarray(seed_q, dtype=float)
            cap = self._time_cap(search_limit)
            with self._lock:  # (the bound table and scratch serve one run at a time)
                self._rebind(problem, q_start)
                t0 = time.perf_counter()
                with goals_base.kernel_errors_named(lambda: list(problem.compiled_goals)):
                    out = self._search(seed_q, key, max_evals, search_limit, cap)
                elapsed = time.perf_counter() - t0
            if out.used >= 8:  # (seconds per evaluation, rising at once, falling slowly; a
                # run of a few evaluations is mostly the call's fixed cost)
                self._eval_s = rising_estimate(self._eval_s, elapsed / out.used)
            if cap is not None and out.used >= cap and search_limit is not None:
                search_limit = min(search_limit, elapsed)  # (the limit's evaluations spent)
            q, fit, n_evals, history = out.q, out.fitness, out.used, out.history
            q.setflags(write=False)  # (the search's own arrays: the Result keeps them as they
            history.setflags(write=False)  # are, read-only, instead of copying them)
            n_evals += first_evals
            elapsed += first_s
            if not math.isfinite(fit) or len(problem.goals) > 1:  # (the problem's own sum)
                fit = float(problem.fitness(q[None])[0])
        else:
            tol_pos, tol_rot = self.tol_pos, self.tol_rot

            def stop(q: np.ndarray) -> bool:
                return problem.is_success(q, tol_pos, tol_rot)

            ev = base.Evaluator(
                problem.fitness, problem.lower, problem.upper, max_evals=max_evals,
                time_limit=search_limit, problem=problem, q0=q_start,
                stop=stop if self.stop_on_success else None, tolerance=(tol_pos, tol_rot),
                on_improvement=on_improvement, key=key,
            )  # fmt: skip
            t0 = time.perf_counter()
            # the values of Python goals computed once per point, the answer's kept for the
            # judge (a slow goal's stop test, fitness and check read the search's evaluation)
            with (
                goals_base.reuse_goal_values(bool(problem.python_goals), park=True),
                kernels.ctrl_c_counted(raise_at_end=True),  # (a Ctrl-C a kernel lost: raised)
            ):
                self.spec.run(ev, make_rng(seed), **self.kwargs)
                elapsed = time.perf_counter() - t0
                q = ev.best_x.copy()
                fit = ev.best_f if np.isfinite(ev.best_f) else problem.fitness(q[None])[0]
                fit = float(fit)
            n_evals, history = ev.n_evals, np.asarray(ev.history, dtype=float)
            n_evals += first_evals
            elapsed += first_s
        t_judge = time.perf_counter()
        result = self.judge(
            problem, q, fit, n_evals, elapsed, history, seed_val, q_start,
            limit=search_limit, max_evals=budget[0],
        )  # fmt: skip
        # what judging costs this route (rising at once, falling slowly): kept out of the
        # search's time limit, so that the whole call stays within it
        self._judge_s = rising_estimate(self._judge_s, time.perf_counter() - t_judge)
        problem.robot._cache.setdefault("judge_s", {})[self._judge_kind] = self._judge_s
        return result

    def _search_limit(self, time_limit: float | None) -> float | None:
        """The search's share of ``time_limit``: less what judging its answer costs on this
        route (measured on its earlier runs), at most 90 % of it (coal's check of a collision
        goal takes most of a 1 ms limit: half of it kept for the search overran such a limit
        by 70 %)."""
        if time_limit is None:
            return None
        return time_limit - min(self._judge_s, 0.9 * time_limit)

    def _collision_free_first(
        self,
        problem: IKProblem,
        q_start: np.ndarray | None,
        seed: int,
        time_limit: float | None,
        max_evals: int | None,
    ) -> tuple[Result | None, int]:
        """A problem with a collision goal, first solved without it: searches of the other
        goals (from ``q_start``, then from random starts) for half of ``time_limit`` and of
        ``max_evals`` (without a time limit: at most :data:`COLLISION_FIRST_TRIES` searches,
        and none after one that does not meet the other goals),
        each answer checked by coal's exact check and judged on the whole problem; the first
        that passes is the answer.  Most
        targets of a scene are answered so, exactly, without the search's conservative
        sphere rows (which refuse some free answers: in a cubby or between narrow shelf boards
        the spheres put 30–46 % of the Panda's free generating configurations in contact,
        ``docs/results/collision/hard``, its diagnosis).
        Returns ``(the answer, evaluations)``, the answer None when no try passes (the search
        with the rows follows)."""
        free = problem.without_collisions()
        if free is None:
            return None, 0
        t0 = time.perf_counter()
        share = None if time_limit is None else 0.5 * time_limit
        half = None if max_evals is None else max(max_evals // 2, 1)
        settings = dict(
            max_evals=None, time_limit=None, tol_pos=self.tol_pos,
            tol_rot=self.tol_rot, stop_on_success=True, prefer="best", params=self.params,
        )  # fmt: skip
        # (one route per robot and goal types, whatever the budget: each try is given what is
        # left of the half; a route keyed by that budget was made again on every call)
        route = route_for(free, self.solver, settings)
        rng = None  # (the random starts' stream, made when a second try needs one)
        col = problem.collision_goal
        collides = problem.robot.collision_model().collides
        evals = 0
        k = 0
        check_s = 0.0  # (what coal's check of a try's answer took: kept out of the share)
        while share is not None or k < COLLISION_FIRST_TRIES:
            spent = time.perf_counter() - t0
            if share is not None and spent + check_s >= share:
                break
            if half is not None and evals >= half:
                break
            if k > 0 and rng is None:
                rng = np.random.default_rng(seed)
            start = q_start if rng is None else rng.uniform(problem.lower, problem.upper)
            left = (
                None if half is None else half - evals,
                None if share is None else share - spent - check_s,  # (> 0: tested above)
            )
            res = route.run(free, start, (seed + k) % SEED_LIMIT, budget=left)
            evals += res.n_evals
            k += 1
            if not res.success:
                if share is None:
                    break  # (no time limit: a search that cannot meet the other goals ends them)
                continue
            t_check = time.perf_counter()
            free_q = not collides(res.q, col.scene, col.margin, bool(col.self_collision))
            check_s = rising_estimate(check_s, time.perf_counter() - t_check)
            if free_q:
                out = self.judge(
                    problem, res.q, res.fitness, evals, 0.0, res.history, seed, q_start
                )
                if out.success:
                    return dataclasses.replace(out, time_s=time.perf_counter() - t0), evals
        return None, evals

    def judge(
        self,
        problem: IKProblem,
        q: np.ndarray,
        fitness: float,
        n_evals: int,
        elapsed: float,
        history: np.ndarray,
        seed: int | None,
        q_start: np.ndarray | None = None,
        limit: float | None = None,
        max_evals: int | None = None,
    ) -> Result:
        """The one judge: the answer's errors from Pinocchio, its limits, why it ended
        (``limit``: the search's time limit, when it was given less than the route's; the
        reason reads the search's ``elapsed`` seconds against it).  A Python goal is judged
        from the values the search kept for the answer
        (:func:`swarm_ik.goals.base.reuse_goal_values`), each computed once; ``time_s`` is
        the search's ``elapsed``."""
        scope = goals_base.reuse_goal_values(resume=True) if problem.python_goals else _NO_SCOPE
        with scope:  # (a slow goal: its values at q computed once, if not yet)
            goal_errors = problem.verify_checked(q, self.tol_pos, self.tol_rot, q_start)
            within = problem.within_bounds(q)
            success = within
            dp = dr = 0.0
            for e in goal_errors:
                success = success and e.met
                if e.position_error > dp:  # (NaN: no such error)
                    dp = e.position_error
                if e.rotation_error > dr:
                    dr = e.rotation_error
            reason = end_reason(
                problem,
                success,
                n_evals,
                self.max_evals if max_evals is None else max_evals,
                elapsed,
                self.time_limit if limit is None else limit,
                self.tol_pos,
                self.tol_rot,
                q,
            )
            return Result(
                q=q,
                fitness=float(fitness),
                position_error=float(dp),
                rotation_error=float(dr),
                n_evals=int(n_evals),
                time_s=float(elapsed),
                success=success,
                within_limits=bool(within),
                history=history,
                solver=self.solver,
                seed=seed,
                goal_errors=goal_errors,
                reason=reason,
            )


_NOT_YET = object()
"""A value a route finds when first needed (:attr:`Route._mid`)."""

_NO_SCOPE = contextlib.nullcontext()
"""The judge's scope for a problem without Python goals (nothing kept)."""

COLLISION_FIRST_TRIES = 256
"""Searches without the collision goal a solve with no time limit makes before the search
with its rows (:meth:`Route._collision_free_first`; with a limit: half of it; a batch target:
:data:`swarm_ik.batch.FREE_RETRIES_PER_START`).  Each that meets the other goals costs a
polish and coal's check (well under a millisecond among 45 boxes); with 4, a held-out set of
300 free targets among 45 boxes left 4 to the rows, which met none of them in a second of
search, where a time limit of 50 ms (its half: tens of tries) met all 300.  On another
held-out set (300 among 50 boxes, from 0.15 m of the base axis) 48 tries solved 294 in 3.7 s,
256 tries 298 in 1.6 s (fewer targets left to the rows' slower search), a time limit of
0.5 s 299."""


def route_for(problem: IKProblem, solver: str, settings: dict[str, Any]) -> Route:
    """The route of ``problem`` with ``settings`` (:class:`Route`'s keywords), shared by the
    problems of one robot that agree on everything but their targets (:func:`_route_key`)."""
    key = _route_key(problem, solver, settings)
    routes = problem.robot._cache.setdefault("routes", {})
    route = None if key is None else routes.get(key)
    if route is None:
        route = Route(problem, solver, **settings)
        if key is not None:
            if len(routes) >= 64:
                routes.clear()
            routes[key] = route
    return route  # type: ignore[no-any-return]


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
        problem: The problem (robot, goals, fitness, bounds).
        solver: Registry name; see :func:`swarm_ik.solvers.names`.
        seed: Integer seed in ``[0, 2**63)``, None, or a ``numpy.random.Generator``; the same
            seed gives the same result.
        max_evals: Most evaluations (a Jacobian evaluation counts as one); default: the
            solver's own iteration count.
        time_limit: Most wall-clock seconds.
        q0: Optional starting joint vector ``(nq,)``; refused when the length is wrong or
            values are not finite, clipped into the limits (with a warning) when outside.
        tol_pos: Position tolerance for success [m].
        tol_rot: Rotation tolerance for success [rad].
        stop_on_success: Stop as soon as the tolerances are met (False runs the whole budget,
            as the papers' experiments do).
        prefer: ``"best"`` (default: the lowest fitness found) or ``"nearest"``: among the
            solutions found, the one nearest to ``q0`` in joint space, each as its 2π copy
            within the limits nearest to ``q0`` on joints whose range is 2π or more (the same
            pose; continuous joints wrapped).  ``"nearest"`` needs ``q0`` and a solver with a
            ``prefer`` parameter (``swarm``).
        on_improvement: Optional callback ``(q (nq,), fitness)`` called each time the best
            point found improves (e.g. to record a trace, :func:`swarm_ik.viz.solve_traced`).
        **params: The solver's own parameters; unknown names are refused with the valid list.

    Returns:
        The frozen :class:`~swarm_ik.result.Result`; ``success`` is checked with Pinocchio,
        never taken from the solver.
    """
    if not isinstance(problem, IKProblem):
        raise InvalidArgumentError(f"problem must be an IKProblem, got {type(problem).__name__}")
    if on_improvement is not None and not callable(on_improvement):
        raise InvalidArgumentError(
            "on_improvement must be None or a callable (q, fitness), got "
            f"{type(on_improvement).__name__}"
        )
    t_call = time.perf_counter()
    max_evals, time_limit = plain_number(max_evals), plain_number(time_limit)
    tol_pos, tol_rot = plain_number(tol_pos), plain_number(tol_rot)
    settings = dict(
        max_evals=max_evals, time_limit=time_limit, tol_pos=tol_pos, tol_rot=tol_rot,
        stop_on_success=stop_on_success, prefer=prefer, params=params,
    )  # fmt: skip
    route = route_for(problem, solver, settings)  # (a new route loads its kernels)
    return route.run(problem, q0, seed, on_improvement, spent=time.perf_counter() - t_call)


_ROUTE_SETTINGS = frozenset(
    ("max_evals", "time_limit", "tol_pos", "tol_rot", "stop_on_success", "prefer", "params")
)
"""The keywords of :class:`Route` a route's key names (:func:`_route_key`)."""


def _route_key(problem: IKProblem, solver: str, settings: dict[str, Any]) -> Any:
    """What a route bound to another problem must share with ``problem`` to run it (the
    solver, every setting, the goal types, frames, weights and priorities, the bounds, the
    tree, and each compiled goal's block sizes and integer parameters: a route rewrites only
    the floats), or None when a setting cannot be a key (then a route is made for this
    call)."""
    part = problem.__dict__.get("_route_key_part")
    if part is None:  # (the problem's share, made once per problem and kept by its retargeted
        # copies, with which it shares all of it: IKProblem.with_target)
        # (a bounded Pose or Position encodes other rows and flags: its form is part of the
        # key, as a route rebinds only the floats)
        goals = tuple(
            (type(g), g.frame_name(), g.weight, g.primary, g.exact) for g in problem.goals
        )
        # a goal that adds frames (collision bodies…) encodes more than floats: the goal itself
        adding = tuple(problem.compiled_goals[i] for i in sorted(problem._frame0))
        part = problem.__dict__["_route_key_part"] = (
            goals, adding, problem.fitness_name, problem.w_rot, problem.position_only,
            problem.lower.tobytes(), problem.upper.tobytes(), id(problem.tree),
            problem.python_goals == (), problem.__dict__.get("_blocks"),
        )  # fmt: skip
    if not settings.keys() <= _ROUTE_SETTINGS:  # (a setting the key below does not name)
        return None
    get, params = settings.get, settings.get("params") or {}
    values = tuple(
        plain_number(get(k))  # (a 0-d array, taken as its number, keys as it)
        for k in ("max_evals", "time_limit", "tol_pos", "tol_rot", "stop_on_success", "prefer")
    )
    # (each value's type too: True == 1 and 2000.0 == 2000, and a route found is not checked
    # again, so a value the checks refuse must not find the route of one they accept)
    key = (
        solver, values, tuple(map(type, values)),
        tuple(sorted((k, type(v), v) for k, v in params.items())) if params else (), part,
    )  # fmt: skip
    try:
        hash(key)
    except TypeError:  # a setting given as a list, say: no shared route
        return None
    return key


def _rebuild_ik_solver(robot: Any, solver: str, kwargs: dict[str, Any]) -> IKSolver:
    return IKSolver(robot, solver, **kwargs)


class IKSolver:
    """A solver bound to one robot: validate once, solve many targets.

    Like roboticstoolbox's ``IKSolver`` or TRAC-IK's solver object: the settings are checked
    and the route (:class:`Route`) bound to a pose problem of the robot's first goal frame
    when it is made, so each :meth:`solve` writes the new target into the bound goal table,
    searches and judges.  Its results are those of :func:`solve` with the same arguments.
    Pickled as its arguments.

    Args:
        robot: The robot (its first goal frame is the one a target is for).
        solver: Registry name (default ``"swarm"``).
        tol_pos: Position tolerance [m].
        tol_rot: Angular tolerance [rad].
        time_limit: Most seconds per solve (None: the solver's own iteration count).
        max_evals: Most evaluations per solve.
        w_rot: Weight of the rotation error; 0 makes targets position-only.
        prefer: ``"best"`` or ``"nearest"`` (each solve then needs ``q0``), as in
            :func:`solve`.
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
        prefer: str = "best",
        **params: Any,
    ) -> None:
        if not isinstance(robot, RobotModel):
            raise InvalidArgumentError(
                f"robot must be a RobotModel (see swarm_ik.load_robot), got {type(robot).__name__}"
            )
        self.robot = robot
        self.solver = solver
        self.params = dict(params)
        max_evals, time_limit = plain_number(max_evals), plain_number(time_limit)
        tol_pos, tol_rot = plain_number(tol_pos), plain_number(tol_rot)
        self.tol_pos, self.tol_rot = tol_pos, tol_rot
        self.time_limit, self.max_evals = time_limit, max_evals
        self.prefer = prefer
        self._template = IKProblem(robot, robot.fk_pinocchio(robot.mid_q()), w_rot=w_rot)
        self._route = Route(
            self._template, solver, max_evals=max_evals, time_limit=time_limit,
            tol_pos=tol_pos, tol_rot=tol_rot, prefer=prefer, params=params,
        )  # fmt: skip
        warm_up(self._route)

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickled as its arguments (the route is bound again where it is unpickled)."""
        kwargs = dict(
            tol_pos=self.tol_pos, tol_rot=self.tol_rot, time_limit=self.time_limit,
            max_evals=self.max_evals, w_rot=self._template.w_rot, prefer=self.prefer,
            **self.params,
        )  # fmt: skip
        return (_rebuild_ik_solver, (self.robot, self.solver, kwargs))

    @keywords_checked
    def solve(
        self, target: Any, q0: Any = None, seed: int | np.random.Generator | None = 0
    ) -> Result:
        """Solve one target.

        Args:
            target: A pose for the robot's first goal frame (4×4, ``(position, quaternion
                xyzw)``, 7 numbers, SE3) or an :class:`~swarm_ik.problem.IKProblem` of this
                robot (solved by :func:`solve` with this solver's settings).
            q0: Optional start ``(nq,)``.
            seed: Integer seed in ``[0, 2**63)``, None or a Generator.

        Returns:
            The :class:`~swarm_ik.result.Result`, checked with Pinocchio.
        """
        if isinstance(target, IKProblem):
            if target.robot is not self.robot:
                raise InvalidArgumentError("the problem is of another robot than this IKSolver's")
            return solve(
                target, self.solver, seed=seed, max_evals=self.max_evals,
                time_limit=self.time_limit, q0=q0, tol_pos=self.tol_pos, tol_rot=self.tol_rot,
                prefer=self.prefer, **self.params,
            )  # fmt: skip
        return self._route.run(self._template.with_target(target), q0, seed)

    def __repr__(self) -> str:
        return (
            f"IKSolver(robot={self.robot.name!r}, solver={self.solver!r}, "
            f"tol_pos={self.tol_pos}, tol_rot={self.tol_rot}, time_limit={self.time_limit}, "
            f"max_evals={self.max_evals}, prefer={self.prefer!r})"
        )
