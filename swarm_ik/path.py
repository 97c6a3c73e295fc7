"""Jump-free Cartesian paths: one IK solution per waypoint, consecutive ones close in joint space.

:func:`solve_path` takes ``N`` waypoints (poses of a frame, or goal lists) and returns a joint
path ``q (N, nq)`` whose consecutive configurations differ by at most ``max_joint_step`` on
every joint, when one exists among the candidates it builds, else the path with the fewest
such jumps (each one reported with its waypoint and size).

**Method.**

1. *Candidates per waypoint.*

   * every IK branch from :func:`swarm_ik.solve_many`; where the closed form applies (eaik,
     6R arms such as UR5/UR10) every in-limit 2π copy of each branch too, and the solutions
     found by polishing eaik's least-squares points (at a singular pose a pair of branches
     merging, or a whole continuum of solutions, comes back as one such point);
   * where the set is not known complete: solutions *tracked* from the previous waypoint's
     best candidates (each solved starting from that candidate, so the local polish lands on
     the nearest solution);
   * on a 7-joint arm with pose waypoints, samples covering its self-motion (a curve): the
     previous waypoint's samples tracked (one :func:`swarm_ik.solve_batch` call), the gaps
     and ends filled by walking along the null space of the Jacobian, a sample every
     :data:`COVER_STEP` of the bound, each polished back onto the waypoint; on other
     redundant problems, samples pushed along the self-motion around each tracked solution;
   * where every tracked candidate jumps, or none meets the waypoint, the waypoint's own
     spread of solutions (``solve_many``); if the path still jumps, a second pass tracks
     backwards from the last waypoint.

2. *Dynamic programming* through the layered graph: minimise lexicographically (number of
   steps beyond the bound, joint travel), the travel of a step being
   ``Σ_j |Δq_j| / max_joint_step_j`` (continuous joints wrapped).
3. ``densify=k``: each chosen step is checked by tracking ``k`` poses interpolated between
   its two waypoints (position lerp, rotation slerp) from the first configuration and on to
   the second; a step whose tracked chain loses the path or moves some joint, in total (out
   and back counts twice), by more than the bound counts as a jump, and the search is run
   again without it.  A step that stays put at a waypoint nothing meets (its stand-in: the
   configuration before it) is no motion, and is not tracked.

**Guarantees.**  ``success`` and the per-waypoint errors come from
:meth:`swarm_ik.IKProblem.verify` (Pinocchio's FK, coal for collisions), never from the
solver.  ``jump_free`` is measured on the returned ``q``.  When every waypoint's candidate
set is *certified complete* (closed form on a 6R arm with three parallel axes or a spherical
wrist, so at most 8 branches; no solution found by polishing eaik's least-squares points
that is not a known branch; no candidate with a Jacobian singular value below
:data:`SINGULAR_SIGMA`, where a continuum of solutions or a pair about to merge could hide
one) the dynamic programme is exhaustive: a path with jumps
then proves that no jump-free sequence of IK solutions through these waypoints exists (the
``reason`` says so, and ``exhaustive`` is True).  With other goals (collisions, …) each
complete set is filtered by them, and stays complete; a waypoint whose branches they all
reject is proven unreachable.  Otherwise the verdict is the best found.

A waypoint that nothing meets holds stand-ins: the configurations of the waypoint before it
(all of them, up to :data:`MAX_HELD`: staying put adds no jump) and the best failed
attempts; the reason says why it is not met (beyond reach, no closed-form branch within the
limits, or every branch rejected by the other goals: with a scene, "no collision-free IK
solution", naming the obstacle that holds the target point).

>>> import numpy as np, swarm_ik
>>> from swarm_ik.path import solve_path
>>> robot = swarm_ik.load_robot("ur5")
>>> qs = np.linspace([0.2, -1.2, 1.4, -0.6, 1.2, 0.1], [0.8, -0.9, 1.0, -0.9, 1.5, 0.4], 20)
>>> res = solve_path(robot, robot.fk(qs))
>>> res.success, res.jump_free
(True, True)
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from swarm_ik._validate import count, floats_or, keywords_checked, positive_float
from swarm_ik.api import conflicting_goals, reach_limit, unreachable_goal
from swarm_ik.branches import SINGULAR_SIGMA, sigma_min
from swarm_ik.errors import InvalidArgumentError, InvalidTargetError
from swarm_ik.goals import base as goals_base
from swarm_ik.kernels import joints
from swarm_ik.optimize import check_budget, make_rng
from swarm_ik.result import FrozenArrays

FloatArray = NDArray[np.float64]

DEFAULT_MAX_JOINT_STEP = 0.2
"""Default bound on each joint's change between consecutive waypoints [rad, or m]."""
BEAM = 8
"""Candidates of a waypoint (the best by the running dynamic programme) tracked into the next."""
SEEDS = 8
"""``n`` of :func:`swarm_ik.solve_many` for a waypoint's own spread of solutions (numerical)."""
CLOSED_FORM_N = 16
"""``n`` of :func:`swarm_ik.solve_many` where the closed form applies (every branch: ≤ 16)."""
TRACK_EVALS = 3000
"""Evaluation budget of one tracking solve (a budget, not a time limit: deterministic)."""
FINISH_PER_WAYPOINT = 2e-5
"""Seconds per waypoint that :func:`solve_path` keeps out of a ``time_limit`` for the check
of the path at its end (Pinocchio's FK and each waypoint's goals: 15–25 µs per waypoint
measured, Panda), with :data:`SEARCH_PER_LAYER` up to half the limit."""
FINISH_PER_WAYPOINT_SCENE = 5e-4
"""Seconds per waypoint more for the check at the end among obstacles: coal's verdict of each
waypoint, and its distances where a waypoint is left in contact (0.25–0.5 ms measured,
Panda among a box and a sphere: a 60-waypoint path's check took 15–32 ms, and overran a
50 ms limit by 30 ms with the scene-free reserve)."""
SEARCH_PER_LAYER = 5e-6
"""Seconds per waypoint kept for the search through the candidates (one compiled call per
layer: 2.5–3.5 µs measured), besides :data:`SEARCH_PER_PAIR`."""
SEARCH_PER_PAIR = 1e-8
"""Seconds per pair of candidates of consecutive waypoints kept for the search as the
candidates are built (7 ns measured on a UR5, 14–16 ns on a Panda: a UR5 circle of 200
waypoints has 8 million pairs, a 58 ms search), so that a ``time_limit`` stops building
candidates early enough for the search and the check to end within it."""
SEARCH_SHARE = 0.5
"""Share of a ``time_limit`` (after the check's reserve) for building candidates; the rest
tracks the remaining waypoints one solve each (unless the waypoints left fit: see
:meth:`_Context.out_of_time`)."""
TRACK_SHARE = 0.2
"""Share of a ``time_limit`` (after the check's reserve) that building candidates past
:data:`SEARCH_SHARE` always leaves to the tracking of the waypoints left."""
FULL_BRANCHES = 8
"""Branches (modulo 2π) of a generic pose of a 6R arm with three parallel axes or a
spherical wrist: a closed-form set with this many is complete."""
NEAR_SINGULAR = 1e-3
"""A closed-form candidate whose smallest Jacobian singular value is below this has the curve
of solutions through it sampled (:func:`_fill`), as a 7-joint arm's self-motion."""
DUPLICATE = 1e-3
"""Two candidates closer than this (largest ``|Δq_j| / max_joint_step_j``) are one."""
DIVERSE = 0.25
"""Tracked parents are picked at least this far apart (same measure) while there is choice."""
TIE_BREAK = 1e-6
"""Weight of the first configuration's distance to mid-range in the travel (ties only)."""
COVER_STEP = 0.4
"""Spacing of the self-motion samples of a 7-joint arm (largest ``|Δq_j| / max_joint_step_j``):
a path within ``1 − 2·COVER_STEP/2`` of the bound keeps a neighbour within the bound."""
COVER_MERGE = 0.1
"""Self-motion samples closer than this (same measure) are one."""
COVER_GAP = 2.0
"""A sample with no neighbour within ``COVER_GAP · COVER_STEP`` along the self-motion on one
side walks that way (a gap opened, or the end of the covered stretch)."""
MAX_COVER = 200
"""Most samples of one waypoint's self-motion (those of the previous waypoint tracked, then
the walks)."""
MAX_WALK = 200
"""Most steps of the walks along the self-motion of one waypoint."""
MAX_PATH_POSES = 100_000
"""Most poses one path solves: waypoints plus the ``densify`` poses between them (each costs
a solve, 0.1–1 ms; more are refused rather than run for hours with their memory growing)."""


def _warm_up(robot: Any, frame: str | None) -> None:
    """Load what a path of ``robot`` runs (the solvers' and the batch's kernels, the robot's
    closed form) with an untimed path of two waypoints at the pose of the middle of the
    ranges (tens of milliseconds once loaded), once per robot and process."""
    mid = robot.mid_q()
    pose = robot.fk_pinocchio(mid, frame)
    robot._cache["path_warm"] = True
    solve_path(robot, [pose, pose], q0=mid, frame=frame)


def _warm_goals(robot: Any, wps: _Waypoints) -> None:
    """Load what the waypoints' goals beyond a plain pose run, without solving: for each
    distinct set of goal types, the compiled kernels of its solves (``"best"`` and
    ``"nearest"``, :func:`swarm_ik.api.warm_up`: nothing once loaded, no Python goal called),
    and for each scene the exact collision checker (coal's, made at its first check: 5 ms),
    checked once at mid-range.  (The scene's sphere model is made with the problems.)"""
    if wps.plain:
        return
    from swarm_ik import api
    from swarm_ik.goals import AvoidCollisions

    mid = robot.mid_q()
    kinds: set[Any] = set()
    scenes: dict[Any, Any] = {}
    for i in range(wps.n if wps.goal_lists is not None else 1):
        problem = wps.problem(i)
        kind = (tuple(type(g) for g in problem.goals), problem.has_secondary)
        if kind not in kinds:
            kinds.add(kind)
            for prefer in ("best", "nearest"):
                settings = dict(max_evals=TRACK_EVALS, prefer=prefer)
                api.warm_up(api.route_for(problem, api.DEFAULT_SOLVER, settings))
        for g in problem.goals:
            if isinstance(g, AvoidCollisions):
                scenes.setdefault((id(g.scene), bool(g.self_collision)), g)
    if scenes:
        rc = robot.collision_model()
        for g in scenes.values():
            rc.collides(mid, g.scene, g.margin, bool(g.self_collision))


def _check_path_size(n: int, densify: int) -> None:
    """Refuse a path of more than :data:`MAX_PATH_POSES` poses (``n`` waypoints, ``densify``
    poses between consecutive ones)."""
    total = n + max(n - 1, 0) * densify
    if total > MAX_PATH_POSES:
        raise InvalidArgumentError(
            f"a path of {n} waypoints with densify={densify} has {total} poses, more than "
            f"{MAX_PATH_POSES} (swarm_ik.path.MAX_PATH_POSES); split it or densify less"
        )


MAX_HELD = 256
"""Most configurations of the waypoint before that stand in for a waypoint nothing meets (a
UR5 closed-form layer has up to 8 × 32 = 256; more are picked by the running programme)."""
DENSIFY_ROUNDS = 32
"""Most rounds of the densify check (each removes the failing steps and searches again)."""
_STEP_SLACK = 1e-9
"""Relative slack on the bound (round-off)."""


class InvalidWaypointError(InvalidArgumentError, InvalidTargetError):
    """A waypoint that is not a finite rigid transform (caught as either parent class)."""


@dataclass(frozen=True, eq=False)
class PathResult(FrozenArrays):
    """What :func:`solve_path` returns (its arrays read-only, as checked; ``.copy()`` gives a
    writable one).

    Attributes:
        q: The joint path, shape ``(N, nq)`` (rad / m; continuous joints in ``[-π, π)``).
        success: Every waypoint met to tolerance (judged with Pinocchio's FK by
            :meth:`swarm_ik.IKProblem.verify`, coal for collisions) and within the limits.
        jump_free: Every consecutive step (and the step from ``q0``, when given) within
            ``max_joint_step`` on every joint, and, with ``densify``, every step's tracked
            chain through the interpolated poses too (each pose met, each joint's travel
            within the bound).
        reconfigurations: ``(index, size)`` per step beyond the bound: ``index`` is the
            waypoint the step arrives at (0: the step from ``q0``), ``size`` the change of
            the joint furthest beyond its bound in that step (the largest ``|Δq_j| /
            max_joint_step_j``; with one bound for every joint, the largest change)
            [rad / m] (a step within the bound that fails the densify check: the largest
            joint travel along its tracked chain).
        max_step: Largest joint change between consecutive configurations [rad / m].
        max_step_ratio: Largest ``|Δq_j| / max_joint_step_j`` (≤ 1 when jump-free).
        position_errors: Per waypoint, the largest position error of its goals [m], ``(N,)``.
        rotation_errors: Per waypoint, the largest angular error [rad], ``(N,)``.
        reached: Per waypoint, whether it is met, ``(N,)``.
        reason: One line: what was found and why it is (not) a success.
        status: Why the call ended, in :attr:`swarm_ik.Result.reason`'s words (``reason``
            says more): ``"converged"`` (every waypoint met, jump-free), ``"jumps"`` (every
            waypoint met, with steps beyond ``max_joint_step``: :attr:`reconfigurations`),
            ``"unreachable"`` (a waypoint proven to have no solution), ``"conflicting_goals"``
            (a waypoint's goals proven contradictory, or pulling against each other where the
            path holds it), ``"time_limit"`` / ``"budget"`` (the limit ended the call before
            every waypoint was met), ``"local_minima"`` (a waypoint not met, no budget spent
            and nothing proven).
        time_s: Wall-clock time of the call, from entry to return (what it loaded first
            included) [s].
        exhaustive: Every waypoint's candidate set was certified complete (closed form), so
            the jump verdict is exact: with jumps, no jump-free path through the waypoints
            exists (False when the jumps are only those the densify check found: that check
            proves nothing).  With other goals (a scene) a waypoint's set is its pose's
            complete closed-form set filtered by them, so it still holds every solution: one
            they empty is a proof that the waypoint has none (the reason says so).
        n_candidates: Candidates considered per waypoint, ``(N,)``.
        travel: Joint travel of the path, ``Σ_steps Σ_j |Δq_j|`` [rad / m].
        q_dense: With ``densify=k``: the checked path through the interpolated poses,
            shape ``((N − 1)(k + 1) + 1, nq)``; else None.  The rows of a step listed in
            ``reconfigurations`` are its tracked chain as far as it went and need not meet
            their poses (a UR5 step whose chain travelled 12.7 rad: rows 5–8 mm off).
        n_evals: Evaluations the call's solves spent (``max_evals`` bounds them).
    """

    q: FloatArray
    success: bool
    jump_free: bool
    reconfigurations: tuple[tuple[int, float], ...]
    max_step: float
    max_step_ratio: float
    position_errors: FloatArray
    rotation_errors: FloatArray
    reached: NDArray[np.bool_]
    reason: str
    time_s: float
    exhaustive: bool = False
    n_candidates: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    travel: float = 0.0
    q_dense: FloatArray | None = None
    n_evals: int = 0
    status: str = ""

    def __repr__(self) -> str:
        return (
            f"PathResult(success={self.success}, jump_free={self.jump_free}, "
            f"waypoints={self.q.shape[0]}, reconfigurations={list(self.reconfigurations)}, "
            f"max_step={self.max_step:.4g}, time_s={self.time_s:.4f}, status={self.status!r}, "
            f"reason={self.reason!r})"
        )


# ------------------------------------------------------------------------------- API
@keywords_checked
def solve_path(
    robot: Any,
    poses: Any = None,
    *,
    max_joint_step: Any = DEFAULT_MAX_JOINT_STEP,
    q0: Any = None,
    goals: Any = None,
    scene: Any = None,
    frame: str | None = None,
    time_limit: float | None = None,
    max_evals: int | None = None,
    seed: int | np.random.Generator = 0,
    densify: int = 0,
    tol_pos: float = 1e-5,
    tol_rot: float = 1e-5,
) -> PathResult:
    """A joint path through Cartesian waypoints with no jump between consecutive ones.

    Args:
        robot: The robot (:func:`swarm_ik.load_robot`).
        poses: Waypoints of ``frame``: shape ``(N, 4, 4)`` [m], or ``(N, 7)`` rows
            ``[x y z qx qy qz qw]`` (metres, quaternion x y z w, as
            :func:`swarm_ik.make_pose`); ``N >= 2``.  None when ``goals`` lists each
            waypoint's goals.
        max_joint_step: Largest change of each joint between consecutive waypoints: a number
            or one per joint, shape ``(nq,)`` [rad, or m for prismatic joints], ``> 0``.
        q0: Optional current configuration ``(nq,)``: the path must start within the bound
            of it (the step ``q0 → q[0]`` counts as a step).  Refused outside the limits.
        goals: With ``poses``: a flat list of goal terms (:mod:`swarm_ik.goals`, e.g. a
            secondary ``Posture``) added at every waypoint.  With ``poses=None``: a list of
            ``N`` goal lists, one per waypoint (paths of other goals, e.g. ``Position`` +
            ``Axis``).
        scene: Obstacles (a :class:`swarm_ik.scene.Scene`, shapes, or a scene JSON file):
            shortcut for adding ``AvoidCollisions(scene)`` at every waypoint.
        frame: The goal frame of ``poses`` (default ``robot.ee_frame``).
        time_limit: Most wall-clock seconds for the whole call [s].  After :data:`SEARCH_SHARE` of
            it (less what the search through the candidates and the final check will take:
            :data:`FINISH_PER_WAYPOINT` and :data:`SEARCH_PER_LAYER` per waypoint, up to half the
            limit, and :data:`SEARCH_PER_PAIR` per pair of candidates built) no more candidates are
            built, unless the waypoints left, each at the mean building time of those built, fit
            before the limit: the remaining waypoints are only tracked (one solve each, 0.1–1 ms)
            and the remaining interpolated poses are not solved (the path through them is filled in
            joint space and reported unchecked, not as jumps).  Waypoints not tracked by the limit
            are not solved: they hold the configuration before them and are reported not reached.
            The reason says which of these happened.  Waypoint 0 always gets one solve, and the
            poses are validated and the answers checked in any case (about 45 µs per waypoint;
            among obstacles coal's check adds 0.25–0.5 ms per waypoint), so a limit shorter than
            these is overrun (2,000 Panda waypoints among two obstacles: 0.1 s took 0.2 s).
            What a call loads the first time is loaded before
            the clock: the first timed path of a robot in a process loads its kernels (0.7–1 s from
            numba's cache, with an untimed path of two waypoints); a path with goals beyond the pose
            loads their kernels (tens of milliseconds, no solve run) and, with a scene, its sphere
            model (made with the waypoints' problems: 0.2–0.6 s for a robot's first scene, its own
            self-collision pairs sampled; milliseconds for a later one) and coal's checker of it
            (about 5 ms). All the call spent before the clock (that loading, and validating the
            waypoints) is charged to the limit up to half of it, as a first :func:`swarm_ik.solve`'s
            loading: such a call overruns by the loading and still gets half its limit; ``time_s``
            counts it.  Results are deterministic for a seed only when the limit is not reached.
        max_evals: Most evaluations (FK and Jacobian, as :func:`swarm_ik.solve` counts them)
            for the whole call, over every solve it runs (the branch searches, the tracking
            solves, the densify checks): it ends building as ``time_limit`` does, after
            :data:`SEARCH_SHARE` of them unless the waypoints left, each at the mean of those
            built, fit in :data:`TRACK_SHARE` less than all of them; the remaining waypoints
            are tracked while evaluations are left, the others not solved.  A budget, not a
            clock: the same seed gives the same path.  ``PathResult.n_evals`` is what was spent.
        seed: Seed (or Generator) of every random choice (the solvers' seeds are drawn from
            it): the same seed gives the same path.
        densify: Poses interpolated between consecutive waypoints (position lerp, rotation
            slerp) that each chosen step is checked through by tracking, ``>= 0``; needs
            ``poses``.
        tol_pos: Position tolerance of every waypoint [m].
        tol_rot: Angular tolerance of every waypoint [rad].

    Returns:
        The :class:`PathResult`.

    Raises:
        InvalidArgumentError: a bad shape, ``N < 2``, a non-positive or wrongly sized
            ``max_joint_step``, ``q0`` of the wrong length, not finite or outside the limits,
            a bad ``densify``, ``time_limit``, ``max_evals``, tolerance, seed or goal list.
        InvalidWaypointError: a pose that is not a finite rigid transform (a subclass of
            both :class:`InvalidArgumentError` and :class:`InvalidTargetError`).
        UnknownNameError: ``frame`` is not a goal frame of the robot.
    """
    from swarm_ik.robot import RobotModel

    t_start = time.perf_counter()
    if not isinstance(robot, RobotModel):
        raise InvalidArgumentError(
            f"robot must be a RobotModel (see swarm_ik.load_robot), got {type(robot).__name__}"
        )
    step = _check_step(robot, max_joint_step)
    start = _check_q0(robot, q0)
    densify = count(densify, "densify", 0)
    tol_pos = positive_float(tol_pos, "tol_pos")
    tol_rot = positive_float(tol_rot, "tol_rot")
    if time_limit is not None:
        time_limit = positive_float(time_limit, "time_limit (or None)")
    check_budget(max_evals, None)
    rng = make_rng(seed)
    wps = _Waypoints.build(robot, poses, goals, scene, frame)
    if densify and wps.poses is None:
        raise InvalidArgumentError("densify needs poses (goal lists are not interpolated)")
    _check_path_size(wps.n, int(densify))
    deadline = limit = None
    t_clock = t_start  # (when the time limit's clock starts; time_s counts from t_start)
    if time_limit is not None:
        # what the call loads the first time (a robot's kernels, 0.7-1 s from numba's cache;
        # a scene's sphere model, made with the waypoints' problems above, 0.2-0.6 s for the
        # robot's first; the goals' kernels and the scene's collision checker) is loaded
        # before the clock, and what the call spent so far is charged to the limit up to half
        # of it, as a first solve's loading (the rest of the call keeps at least half)
        if not robot._cache.get("path_warm"):
            _warm_up(robot, frame)
        _warm_goals(robot, wps)
        spent = time.perf_counter() - t_start
        time_limit = max(float(time_limit) - spent, 0.5 * float(time_limit))
        t_clock = time.perf_counter()
        # (the search and the check at the end are inside the limit)
        per_waypoint = FINISH_PER_WAYPOINT + SEARCH_PER_LAYER
        if wps.problem(0).collision_goal is not None:  # (coal's check of each waypoint)
            per_waypoint += FINISH_PER_WAYPOINT_SCENE
        reserve = min(per_waypoint * wps.n, 0.5 * float(time_limit))
        limit = t_clock + float(time_limit) - reserve
        deadline = t_clock + SEARCH_SHARE * (limit - t_clock)
    ctx = _Context(robot, wps, step, float(tol_pos), float(tol_rot), rng, deadline, limit)
    ctx.max_evals = None if max_evals is None else int(max_evals)
    if limit is not None:
        ctx.keep = TRACK_SHARE * (limit - t_clock)
    graph = _build(ctx, start)
    rejected: Rejected = {}
    choice = _search(graph, start, ctx, rejected)
    proof = graph.exhaustive and choice.reconfigs > 0  # before densify: waypoints alone
    dense, densify_ok = None, True
    if densify:
        choice, dense, densify_ok = _densify(ctx, graph, start, choice, int(densify), rejected)
    return _finish(
        ctx, graph, start, choice, proof, dense, densify_ok, rejected, t_start, int(densify)
    )


# -------------------------------------------------------------------- input checks
def _check_step(robot: Any, value: Any) -> FloatArray:
    """``max_joint_step`` as ``(nq,)`` positive finite floats."""
    if isinstance(value, (str, bytes, bool, np.bool_)) or value is None:
        raise InvalidArgumentError(
            f"max_joint_step must be a positive number or {robot.nq} of them, got {value!r}"
        )
    arr = floats_or(
        value,
        lambda: f"max_joint_step must be a positive number or {robot.nq} of them, got {value!r}",
    )
    if arr.ndim == 0:
        arr = np.full(robot.nq, float(arr))
    if arr.shape != (robot.nq,):
        raise InvalidArgumentError(
            f"max_joint_step must be one number or {robot.nq} (one per joint: "
            f"{', '.join(robot.joint_names)}); got shape {arr.shape}"
        )
    if not np.all(np.isfinite(arr) & (arr > 0)):
        raise InvalidArgumentError(
            f"max_joint_step must be finite and > 0 on every joint, got {arr.tolist()}"
        )
    return arr


def _check_q0(robot: Any, q0: Any) -> FloatArray | None:
    """``q0`` checked: ``(nq,)``, finite, continuous joints wrapped, within the limits."""
    if q0 is None:
        return None
    q = robot.wrap(robot.check_q(q0, "q0"))  # wrong length / not finite: refused there
    outside = np.flatnonzero((q < robot.lower - 1e-9) | (q > robot.upper + 1e-9))
    if outside.size:
        j = int(outside[0])
        raise InvalidArgumentError(
            f"q0 lies outside the joint limits at joint {robot.joint_names[j]!r}: "
            f"{q[j]:g} not in [{robot.lower[j]:g}, {robot.upper[j]:g}]"
        )
    return np.clip(q, robot.lower, robot.upper)


def _goal_list(value: Any, what: str) -> list[Any]:
    from swarm_ik.goals import Goal

    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence):
        raise InvalidArgumentError(f"{what} must be a list of goal terms, got {value!r}")
    out = list(value)
    for g in out:
        if not isinstance(g, Goal):
            raise InvalidArgumentError(
                f"{what} must hold swarm_ik.goals terms, got {type(g).__name__}"
            )
    return out


def interpolate_pose(a: FloatArray, b: FloatArray, s: float) -> FloatArray:
    """The pose a fraction ``s`` ∈ [0, 1] of the way from ``a`` to ``b`` (both ``(4, 4)``):
    position interpolated linearly, rotation along the geodesic (slerp)."""
    from scipy.spatial.transform import Rotation

    out = np.eye(4)
    out[:3, 3] = (1.0 - s) * a[:3, 3] + s * b[:3, 3]
    rel = Rotation.from_matrix(a[:3, :3].T @ b[:3, :3]).as_rotvec()
    out[:3, :3] = a[:3, :3] @ Rotation.from_rotvec(s * rel).as_matrix()
    return out


# -------------------------------------------------------------------- waypoints
@dataclass
class _Waypoints:
    """The waypoints: poses of a frame and/or goal lists, and their problems (made lazily)."""

    robot: Any
    n: int
    poses: FloatArray | None
    frame: str
    extra: list[Any]
    goal_lists: list[list[Any]] | None
    plain: bool
    _problems: dict[int, Any]

    @classmethod
    def build(cls, robot: Any, poses: Any, goals: Any, scene: Any, frame: str | None) -> _Waypoints:
        from swarm_ik.goals import AvoidCollisions

        extra: list[Any] = []
        goal_lists = None
        if poses is None:
            if goals is None:
                raise InvalidArgumentError("give poses (N, 4, 4) or (N, 7), or goals= per waypoint")
            if frame is not None:
                raise InvalidArgumentError(
                    "frame applies to poses; with goals= name each goal's frame"
                )
            if isinstance(goals, (str, bytes)) or not isinstance(goals, Sequence):
                raise InvalidArgumentError(
                    f"goals must be a list of N goal lists (one per waypoint), got {goals!r}"
                )
            goal_lists = [_goal_list(g, f"goals[{i}]") for i, g in enumerate(goals)]
            for i, gl in enumerate(goal_lists):
                if not gl:
                    raise InvalidArgumentError(
                        f"goals[{i}] is empty: each waypoint needs at least one goal term"
                    )
            n = len(goal_lists)
            frame_name = robot.ee_frame
            arr = None
        else:
            frame_name = robot.ee_frame if frame is None else frame
            robot.frame_index(frame_name)  # UnknownNameError naming the goal frames
            arr = _parse_poses(poses)
            n = arr.shape[0]
            if goals is not None:
                extra = _goal_list(goals, "goals (with poses: goal terms added at every waypoint)")
        if n < 2:
            raise InvalidArgumentError(f"a path needs at least 2 waypoints, got {n}")
        if scene is not None:
            extra.append(AvoidCollisions(scene))
        plain = arr is not None and not extra and frame_name == robot.ee_frame
        wps = cls(robot, n, arr, frame_name, extra, goal_lists, plain, {})
        for i in range(n):  # every goal list validated against the robot now
            try:
                wps.problem(i)
            except InvalidArgumentError as exc:
                raise type(exc)(f"waypoint {i}: {exc}") from None
        return wps

    def problem(self, i: int) -> Any:
        """The IK problem of waypoint ``i`` (cached)."""
        p = self._problems.get(i)
        if p is None:
            p = self._problems[i] = self.problem_at(
                self.poses[i] if self.poses is not None else None, i
            )
        return p

    def problem_at(self, pose: FloatArray | None, i: int) -> Any:
        """The problem of a pose of the path's frame with the extra goals (``pose`` None: the
        goal list of waypoint ``i``)."""
        import swarm_ik
        from swarm_ik.goals import Pose

        if pose is None:
            assert self.goal_lists is not None
            return swarm_ik.IKProblem(self.robot, goals=[*self.goal_lists[i], *self.extra])
        if self.plain:
            return swarm_ik.IKProblem(self.robot, pose)
        return swarm_ik.IKProblem(self.robot, goals=[Pose(self.frame, pose), *self.extra])

    def pose_only(self, i: int) -> Any:
        """The plain pose problem of waypoint ``i`` when the closed form could apply (poses of
        the end effector), else None."""
        import swarm_ik

        if self.poses is None or self.frame != self.robot.ee_frame:
            return None
        if self.plain:
            return self.problem(i)
        return swarm_ik.IKProblem(self.robot, self.poses[i])

    def target(self, i: int) -> tuple[FloatArray | None, Any]:
        """What the tracker solves for waypoint ``i``: ``(the end effector's pose or None,
        the problem, or None when the pose alone is the problem)``."""
        if self.poses is None:
            return None, self.problem(i)
        if self.plain:
            return self.poses[i], None
        return self._ee(self.poses[i]), self.problem(i)

    def target_at(self, pose: FloatArray, i: int) -> tuple[FloatArray | None, Any]:
        """:meth:`target` of another pose of the path's frame (with waypoint ``i``'s goals)."""
        if self.plain:
            return pose, None
        return self._ee(pose), self.problem_at(pose, i)

    def _ee(self, pose: FloatArray) -> FloatArray | None:
        return pose if self.frame == self.robot.ee_frame else None


def _parse_poses(poses: Any) -> FloatArray:
    """Waypoint poses as ``(N, 4, 4)``."""
    from swarm_ik.pose import as_pose

    if isinstance(poses, (str, bytes)):
        raise InvalidArgumentError(f"poses must be an array (N, 4, 4) or (N, 7), got {poses!r}")
    arr = floats_or(poses, lambda: "poses must be an array of numbers, shape (N, 4, 4) or (N, 7)")
    if not (arr.ndim == 3 and arr.shape[1:] == (4, 4)) and not (
        arr.ndim == 2 and arr.shape[1] == 7
    ):
        raise InvalidArgumentError(
            f"poses must have shape (N, 4, 4) or (N, 7) [x y z qx qy qz qw]; got {arr.shape}"
        )
    if arr.shape[0] < 2:
        raise InvalidArgumentError(f"a path needs at least 2 waypoints, got {arr.shape[0]}")
    _check_path_size(arr.shape[0], 0)
    out = np.empty((arr.shape[0], 4, 4))
    for i, row in enumerate(arr):
        try:
            out[i] = as_pose(row)
        except InvalidTargetError as exc:
            raise InvalidWaypointError(f"poses[{i}]: {exc}") from None
    return out


# -------------------------------------------------------------------- solving
def _all_solutions(problem: Any, n: int, seed: int, ctx: _Context) -> tuple[FloatArray, bool, bool]:
    """Every distinct solution :func:`swarm_ik.solve_many` finds: ``(q (k, nq), closed
    form)``, its search ended at ``deadline`` (``time.perf_counter()`` seconds; None: no
    deadline) and at its own count of starts without a limit (``64 n``) in any case, so that
    a search the deadline does not cut finds what it finds without one (goals written in
    Python, milliseconds a call, took minutes past a path's time limit here), and within
    the evaluations left of the call's (:meth:`_Context.spend`) less :attr:`_Context.keep_evals`.
    The third value: the search ran to its own end (no budget or time limit cut it)."""
    import swarm_ik

    deadline = ctx.deadline
    limit = None if deadline is None else max(deadline - time.perf_counter(), 1e-3)
    left = ctx.evals_left()
    if left is not None:
        left -= min(ctx.keep_evals, left // 2)
    if left == 0:
        return np.empty((0, problem.nq)), False, False
    results = swarm_ik.solve_many(
        problem, n=n, seed=seed, tol_pos=ctx.tol_pos, tol_rot=ctx.tol_rot, time_limit=limit,
        max_evals=left, max_starts=64 * n,
    )  # fmt: skip
    ctx.spend(results.n_evals)
    qs = np.array([r.q for r in results if r.success], dtype=float).reshape(-1, problem.nq)
    # (closed form: eaik's set, with the numerical search's added where it is incomplete)
    closed = any(r.solver == "analytic" for r in results)
    return qs, closed, results.reason not in ("budget", "time_limit")


class _Context:
    """What every step of the search shares: robot, waypoints, bound, tolerances, solvers."""

    def __init__(
        self, robot: Any, wps: _Waypoints, step: FloatArray, tol_pos: float, tol_rot: float,
        rng: np.random.Generator, deadline: float | None, limit: float | None,
    ) -> None:  # fmt: skip
        import swarm_ik

        self.robot = robot
        self.wps = wps
        self.step = step
        self.tol_pos = tol_pos
        self.tol_rot = tol_rot
        self.rng = rng
        self.deadline = deadline  # no candidates are built after it (only tracking)
        self.limit = limit  # no waypoint is solved after it
        self.true_wrap = np.ascontiguousarray(robot.continuous_mask)
        self.wrap = self.true_wrap  # the search's metric (set below for a 7-joint arm)
        self.angular = np.array([k != "prismatic" for k in robot.joint_kinds], dtype=bool)
        self.lower, self.upper = robot.lower, robot.upper
        self.ik = (
            swarm_ik.IKSolver(robot, tol_pos=tol_pos, tol_rot=tol_rot, max_evals=TRACK_EVALS)
            if wps.poses is not None and wps.frame == robot.ee_frame
            else None
        )
        # extra goals all primary (collisions): the pose solved first, then checked
        self.pose_first = all(g.is_primary for g in wps.extra)
        self.redundant_pose = wps.poses is not None and robot.nq > 6
        # one-dimensional self-motion (7 joints, a pose): covered by samples, all tracked
        self.cover = wps.poses is not None and robot.nq == 7
        self.windings = _winding_joints(robot)
        if self.cover:  # samples modulo 2π on the wide joints; the path unwound at the end
            self.wrap = np.ascontiguousarray(self.true_wrap | self.windings)
        self.full_branches = _structural_branches(robot)
        self.timed_out = False
        self.cut: int | None = None  # the first waypoint left unsolved at the limit
        self.search_s = 0.0  # what searching the candidates built so far will take [s]
        self.layer = 0  # the waypoint whose candidates are being built
        self.keep = 0.0  # seconds before the limit that building always leaves to tracking
        self.stopped_at: int | None = None  # the layer being built when building stopped
        self.t_build: float | None = None  # when the first layer's building began
        self.max_evals: int | None = None  # the call's evaluation budget (None: none)
        self.used = 0  # evaluations spent by the solves so far
        self.spent = False  # the budget of evaluations (not the clock) ended the building
        self.cut_by = "time_limit"  # what the last past_limit() found spent
        self.cut_reason = "time_limit"  # what left the waypoints from ctx.cut on unsolved
        self.budget_cut = False  # the budget cut a solve short (a closed form's probe: no proof)
        self.keep_evals = 0  # evaluations a branch search leaves for the solve after it
        self.cut_layers: set[int] = set()  # waypoints whose closed-form search was cut

    def evals_left(self) -> int | None:
        """Evaluations left of ``max_evals`` (None: no budget)."""
        return None if self.max_evals is None else max(self.max_evals - self.used, 0)

    def spend(self, n: int) -> None:
        """``n`` evaluations spent by a solve."""
        self.used += int(n)

    def seed(self) -> int:
        return int(self.rng.integers(2**31))

    def built(self, k_before: int, k: int) -> None:
        """A layer of ``k`` candidates after one of ``k_before``: the search's time for their
        pairs (:data:`SEARCH_PER_PAIR`) is kept out of the time limit (not out of the
        candidates' share: the tracking after it is short of the limit) from now on."""
        self.search_s += SEARCH_PER_PAIR * k_before * k

    def relaxed(self, k_before: int, k: int) -> None:
        """A layer relaxed by the build (:attr:`_Graph.relaxed`): the search reuses it, so
        its pairs' time is no longer kept out of the limit."""
        self.search_s = max(self.search_s - SEARCH_PER_PAIR * k_before * k, 0.0)

    def begin(self, i: int) -> None:
        """Building the candidates of waypoint ``i`` begins (layers are built in order)."""
        if self.t_build is None:
            self.t_build = time.perf_counter()
        self.layer = i

    def out_of_time(self) -> bool:
        """Whether the candidates' share of the time limit is spent (tracking only): past
        :data:`SEARCH_SHARE` of it, unless the waypoints left, each built in the mean time of
        those built so far (a tracking solve costs less than building a layer), still fit
        before the limit less :attr:`keep` (a path that builds every layer in 0.55 of its
        limit used to stop at half of it and track the rest one solve each, jumping where the
        layers would not have)."""
        if not self.timed_out and self.max_evals is not None:
            i, cap = self.layer, self.max_evals
            if self.used >= SEARCH_SHARE * cap and not (
                i > 0 and self.used + (self.wps.n - i) * self.used / i < (1 - TRACK_SHARE) * cap
            ):  # (the evaluations' share spent, as the clock's below)
                self.timed_out = self.spent = True
                self.stopped_at = i
        if self.timed_out or self.deadline is None:
            return self.timed_out
        now = time.perf_counter()
        if now >= self.deadline:
            i, t0 = self.layer, self.t_build
            fits = (
                i > 0
                and t0 is not None
                and self.limit is not None
                and now + (self.wps.n - i) * (now - t0) / i < self.limit - self.search_s - self.keep
            )
            self.timed_out = not fits
            if self.timed_out:
                self.stopped_at = i
        return self.timed_out

    def past_limit(self) -> bool:
        """Whether the time limit or the evaluations are spent (no waypoint is solved any
        more)."""
        if self.max_evals is not None and self.used >= self.max_evals:
            self.spent = self.spent or not self.timed_out
            self.cut_by = "max_evals"
            return True
        if self.limit is not None and time.perf_counter() + self.search_s >= self.limit:
            self.cut_by = "time_limit"
            return True
        return False

    def track(
        self, target: tuple[FloatArray | None, Any], q_start: FloatArray
    ) -> tuple[FloatArray, bool]:
        """Solve ``target`` (:meth:`_Waypoints.target`) from ``q_start``, preferring the
        solution nearest to it: ``(q, success)``, success judged with Pinocchio (the solver's
        Result, or :meth:`IKProblem.verify` when a pose solution is checked against the
        waypoint's other goals)."""
        import swarm_ik

        pose, problem = target
        q_start = np.ascontiguousarray(np.clip(q_start, self.lower, self.upper))
        left = self.evals_left()
        if left == 0:  # (the budget spent: not solved)
            self.budget_cut = True
            return q_start, False
        budget = TRACK_EVALS if left is None else min(TRACK_EVALS, left)
        if pose is not None and self.ik is not None and (problem is None or self.pose_first):
            pose = np.ascontiguousarray(pose, dtype=float)
            if budget == TRACK_EVALS:  # (the bound solver's budget)
                res = self.ik.solve(pose, q0=q_start, seed=self.seed())
            else:  # (what is left of the call's budget)
                res = swarm_ik.solve(
                    swarm_ik.IKProblem(self.robot, pose), q0=q_start, seed=self.seed(),
                    max_evals=budget, tol_pos=self.tol_pos, tol_rot=self.tol_rot,
                )  # fmt: skip
            self.spend(res.n_evals)
            self.budget_cut = self.budget_cut or (budget < TRACK_EVALS and not res.success)
            q = np.array(res.q, dtype=float)
            if problem is None:
                return q, bool(res.success)
            if res.success and _meets(problem, q, self):
                return q, True
            left = self.evals_left()
            if left == 0:
                return q, False
            budget = TRACK_EVALS if left is None else min(TRACK_EVALS, left)
        res = swarm_ik.solve(
            problem, q0=q_start, seed=self.seed(), max_evals=budget,
            time_limit=self.solve_limit(), tol_pos=self.tol_pos, tol_rot=self.tol_rot,
            prefer="nearest",
        )  # fmt: skip
        self.spend(res.n_evals)
        self.budget_cut = self.budget_cut or (budget < TRACK_EVALS and not res.success)
        return np.array(res.q, dtype=float), bool(res.success)

    def solve_limit(self) -> float | None:
        """The time limit of one tracking solve under the call's: what is left of it rounded
        down to a power of two (few distinct values, so that the solves share their route),
        at least 1 ms.  A waypoint whose goals are slow Python (milliseconds a call) and
        cannot be met took its whole evaluation budget: a 0.3 s path limit ended at 14 s."""
        if self.limit is None:
            return None
        left = max(self.limit - time.perf_counter(), 1e-3)
        return float(2.0 ** math.floor(math.log2(left)))

    def steps(self, a: FloatArray, b: FloatArray, true: bool = False) -> FloatArray:
        """``|b − a|`` per joint, broadcasting: continuous joints wrapped, and, in the search's
        metric (``true`` False) on a 7-joint arm, the joints with a range of 2π or more too
        (its samples are kept modulo 2π there, :func:`_unwind`)."""
        wrap = self.true_wrap if true else self.wrap
        d = np.asarray(b, dtype=float) - np.asarray(a, dtype=float)
        if wrap.any():
            _wrap_angles(d, wrap)
        return np.abs(d)

    def self_motion(self, i: int, q: FloatArray) -> list[FloatArray]:
        """Starts pushed from ``q`` along the self-motion of waypoint ``i`` (null space of the
        frame's Jacobian, half the bound each way; random pushes for goal lists); none once
        the time limit is reached (each later waypoint: one solve)."""
        if self.cover or self.timed_out:
            return []  # (cover: covered by walks along the self-motion, _fill)
        if self.redundant_pose:
            jac = self.robot.jacobian_pinocchio(q, self.wps.frame)
            _, _, vt = np.linalg.svd(jac)
            out = []
            for v in vt[6 : 6 + 2]:
                scale = 0.5 / max(float(np.max(np.abs(v) / self.step)), 1e-12)
                out += [q + scale * v, q - scale * v]
            return out
        if self.wps.goal_lists is not None:
            push = self.rng.uniform(-0.5, 0.5, size=(2, q.shape[0])) * self.step
            return [q + p for p in push]
        return []


def _winding_joints(robot: Any) -> NDArray[np.bool_]:
    """Revolute (not continuous) joints whose range holds more than one copy of an angle."""
    kinds = np.array([k == "revolute" for k in robot.joint_kinds])
    return kinds & (robot.upper - robot.lower >= 2 * np.pi - 1e-9)


def _with_windings(qs: FloatArray, lower: FloatArray, upper: FloatArray, joints: Any) -> FloatArray:
    """Every in-limit 2π copy of each row of ``qs`` (``(m, nq)``, within the limits) on the
    ``joints`` given (each row's copies together, in increasing order)."""
    out = qs
    for j in np.flatnonzero(joints):
        turns = int(math.ceil((upper[j] - lower[j]) / (2 * np.pi)))
        vals = out[:, j, None] + 2 * np.pi * np.arange(-turns, turns + 1)
        keep = (vals >= lower[j] - 1e-9) & (vals <= upper[j] + 1e-9)
        rows, cols = np.nonzero(keep)
        out = out[rows]
        out[:, j] = np.clip(vals[rows, cols], lower[j], upper[j])
    return out


def _structural_branches(robot: Any) -> int | None:
    """:data:`FULL_BRANCHES` for a 6R chain with three consecutive parallel axes or a
    spherical wrist (first or last three axes through one point), else None (no bound
    known: closed-form sets are then not certified complete)."""
    if robot.nq != 6 or any(k != "revolute" for k in robot.joint_kinds) or robot.mimic:
        return None
    q = robot.mid_q()
    jac = robot.jacobian_pinocchio(q)
    p_ee = robot.fk_pinocchio(q)[:3, 3]
    axes, points = [], []
    for j in range(6):
        w, v = jac[3:, j], jac[:3, j]
        nw = float(w @ w)
        if nw < 1e-12:
            return None
        axes.append(w / math.sqrt(nw))
        points.append(p_ee - np.cross(v, w) / nw)  # v = w × (p_ee − p) on the axis line
    for j in range(4):
        if all(np.linalg.norm(np.cross(axes[j], axes[k])) < 1e-9 for k in (j + 1, j + 2)):
            return FULL_BRANCHES
    from swarm_ik.branches import through_one_point

    for k in (0, 3):
        if through_one_point(points[k : k + 3], axes[k : k + 3], tol=1e-7):
            return FULL_BRANCHES
    return None


# -------------------------------------------------------------------- the graph
@numba.njit(cache=True)
def _relax(
    qa: FloatArray, ra: NDArray[np.int64], ta: FloatArray, qb: FloatArray, step: FloatArray,
    wrap: NDArray[np.bool_], forbid: NDArray[np.bool_], rb: NDArray[np.int64], tb: FloatArray,
    parent: NDArray[np.int64],
) -> None:  # pragma: no cover - compiled  # fmt: skip
    """One layer of the dynamic programme: for each row ``b`` of ``qb`` the best predecessor
    ``a`` of ``qa`` by (jumps ``ra[a] + [step a→b beyond the bound]``, travel ``ta[a] +
    Σ_j |Δq_j| / step_j``), lexicographically; ``forbid[a, b]`` (when shaped ``(ka, kb)``)
    makes a step a jump."""
    ka = qa.shape[0]
    n = qa.shape[1]
    has_forbid = forbid.shape[0] == ka and forbid.shape[1] == qb.shape[0]
    for b in range(qb.shape[0]):
        best_r = 1 << 40
        best_t = math.inf
        best_a = -1
        for a in range(ka):
            r = ra[a]
            if has_forbid and forbid[a, b]:
                r += 1
            if r > best_r:
                continue
            jumped = r > ra[a]
            t = ta[a]
            worse = False
            for j in range(n):  # (stops as soon as the step cannot be the best)
                d = qb[b, j] - qa[a, j]
                if wrap[j]:
                    d = joints.wrapped(d)
                d = abs(d)
                if not jumped and d > step[j] * (1.0 + 1e-9):
                    jumped = True
                    r += 1
                    if r > best_r:
                        worse = True
                        break
                t += d / step[j]
                if r == best_r and t >= best_t:
                    worse = True
                    break
            if worse:
                continue
            if r < best_r or t < best_t:
                best_r, best_t, best_a = r, t, a
        rb[b] = best_r
        tb[b] = best_t
        parent[b] = best_a


def _relax_layer(
    qa: FloatArray,
    ra: Any,
    ta: Any,
    qb: FloatArray,
    step: FloatArray,
    wrap: Any,
    forbid: Any = None,
) -> tuple[NDArray[np.int64], FloatArray, NDArray[np.int64]]:
    kb = qb.shape[0]
    rb = np.empty(kb, dtype=np.int64)
    tb = np.empty(kb)
    parent = np.empty(kb, dtype=np.int64)
    fb = np.zeros((0, 0), dtype=np.bool_) if forbid is None else forbid
    _relax(
        np.ascontiguousarray(qa), np.ascontiguousarray(ra, dtype=np.int64),
        np.ascontiguousarray(ta, dtype=float), np.ascontiguousarray(qb), step, wrap, fb, rb, tb,
        parent,
    )  # fmt: skip
    return rb, tb, parent


@dataclass
class _Graph:
    """Candidates per waypoint: ``layers[i] (k_i, nq)``, which meet the waypoint
    (``valid[i]``), whether the set is certified complete (``certified[i]``: for a waypoint
    with other goals, the closed-form set of its pose before they filtered it), and, where
    the closed form gave the pose branches within the limits but the other goals rejected
    every one, the indices of the goals they failed in its problem (``blocked[i]``; -1: its
    bounds), else None."""

    layers: list[FloatArray]
    valid: list[NDArray[np.bool_]]
    certified: list[bool]
    closed: list[bool]
    unreachable: list[int]
    repaired: int = 0
    blocked: list[tuple[int, ...] | None] = field(default_factory=list)
    relaxed: dict[int, tuple[Any, FloatArray, Any, FloatArray, Any]] = field(default_factory=dict)
    """The dynamic programme's layers the build already relaxed (its tracking reads them):
    waypoint ``i`` → ``(the layer before (or the start), the layer, jumps, travel,
    parents)``, reused by :func:`_search` while the layers are those same arrays and no step
    into them was rejected (relaxing 256 × 256 candidates a layer twice overran a UR5 path's
    time limit by a fifth)."""

    @property
    def exhaustive(self) -> bool:
        return all(self.certified)


def _merge(base: FloatArray, new: Any, ctx: _Context, tol: float = DUPLICATE) -> FloatArray:
    """``base`` (distinct rows) and the rows of ``new`` that are no near-duplicate (closer
    than ``tol``: largest ``|Δq_j| / max_joint_step_j``) of a row kept before them."""
    nq = base.shape[1]
    rows = np.ascontiguousarray(np.asarray(new, dtype=float).reshape(-1, nq))
    if rows.shape[0] == 0:
        return base
    idx = np.empty(rows.shape[0], dtype=np.int64)
    c = joints.fresh_rows(
        rows, np.ascontiguousarray(base), ctx.wrap, ctx.step, float(tol), True, idx
    )
    return np.vstack([base, rows[idx[:c]]]) if c else base


def _pick(qs: FloatArray, r: Any, t: Any, k: int, ctx: _Context) -> FloatArray:
    """Up to ``k`` rows of ``qs`` by (``r``, ``t``), at least :data:`DIVERSE` apart while
    there is choice."""
    order = np.lexsort((t, r))
    if k >= qs.shape[0]:  # all of them: best first
        return qs[order]
    chosen: list[int] = []
    for i in order:
        if len(chosen) >= k:
            break
        if (
            chosen
            and float(np.min(np.max(ctx.steps(qs[chosen], qs[i]) / ctx.step, axis=1))) < DIVERSE
        ):
            continue
        chosen.append(int(i))
    for i in order:  # fill up with the rest
        if len(chosen) >= k:
            break
        if int(i) not in chosen:
            chosen.append(int(i))
    return qs[chosen]


def _closed_form(
    ctx: _Context, i: int
) -> tuple[FloatArray, bool, bool, tuple[int, ...] | None] | None:
    """Waypoint ``i``'s closed-form set with every in-limit 2π copy: ``(q, closed form used,
    certified complete, blocked)``; None when the waypoint has no end-effector pose.  With
    other goals (collisions, …) the pose's set is filtered by them; ``blocked``: where they
    rejected every branch, the goals failed (:func:`_goal_filter`), else None.  The
    certificate is the pose's set's, before the filter: a complete set filtered by a check
    of each branch leaves every solution of the waypoint's problem.

    eaik's least-squares solutions are probed (``solve_many`` polishes them as well, and adds
    its numerical search where that finds a singular solution; this probe also decides the
    certificate): each is polished (its own start only); a solution it leads to that is no
    known branch
    (modulo 2π) was missed — at a singular pose a whole continuum of solutions (e.g. a UR
    wrist at ``q5 = 0``) comes back as one least-squares point — and joins the candidates.

    Certified: the arm's branch count is bounded (:func:`_structural_branches`), eaik could
    be asked for its least-squares solutions, none of them led to a missed solution, and no
    candidate is near a singularity (smallest Jacobian singular value ≥
    :data:`SINGULAR_SIGMA`: no continuum of solutions, no pair about to merge)."""
    pose_problem = ctx.wps.pose_only(i)
    if pose_problem is None:
        return None
    qs, closed, whole = _all_solutions(pose_problem, CLOSED_FORM_N, ctx.seed(), ctx)
    if not closed:
        return qs, False, False, None
    assert ctx.wps.poses is not None
    near = _least_squares_solutions(ctx.robot, ctx.wps.poses[i])
    certified = whole and ctx.full_branches is not None and near is not None
    if near is not None and near.shape[0]:
        missed, cut = _missed_solutions(ctx, ctx.wps.poses[i], qs, near)
        if missed.shape[0] or cut:  # (a probe the budget cut proves nothing)
            certified = False
            qs = _merge(qs, missed, ctx)
    if not whole:  # (cut by the budget or the clock: its set proves nothing)
        ctx.cut_layers.add(i)
        ctx.budget_cut = ctx.budget_cut or ctx.max_evals is not None
    if certified:
        assert ctx.full_branches is not None
        certified = 0 < qs.shape[0] <= ctx.full_branches
    if certified:  # no candidate near a singularity (a continuum, or a pair merging)
        certified = all(sigma_min(ctx.robot, q) >= SINGULAR_SIGMA for q in qs)
    blocked = None
    if not ctx.wps.plain and qs.shape[0]:  # the other goals (collisions, …) filter the set
        keep, failed, cut = _goal_filter(ctx.wps.problem(i), qs, ctx)
        blocked = None if keep.any() or cut else failed
        certified = certified and not cut  # (rows left unchecked: no proof from them)
        qs = qs[keep]
    return _with_windings(qs, ctx.lower, ctx.upper, ctx.windings), True, certified, blocked


def _goal_filter(
    problem: Any, qs: FloatArray, ctx: _Context
) -> tuple[NDArray[np.bool_], tuple[int, ...], bool]:
    """Which rows of ``qs`` meet ``problem`` (:meth:`IKProblem.verify` and its bounds), the
    indices in ``problem.goals`` of the goals some row failed (-1: the bounds), sorted, and
    whether the time limit cut the checks short (the rows after it not kept, and no proof
    drawn from them: a check among thousands of obstacles may take 0.1 s a row)."""
    primary = [k for k in range(len(problem.goals)) if problem.primary[k]]
    keep = np.zeros(qs.shape[0], dtype=bool)
    failed: set[int] = set()
    for r in range(qs.shape[0]):
        if r and keep.any() and ctx.past_limit():
            return keep, tuple(sorted(failed)), True
        errs = problem.verify(qs[r], ctx.tol_pos, ctx.tol_rot)
        missed = {k for k, e in zip(primary, errs, strict=True) if not e.met}
        if not problem.within_bounds(qs[r]):
            missed.add(-1)
        keep[r] = not missed
        failed |= missed
    return keep, tuple(sorted(failed)), False


NEAR_LS_STARTS = 16
"""Starts scattered around each of eaik's least-squares points (:func:`_missed_solutions`)."""

NEAR_LS_SPREAD = 0.7
"""Half-width [rad] of the box the starts around a least-squares point are drawn in."""


def _missed_solutions(
    ctx: _Context, pose: FloatArray, known: FloatArray, near: FloatArray
) -> tuple[FloatArray, bool]:
    """Solutions of ``pose`` next to eaik's least-squares points ``near`` that are no branch
    of ``known`` (modulo 2π, 1e-4 rad): each point polished from itself alone (one
    :func:`swarm_ik.solve_batch` call), judged by its check, brought within the limits."""

    # each point and NEAR_LS_STARTS starts scattered around it: at a singular pose eaik's
    # point may lie centimetres from its branch's solutions (a UR wrist at q5 = 0 gave one
    # 5 cm off, which its polish alone did not bring back: a jump-free path was "proven"
    # impossible)
    rng = np.random.default_rng(ctx.seed())
    scatter = rng.uniform(
        -NEAR_LS_SPREAD, NEAR_LS_SPREAD, (near.shape[0], NEAR_LS_STARTS, near.shape[1])
    )
    starts = np.concatenate([near, (near[:, None, :] + scatter).reshape(-1, near.shape[1])])
    starts = np.clip(starts, ctx.lower, ctx.upper)
    qs, ok, cut = _polish_each(ctx, pose, starts)
    found = qs[ok]
    known_c = _canon(known, ctx)
    out: list[FloatArray] = []
    for q in found:
        c = _canon(q, ctx)
        if known_c.shape[0] and bool(np.any(_close(known_c, c, 1e-4))):
            continue
        if out and bool(np.any(_close(_canon(np.array(out), ctx), c, 1e-4))):
            continue
        out.append(q)
    return np.array(out).reshape(-1, known.shape[1]), cut


def _close(rows: FloatArray, q: FloatArray, tol: float) -> NDArray[np.bool_]:
    """Rows within ``tol`` of ``q`` on every joint, both canonical (:func:`_canon`)."""
    d = np.abs(rows - q)
    d = np.minimum(d, 2 * np.pi - d)
    return np.asarray(np.all(d < tol, axis=-1))


def _least_squares_solutions(robot: Any, pose: FloatArray) -> FloatArray | None:
    """eaik's least-squares solutions of ``pose``, ``(m, nq)`` (one that meets the tolerances
    is an exact solution eaik classed as least squares: two branches merging at a
    singularity; ``solve_many`` keeps those).  None when eaik cannot be asked (then
    no waypoint is certified complete)."""
    try:
        from swarm_ik.solvers import analytic

        chain = analytic.analytic_chain(robot)
        if not chain.supported:
            return None
        sol = chain.solver.calculate_IK(np.ascontiguousarray(pose, dtype=float))
        qs = np.asarray(sol.Q, dtype=float).reshape(-1, robot.nq)
        ls = np.asarray(sol.is_LS, dtype=bool).reshape(-1)
    except (ImportError, AttributeError, RuntimeError, TypeError, ValueError):
        return None
    return qs[ls]


def _meets(problem: Any, q: FloatArray, ctx: _Context) -> bool:
    errs = problem.verify(q, ctx.tol_pos, ctx.tol_rot)
    return bool(all(e.met for e in errs) and problem.within_bounds(q))


def _spread(ctx: _Context, i: int) -> FloatArray:
    """Waypoint ``i``'s own spread of solutions (numerical ``solve_many``)."""
    qs, _, _ = _all_solutions(ctx.wps.problem(i), SEEDS, ctx.seed(), ctx)
    return qs


def _tracked(
    ctx: _Context, i: int, parents: FloatArray
) -> tuple[list[FloatArray], list[FloatArray]]:
    """Waypoint ``i`` solved from each parent, and the self-motion samples around each
    solution: ``(solutions, failed attempts)``."""
    if ctx.cover:
        qs, found = _track_batch(ctx, i, parents)
        if not found.any():  # e.g. joints pinned at their limits: the full solver, nearest
            retried = [ctx.track(ctx.wps.target(i), p) for p in parents[:BEAM]]
            good_r = [q for q, ok in retried if ok]
            if good_r:
                return good_r, list(qs)
        return list(qs[found]), list(qs[~found])
    target = ctx.wps.target(i)
    good: list[FloatArray] = []
    bad: list[FloatArray] = []
    for p in parents:
        q, ok = ctx.track(target, p)
        if not ok:
            bad.append(q)
            continue
        good.append(q)
        for s in ctx.self_motion(i, q):
            qs, oks = ctx.track(target, s)
            if oks:
                good.append(qs)
    return good, bad


def _singular(ctx: _Context, qs: FloatArray) -> NDArray[np.bool_]:
    """Rows of ``qs`` whose frame Jacobian has a singular value below :data:`NEAR_SINGULAR`."""
    _, jac = ctx.robot.fk_jacobian(np.ascontiguousarray(qs, dtype=float), ctx.wps.frame)
    sigma = np.linalg.svd(np.asarray(jac).reshape(-1, 6, qs.shape[1]), compute_uv=False)
    return np.asarray(sigma[:, -1] < NEAR_SINGULAR)


def _null(ctx: _Context, qs: FloatArray) -> FloatArray:
    """The self-motion direction (the last right singular vector of the frame's Jacobian) at
    each row of ``qs`` ``(k, nq)``, unit rows ``(k, nq)``."""
    _, jac = ctx.robot.fk_jacobian(np.ascontiguousarray(qs, dtype=float), ctx.wps.frame)
    return np.asarray(np.linalg.svd(np.asarray(jac).reshape(-1, 6, qs.shape[1]))[2][:, -1, :])


def _polish_each(
    ctx: _Context, pose: FloatArray, starts: FloatArray
) -> tuple[FloatArray, NDArray[np.bool_], bool]:
    """``pose`` solved from each row of ``starts`` ``(k, nq)`` (inside the limits), the start
    the only one: one compiled :func:`swarm_ik.solve_batch` call, ``(q (k, nq), success
    (k,))``.  Within the call's evaluations left (:meth:`_Context.evals_left`): the first
    starts only, an equal share each, where they are fewer than the rows (the others
    returned as they are, not met).  The third value: the budget cut a start short (one
    left out, or one that stopped unmet at its share), where its answer proves nothing."""
    import swarm_ik

    k = starts.shape[0]
    qs, ok = np.array(starts, dtype=float), np.zeros(k, dtype=bool)
    left = ctx.evals_left()
    m = k if left is None else min(k, left)
    if m == 0:
        ctx.budget_cut = ctx.budget_cut or k > 0
        return qs, ok, k > 0
    share = None if left is None else left // m
    res = swarm_ik.solve_batch(
        ctx.robot, np.repeat(np.asarray(pose)[None], m, axis=0),
        q0=np.ascontiguousarray(starts[:m]), seed=ctx.seed(), tol_pos=ctx.tol_pos,
        tol_rot=ctx.tol_rot, max_starts=1, max_evals=share,
    )  # fmt: skip
    ctx.spend(int(np.sum(res.n_evals)))
    qs[:m] = np.asarray(res.q, dtype=float)
    ok[:m] = np.asarray(res.success, dtype=bool)
    cut = share is not None and (
        m < k or bool(np.any(~ok[:m] & (np.asarray(res.n_evals) >= share)))
    )
    ctx.budget_cut = ctx.budget_cut or cut
    return qs, ok, cut


def _track_batch(ctx: _Context, i: int, starts: Any) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Waypoint ``i`` solved from each row of ``starts`` ``(k, nq)``, the start the only one
    (so the answer is the solution it polishes into): one compiled call of
    :func:`swarm_ik.solve_batch` for an end-effector pose (then checked against the waypoint's
    other goals, if any, with :meth:`IKProblem.verify`), else one solve per start."""

    nq = ctx.robot.nq
    starts = np.clip(np.asarray(starts, dtype=float).reshape(-1, nq), ctx.lower, ctx.upper)
    pose, problem = ctx.wps.target(i)
    if starts.shape[0] == 0:
        return starts, np.zeros(0, dtype=bool)
    if pose is not None and (problem is None or ctx.pose_first):
        qs, ok, _ = _polish_each(ctx, pose, starts)
        if problem is not None:
            ok = np.array(
                [bool(o) and _meets(problem, q, ctx) for q, o in zip(qs, ok, strict=True)]
            )
        return qs, ok
    out = [ctx.track((pose, problem), q) for q in starts]
    return np.array([q for q, _ in out]), np.array([o for _, o in out], dtype=bool)


def _fill(ctx: _Context, i: int, layer: FloatArray) -> FloatArray:
    """``layer`` (samples of waypoint ``i``'s self-motion) with the gaps filled and the ends
    extended: each sample with no neighbour within ``COVER_GAP · COVER_STEP`` on one side
    along the self-motion walks that way, one sample every :data:`COVER_STEP` (pushed along
    the null direction, polished back onto the waypoint), until the walk fails, stops moving
    (a joint limit), or reaches a covered point; at most :data:`MAX_COVER` samples in all.
    The walks advance together (one :func:`_track_batch` per step)."""
    if layer.shape[0] == 0 or layer.shape[0] >= MAX_COVER or ctx.out_of_time():
        return layer
    nulls = _null(ctx, layer)
    d = layer[None, :, :] - layer[:, None, :]  # d[a, b] = layer[b] − layer[a]
    if ctx.wrap.any():
        _wrap_angles(d, ctx.wrap)
    d /= ctx.step
    reach = np.max(np.abs(d), axis=2)
    along = np.einsum("abj,aj->ab", d, nulls / ctx.step)
    near = (reach > 0) & (reach <= COVER_GAP * COVER_STEP)
    walkers: list[tuple[FloatArray, FloatArray]] = []
    gaps: list[float] = []
    for sign in (1.0, -1.0):
        ahead = (reach > 0) & (sign * along > 0)
        lonely = ~np.any(near & ahead, axis=1)
        gap = np.where(ahead, reach, np.inf).min(axis=1)
        walkers += [(layer[a], sign * nulls[a]) for a in np.flatnonzero(lonely)]
        gaps += [float(gap[a]) for a in np.flatnonzero(lonely)]
    order = np.argsort(gaps, kind="stable")  # gaps between samples first, open ends last
    walkers = [walkers[w] for w in order]
    out = layer
    for _ in range(MAX_WALK):
        if not walkers or out.shape[0] >= MAX_COVER or ctx.out_of_time():
            break
        scales = [COVER_STEP / max(float(np.max(np.abs(n) / ctx.step)), 1e-12) for _, n in walkers]
        starts = np.array([q + c * n for (q, n), c in zip(walkers, scales, strict=True)])
        qn, ok = _track_batch(ctx, i, starts)
        moved_on: list[tuple[FloatArray, FloatArray]] = []
        for (q, _), x, good in zip(walkers, qn, ok, strict=True):
            if not good or out.shape[0] >= MAX_COVER:
                continue
            if float(np.max(ctx.steps(q, x) / ctx.step)) < 0.3 * COVER_STEP:
                continue  # stuck (a joint limit)
            if float(np.min(np.max(ctx.steps(out, x) / ctx.step, axis=1))) < 0.5 * COVER_STEP:
                continue  # reached covered ground
            out = np.vstack([out, x[None]])
            moved_on.append((q, x))
        walkers = []
        if moved_on:
            ns = _null(ctx, np.array([x for _, x in moved_on]))
            for (q, x), n in zip(moved_on, ns, strict=True):
                walkers.append((x, n if float(n @ (x - q)) >= 0 else -n))
    return out


def _build(ctx: _Context, start: FloatArray | None) -> _Graph:
    """Candidates of every waypoint: closed form where it applies, the spread of waypoint 0,
    tracking from the previous waypoint's best candidates, a waypoint's own spread where
    every tracked candidate jumps, then, if the path still jumps, a backward pass."""
    n, nq = ctx.wps.n, ctx.robot.nq
    step, wrap = ctx.step, ctx.wrap
    graph = _Graph([], [], [], [], [])
    values: list[tuple[Any, Any] | None] = []

    def value(i: int) -> tuple[Any, Any]:
        """The forward values (jumps, travel) of layer ``i``'s candidates, made on demand (a
        path of certified layers needs none before the search)."""
        k = i
        while k > 0 and values[k - 1] is None:
            k -= 1
        for m in range(k, i + 1):
            if values[m] is not None:
                continue
            layer = graph.layers[m]
            if m > 0:
                ra, ta = values[m - 1]  # type: ignore[misc]
                prev = graph.layers[m - 1]
                r, t, par = _relax_layer(prev, ra, ta, layer, step, wrap)
                graph.relaxed[m] = (prev, layer, r, t, par)
                values[m] = (r, t)
                ctx.relaxed(prev.shape[0], layer.shape[0])
            elif start is None:
                values[m] = (np.zeros(layer.shape[0], dtype=np.int64), _tie_break(layer, ctx))
            else:
                z_r, z_t = np.zeros(1, dtype=np.int64), np.zeros(1)
                r, t, par = _relax_layer(start[None], z_r, z_t, layer, step, wrap)
                graph.relaxed[m] = (start, layer, r, t, par)
                values[m] = (r, t)
        got = values[i]
        assert got is not None
        return got

    closed_ok = True  # until a waypoint shows that the closed form does not apply
    merge_tol = COVER_MERGE if ctx.cover else DUPLICATE
    for i in range(n):
        if i > 0 and (ctx.cut is not None or ctx.past_limit()):
            # not solved: the best candidate of the waypoint before held, not reached
            ctx.timed_out = True
            if ctx.cut is None:
                ctx.cut, ctx.cut_reason = i, ctx.cut_by
            ra, ta = value(i - 1)
            graph.layers.append(_pick(graph.layers[i - 1], ra, ta, 1, ctx))
            ctx.built(graph.layers[i - 1].shape[0], 1)
            graph.valid.append(np.zeros(1, dtype=bool))
            graph.certified.append(False)
            graph.closed.append(False)
            graph.blocked.append(None)
            values.append(None)
            continue
        ctx.begin(i)
        qb = np.empty((0, nq))
        cert = used_closed = spread_done = False
        blocked = None
        if closed_ok and not ctx.out_of_time():
            # (within a budget, waypoint 0's branch search leaves evaluations for the
            # solve from q0 after it: q0 itself may be the answer)
            ctx.keep_evals = TRACK_EVALS if i == 0 and start is not None else 0
            cf = _closed_form(ctx, i)
            ctx.keep_evals = 0
            if cf is None:
                closed_ok = False
            elif cf[1]:
                qb, used_closed, cert, blocked = cf[0], True, cf[2], cf[3]
            elif cf[0].shape[0]:  # numerical: no closed form for this arm
                closed_ok = False
                if ctx.wps.plain:  # (the pose problem is the waypoint's problem)
                    qb, spread_done = _merge(qb, cf[0], ctx), True
        if i == 0:
            if start is not None:
                q, ok = ctx.track(ctx.wps.target(0), start)
                if ok:
                    qb = _merge(qb, q, ctx)
            if not used_closed and not spread_done and not ctx.out_of_time():
                qb, spread_done = _merge(qb, _spread(ctx, 0), ctx), True
            if ctx.cover:
                qb = _fill(ctx, 0, qb)
        prev_q: FloatArray | None
        if i == 0:
            prev_q = None if start is None else start[None]
            ra0, ta0 = np.zeros(1, dtype=np.int64), np.zeros(1)
        else:
            prev_q = graph.layers[i - 1]
            ra0, ta0 = value(i - 1) if not cert else (np.empty(0, dtype=np.int64), np.empty(0))
        bad: list[FloatArray] = []
        par = np.empty((0, nq))
        if i > 0 and not cert:
            qa, ok_rows = graph.layers[i - 1], graph.valid[i - 1]
            # out of time: one solve from the best candidate (the path is still complete)
            beam = 1 if ctx.out_of_time() else MAX_COVER if ctx.cover else BEAM
            if ok_rows.any():
                par = _pick(qa[ok_rows], ra0[ok_rows], ta0[ok_rows], beam, ctx)
            else:
                par = _pick(qa, ra0, ta0, 1, ctx)
            good, bad = _tracked(ctx, i, par)
            qb = _merge(qb, good, ctx, merge_tol)
            if ctx.cover:
                qb = _fill(ctx, i, qb)
        if used_closed and not cert and qb.shape[0] and not ctx.out_of_time():
            # at or near a singular pose: sample the curve of solutions through the singular
            # candidates (a continuum, e.g. q4 + q6 fixed at a UR wrist singularity)
            sing = qb[_singular(ctx, qb)]
            if sing.shape[0]:
                qb = _merge(qb, _fill(ctx, i, sing)[sing.shape[0] :], ctx, COVER_MERGE)
        if not used_closed and not spread_done and not ctx.out_of_time():
            need = qb.shape[0] == 0
            if not need and prev_q is not None:
                rb, _, _ = _relax_layer(prev_q, ra0, ta0, qb, step, wrap)
                need = int(rb.min()) > int(ra0.min())  # every candidate jumps
            if need:
                graph.repaired += 1
                fresh = _merge(np.empty((0, nq)), _spread(ctx, i), ctx)
                if ctx.cover:
                    fresh = _fill(ctx, i, fresh)
                qb = _merge(qb, fresh, ctx, merge_tol)
        ok_b = np.ones(qb.shape[0], dtype=bool)
        if qb.shape[0] == 0 and i > 0:  # nothing meets the waypoint: every configuration of
            # the waypoint before stands in (staying put adds no jump, whatever made that
            # layer: closed form, tracking, stand-ins), with the best failed attempts
            held = graph.layers[i - 1]
            if held.shape[0] > MAX_HELD:  # (the best by the running programme)
                held = _pick(held, *value(i - 1), MAX_HELD, ctx)
            qb = _merge(held, np.array(bad[:BEAM]).reshape(-1, nq), ctx)
            ok_b = np.zeros(qb.shape[0], dtype=bool)
        elif qb.shape[0] == 0:  # the first waypoint: one solve stands in, valid if met, and
            # q0 when it is not met (staying put adds no jump)
            q, met = _stand_in(ctx, start)
            qb, ok_b = q[None], np.array([met])
            if not met and start is not None:
                qb = _merge(qb, start[None], ctx)
                ok_b = np.zeros(qb.shape[0], dtype=bool)
        graph.layers.append(qb)
        if i > 0:
            ctx.built(graph.layers[i - 1].shape[0], qb.shape[0])
        graph.valid.append(ok_b)
        graph.certified.append(cert)
        graph.closed.append(used_closed)
        graph.blocked.append(blocked if not ok_b.any() else None)
        values.append(None)
    if not graph.exhaustive and int(value(n - 1)[0].min()) > 0 and not ctx.out_of_time():
        _backward(ctx, graph)
    graph.unreachable = [i for i in range(n) if not graph.valid[i].any()]
    return graph


def _stand_in(ctx: _Context, start: FloatArray | None) -> tuple[FloatArray, bool]:
    """Waypoint 0 solved from ``q0`` (or mid-range): ``(q, met)``."""
    ref = start if start is not None else ctx.robot.mid_q()
    return ctx.track(ctx.wps.target(0), ref)


def _backward(ctx: _Context, graph: _Graph) -> None:
    """Track backwards from the last waypoint (its own spread added), adding candidates."""
    n = ctx.wps.n
    step, wrap = ctx.step, ctx.wrap
    if graph.valid[-1].any() and not graph.closed[-1]:
        last = _merge(graph.layers[-1][graph.valid[-1]], _spread(ctx, n - 1), ctx)
        graph.layers[-1] = last
        graph.valid[-1] = np.ones(last.shape[0], dtype=bool)
    last = graph.layers[-1]
    rb, tb = np.zeros(last.shape[0], dtype=np.int64), np.zeros(last.shape[0])
    for i in range(n - 2, -1, -1):
        if ctx.out_of_time():
            break
        qa, ok = graph.layers[i + 1], graph.valid[i + 1]
        if not graph.certified[i] and ok.any():
            good, _ = _tracked(ctx, i, _pick(qa[ok], rb[ok], tb[ok], BEAM, ctx))
            if good:
                base = graph.layers[i][graph.valid[i]]
                merged = _merge(base, good, ctx)
                graph.layers[i] = merged
                graph.valid[i] = np.ones(merged.shape[0], dtype=bool)
        rb, tb, _ = _relax_layer(qa, rb, tb, graph.layers[i], step, wrap)


@dataclass
class _Choice:
    """The dynamic programme's path: candidate index per waypoint, its jumps and travel."""

    index: list[int]
    reconfigs: int
    travel: float


Rejected = dict[int, list[tuple[FloatArray, FloatArray, float]]]
"""Steps the densify check found to jump between waypoints: waypoint ``i`` → ``[(qa, qb,
size)]``, configurations of waypoints ``i − 1`` and ``i`` modulo 2π (:func:`_canon`: every
2π copy of the step is the same motion, and fails alike), size the largest joint travel."""


def _wrap_angles(x: FloatArray, mask: NDArray[np.bool_]) -> FloatArray:
    """``x`` with its entries on ``mask`` (along the last axis) wrapped into ``[-π, π)``, in
    place; returns ``x``."""
    x[..., mask] = (x[..., mask] + np.pi) % (2 * np.pi) - np.pi
    return x


def _canon(qs: FloatArray, ctx: _Context) -> FloatArray:
    """Rows of ``qs`` with every revolute joint wrapped into ``[-π, π)``."""
    return _wrap_angles(np.array(qs, dtype=float), ctx.angular)


def _same(rows: FloatArray, q: FloatArray) -> NDArray[np.bool_]:
    """Rows equal to ``q`` modulo 2π (both canonical)."""
    return _close(rows, q, 1e-9)


def _rejected_size(
    rejected: Rejected, i: int, qa: FloatArray, qb: FloatArray, ctx: _Context
) -> float | None:
    """The size recorded when the step ``qa → qb`` into waypoint ``i`` failed the densify
    check, else None."""
    ca, cb = _canon(qa, ctx), _canon(qb, ctx)
    for ra, rb, size in rejected.get(i, []):
        if _same(ra, ca) and _same(rb, cb):
            return size
    return None


def _tie_break(layer: FloatArray, ctx: _Context) -> FloatArray:
    """Start values of the first waypoint's candidates without ``q0``: :data:`TIE_BREAK` times
    their distance to mid-range (in bounds), so that of paths equal but for a 2π turn of a
    joint the one nearer mid-range is taken, whatever the round-off."""
    mid = 0.5 * (ctx.lower + ctx.upper)
    return np.asarray(TIE_BREAK * np.sum(np.abs(layer - mid) / ctx.step, axis=1))


def _search(graph: _Graph, start: FloatArray | None, ctx: _Context, rejected: Rejected) -> _Choice:
    """The path minimising (jumps, travel) through the layers."""
    step, wrap = ctx.step, ctx.wrap
    n = len(graph.layers)
    parents: list[NDArray[np.int64]] = []
    first = graph.layers[0]
    k0 = first.shape[0]
    same = True  # (every layer so far as the build relaxed it: its values still hold)

    def kept(i: int, before: Any, layer: FloatArray, forbid: Any) -> Any:
        entry = graph.relaxed.get(i)
        if same and forbid is None and entry is not None:
            if entry[0] is before and entry[1] is layer:
                return entry[2:]
        return None

    if start is not None:
        forbid0 = _forbid(rejected, 0, start[None], first, ctx)
        got = kept(0, start, first, forbid0)
        same = got is not None
        zero_r, zero_t = np.zeros(1, dtype=np.int64), np.zeros(1)
        r, t, par = got or _relax_layer(start[None], zero_r, zero_t, first, step, wrap, forbid0)
    else:
        r, par = np.zeros(k0, dtype=np.int64), np.zeros(k0, dtype=np.int64)
        t = _tie_break(first, ctx)
    parents.append(par)
    for i in range(1, n):
        qa, qb = graph.layers[i - 1], graph.layers[i]
        forbid = _forbid(rejected, i, qa, qb, ctx)
        got = kept(i, qa, qb, forbid)
        same = got is not None
        r, t, par = got or _relax_layer(qa, r, t, qb, step, wrap, forbid)
        parents.append(par)
    best = int(np.lexsort((t, r))[0])
    idx = [best]
    for i in range(n - 1, 0, -1):
        idx.append(int(parents[i][idx[-1]]))
    idx.reverse()
    return _Choice(idx, int(r[best]), float(t[best]))


def _forbid(rejected: Rejected, i: int, qa: FloatArray, qb: FloatArray, ctx: _Context) -> Any:
    """The ``(ka, kb)`` mask of the steps from ``qa``'s rows into ``qb``'s (waypoint ``i``)
    that failed the densify check, or None."""
    entries = rejected.get(i)
    if not entries:
        return None
    ca, cb = _canon(qa, ctx), _canon(qb, ctx)
    m = np.zeros((qa.shape[0], qb.shape[0]), dtype=np.bool_)
    for ra, rb, _ in entries:
        m[np.ix_(_same(ca, ra), _same(cb, rb))] = True
    return m


def _densify(
    ctx: _Context, graph: _Graph, start: FloatArray | None, choice: _Choice, k: int,
    rejected: Rejected,
) -> tuple[_Choice, FloatArray, bool]:  # fmt: skip
    """Check the chosen steps through ``k`` interpolated poses each, searching again without
    the failing ones until the chosen path passes (at most :data:`DENSIFY_ROUNDS` rounds; the
    last choice is checked in any case, its failing steps then reported as jumps).

    Returns:
        ``(the choice, the dense path ((N − 1)(k + 1) + 1, nq), whether the rounds
        sufficed)``; ``rejected`` gains the failing steps.
    """
    checked: dict[tuple[int, int, int], tuple[bool, FloatArray, float]] = {}

    def check(choice: _Choice) -> tuple[FloatArray, bool]:
        dense = [graph.layers[0][choice.index[0]][None]]
        failed = False
        for i in range(1, ctx.wps.n):
            a, b = choice.index[i - 1], choice.index[i]
            qa, qb = graph.layers[i - 1][a], graph.layers[i][b]
            key = (i, a, b)
            if key not in checked and not graph.valid[i][b] and np.array_equal(qa, qb):
                # staying put at a waypoint nothing meets (its stand-in, the configuration
                # before it): no motion, so nothing to track through (no jump)
                checked[key] = (True, np.repeat(qb[None], k + 1, axis=0), 0.0)
            if key not in checked and ctx.out_of_time():  # the steps left: unchecked at once
                rest = [graph.layers[j][choice.index[j]] for j in range(i - 1, ctx.wps.n)]
                dense.append(_joint_space_chains(np.array(rest), k, ctx).reshape(-1, qa.size))
                return np.vstack(dense), True
            if key not in checked:
                checked[key] = _check_step_dense(ctx, i, qa, qb, k)
            ok, chain, size = checked[key]
            if not ok and ctx.timed_out:  # (cut by the time limit: unchecked, not rejected)
                dense.append(chain)
                failed = True
                continue
            within = float(np.max(ctx.steps(qa, qb) / ctx.step)) <= 1.0 + _STEP_SLACK
            if not ok and within and _rejected_size(rejected, i, qa, qb, ctx) is None:
                rejected.setdefault(i, []).append((_canon(qa, ctx), _canon(qb, ctx), size))
                failed = True
            dense.append(chain)
        return np.vstack(dense), failed

    for _ in range(DENSIFY_ROUNDS):
        dense, failed = check(choice)
        if not failed:
            return choice, dense, True
        if ctx.out_of_time():  # (no round more: the steps left are reported unchecked)
            return choice, dense, False
        choice = _search(graph, start, ctx, rejected)
    dense, failed = check(choice)
    return choice, dense, not failed


def _joint_space_chains(rows: FloatArray, k: int, ctx: _Context) -> FloatArray:
    """The unchecked chains of the steps between consecutive ``rows`` ``(m, nq)``: ``k``
    points evenly spaced in joint space (the short way round on joints modulo 2π) and the
    next row, ``(m − 1, k + 1, nq)``."""
    qa, qb = rows[:-1], rows[1:]
    d = _wrap_angles(qb - qa, ctx.wrap)
    s = np.arange(1, k + 1)[None, :, None] / (k + 1)
    inner = _wrap_angles(qa[:, None, :] + d[:, None, :] * s, ctx.true_wrap)
    return np.concatenate([inner, qb[:, None, :]], axis=1)


def _check_step_dense(
    ctx: _Context, i: int, qa: FloatArray, qb: FloatArray, k: int
) -> tuple[bool, FloatArray, float]:
    """Track from ``qa`` through ``k`` poses between waypoints ``i − 1`` and ``i`` and on to
    ``qb``: the step passes when every interpolated pose is met and each joint's travel along
    the chain (the sum of its changes, so that a joint going out and back counts) stays
    within the bound.

    Returns:
        ``(passes, the chain ((k + 1), nq) ending with qb, the largest joint travel along
        it [rad / m])``.
    """
    assert ctx.wps.poses is not None
    pa, pb = ctx.wps.poses[i - 1], ctx.wps.poses[i]
    chain: list[FloatArray] = []
    q = qa
    met_all = True
    for s in range(1, k + 1):
        if ctx.out_of_time():  # the rest of the step unchecked: joint-space points, not met
            d = _wrap_angles(qb - q, ctx.wrap)  # (the short way round on joints modulo 2π)
            for t in range(1, k + 2 - s):
                chain.append(_wrap_angles(q + d * (t / (k + 2 - s)), ctx.true_wrap))
            met_all = False
            break
        pose = interpolate_pose(pa, pb, s / (k + 1))
        qn, met = ctx.track(ctx.wps.target_at(pose, i), q)
        met_all = met_all and met
        chain.append(qn)
        q = qn
    chain.append(qb)
    links = np.vstack([qa[None], np.array(chain)])
    travel = ctx.steps(links[:-1], links[1:]).sum(axis=0)
    ok = met_all and bool(np.all(travel <= ctx.step * (1 + _STEP_SLACK)))
    return ok, np.array(chain), float(travel.max())


# -------------------------------------------------------------------- the result
def _finish(
    ctx: _Context, graph: _Graph, start: FloatArray | None, choice: _Choice, proof: bool,
    dense: FloatArray | None, densify_ok: bool, rejected: Rejected, t_start: float, k: int,
) -> PathResult:  # fmt: skip
    """The path checked with Pinocchio (each waypoint's problem), its steps and reason."""
    wps, step = ctx.wps, ctx.step
    n = wps.n
    q = np.array([graph.layers[i][choice.index[i]] for i in range(n)])
    if not np.array_equal(ctx.wrap, ctx.true_wrap):  # samples modulo 2π: unwound
        if dense is not None:
            dense = _unwind(dense, start, ctx)
            q = dense[:: k + 1].copy()
        else:
            q = _unwind(q, start, ctx)
    dp = np.zeros(n)
    dr = np.zeros(n)
    reached = np.zeros(n, dtype=bool)
    for i in range(n):  # the independent check (Pinocchio, coal)
        problem = wps.problem(i)
        errs = problem.verify(q[i], ctx.tol_pos, ctx.tol_rot)
        dp[i] = max(
            (e.position_error for e in errs if not math.isnan(e.position_error)), default=0.0
        )
        dr[i] = max(
            (e.rotation_error for e in errs if not math.isnan(e.rotation_error)), default=0.0
        )
        reached[i] = all(e.met for e in errs) and problem.within_bounds(q[i])
    prev = np.vstack([start[None], q]) if start is not None else q
    d = ctx.steps(prev[:-1], prev[1:], true=True)
    off = 0 if start is not None else 1  # the waypoint each step arrives at
    ratio = d / step
    jumps: list[tuple[int, float]] = []
    for s in range(d.shape[0]):
        i = s + off
        if float(ratio[s].max()) > 1.0 + _STEP_SLACK:
            jumps.append((i, float(d[s][int(np.argmax(ratio[s]))])))  # (the joint most over)
        elif i > 0 and rejected.get(i):
            size = _rejected_size(rejected, i, prev[s], prev[s + 1], ctx)
            if size is not None:
                jumps.append((i, size))
    max_ratio = float(ratio.max()) if ratio.size else 0.0
    max_step = float(d.max()) if d.size else 0.0
    status, reason = _reason(
        ctx, graph, start, q, reached, jumps, proof, densify_ok, max_step, max_ratio, k
    )
    for arr in (q, dp, dr, reached):
        arr.flags.writeable = False
    if dense is not None:
        dense.flags.writeable = False
    return PathResult(
        q=q,
        success=bool(reached.all()),
        jump_free=not jumps,
        reconfigurations=tuple(jumps),
        max_step=max_step,
        max_step_ratio=max_ratio,
        position_errors=dp,
        rotation_errors=dr,
        reached=reached,
        reason=reason,
        time_s=time.perf_counter() - t_start,
        # (jumps that only the densify check found prove nothing: the verdict is not exact)
        exhaustive=graph.exhaustive and (not jumps or proof),
        n_candidates=np.array([layer.shape[0] for layer in graph.layers], dtype=np.int64),
        travel=float(d.sum()),
        q_dense=dense,
        n_evals=ctx.used,
        status=status,
    )


def _unwind(rows: FloatArray, start: FloatArray | None, ctx: _Context) -> FloatArray:
    """The path ``rows`` ``(m, nq)``, found modulo 2π on the wide joints, made continuous:
    each such joint unwrapped (from ``q0`` when given) and shifted by the whole turns that
    keep it within its limits, nearest mid-range; where no shift fits, turned back by 2π
    where it leaves them (a jump, then measured and reported as such)."""
    out = np.array(rows, dtype=float)
    two_pi = 2 * np.pi
    for j in np.flatnonzero(ctx.wrap & ~ctx.true_wrap):
        lo, hi = float(ctx.lower[j]), float(ctx.upper[j])
        seq = out[:, j] if start is None else np.concatenate([[start[j]], out[:, j]])
        u = np.unwrap(seq)
        if start is None:
            k_lo = math.ceil((lo - 1e-9 - float(u.min())) / two_pi)
            k_hi = math.floor((hi + 1e-9 - float(u.max())) / two_pi)
            if k_lo <= k_hi:
                mid = 0.5 * (lo + hi)
                k = min(
                    range(k_lo, k_hi + 1), key=lambda m: abs(float(u.mean()) + two_pi * m - mid)
                )
                u = u + two_pi * k
        for t in range(u.shape[0]):  # (only where no shift fits)
            while u[t] > hi + 1e-9:
                u[t:] -= two_pi
            while u[t] < lo - 1e-9:
                u[t:] += two_pi
        out[:, j] = np.clip(u[u.shape[0] - out.shape[0] :], lo, hi)
    return out


def _conflicts(ctx: _Context, missed: list[int], q: FloatArray) -> tuple[str, int | None]:
    """Where the goals of a waypoint not reached conflict, as ``solve`` says it: the first
    waypoint whose goals :func:`swarm_ik.api.conflicting_goals` proves contradictory (what
    they hold their frames to, before any search: a proof), else the first whose goals pull
    against each other at the configuration the path holds for it
    (:meth:`swarm_ik.IKProblem.opposing_goals`, as ``solve`` judges its answer: no proof; the
    first three such waypoints tried).
    Returns ``(the text, the waypoint proven so or None)``; ``("", None)`` when none is found
    (goal lists of a path were "no IK solution found" where ``solve`` of the same goals said
    ``conflicting_goals``)."""
    for i in missed:
        why = conflicting_goals(ctx.wps.problem(i), ctx.tol_pos, ctx.tol_rot)
        if why is not None:
            return f"; the goals of waypoint {i} conflict: {why}", i
    for i in missed[:3]:  # (a few: each test evaluates every goal and its Jacobian once)
        why = ctx.wps.problem(i).opposing_goals(q[i])
        if why is not None:
            return f"; the goals of waypoint {i} pull against each other: {why}", None
    return "", None


def _reason(
    ctx: _Context, graph: _Graph, start: FloatArray | None, q: FloatArray, reached: Any,
    jumps: list[tuple[int, float]], proof: bool, densify_ok: bool, max_step: float,
    max_ratio: float, k: int,
) -> tuple[str, str]:  # fmt: skip
    """``(status, reason)``: why the call ended in :attr:`swarm_ik.Result.reason`'s words
    (:attr:`PathResult.status`), and one line of what the path is and why it is (not) a
    success."""
    parts: list[str] = []
    cut = q.shape[0] if ctx.cut is None else ctx.cut
    missed = [int(i) for i in np.flatnonzero(~np.asarray(reached)) if i < cut]
    word = None
    if missed:
        found, word = _missed_reasons(ctx, graph, q, missed)
        parts.extend(found)
    # (the status in the precedence of Result.reason: a proof, then the budget that ended
    # the call, then nothing known)
    if np.asarray(reached).all():
        status = "jumps" if jumps else "converged"
    elif word is not None:
        status = word
    elif ctx.timed_out:
        status = "budget" if ctx.spent else "time_limit"
    elif ctx.budget_cut and ctx.max_evals is not None:
        status = "budget"
    else:
        status = "local_minima"
    if jumps:
        listed = ", ".join(f"{i} ({s:.3g})" for i, s in jumps[:10])
        listed += " …" if len(jumps) > 10 else ""
        plural = "s" if len(jumps) > 1 else ""
        msg = f"{len(jumps)} jump{plural} beyond max_joint_step, at waypoint (size) {listed}"
        if start is not None and jumps[0][0] == 0:
            layer0 = graph.layers[0][graph.valid[0]] if graph.valid[0].any() else graph.layers[0]
            nearest = float(np.min(np.max(ctx.steps(layer0, start) / ctx.step, axis=-1)))
            msg += (
                "; no IK solution of waypoint 0 lies within max_joint_step of q0 (the nearest "
                f"is {nearest:.3g} times the bound away)"
            )
        if missed:
            msg += (
                "; a waypoint not reached holds a stand-in (the configuration before it, "
                "or the best attempt)"
            )
        elif proof:
            origin = " from q0" if start is not None else ""
            msg += (
                "; exhaustive: every waypoint's closed-form set is complete, so this proves "
                f"that no jump-free path exists{origin} through these waypoints"
            )
        elif graph.exhaustive and k:
            msg += (
                "; the waypoints' closed-form sets are complete and a path through them "
                "alone is jump-free, but the densify check of the interpolated poses failed "
                "its steps: not a proof, the fewest jumps found"
            )
        else:
            msg += "; not exhaustive (numerical candidate sets): the fewest jumps found"
        if k and not densify_ok and not ctx.timed_out:
            msg += f"; densify checks stopped after {DENSIFY_ROUNDS} rounds"
        parts.append(msg)
    if ctx.budget_cut and not ctx.timed_out:
        parts.append(
            "max_evals reached: some solves were cut short (a closed-form set they checked is "
            "not certified complete)"
        )
    if ctx.timed_out:
        unchecked = "; the interpolated poses of the later steps were not checked" if k else ""
        what, lack = ("max_evals", "evaluations") if ctx.spent else ("time_limit", "time")
        msg = f"{what} reached: the later waypoints were only tracked (no {lack} to build them)"
        if ctx.cut is None and ctx.stopped_at is not None and ctx.stopped_at >= q.shape[0] - 1:
            msg = f"{what} reached: every waypoint built, the refinement after it cut short"
        if ctx.cut is not None:
            last = q.shape[0] - 1
            held = f"waypoints {ctx.cut}–{last}" if ctx.cut < last else f"waypoint {last}"
            by = "" if ctx.cut_reason == what else f" ({ctx.cut_reason} reached)"
            msg += f", and {held} not solved{by} (holding waypoint {ctx.cut - 1}'s configuration)"
        parts.append(msg + unchecked)
    if not parts:
        checked = f", {k} interpolated poses per step checked" if k else ""
        return status, (
            f"jump-free: all {q.shape[0]} waypoints reached, largest step {max_step:.3g} "
            f"({max_ratio:.2f} of the bound){checked}"
        )
    return status, "; ".join(parts)


def _listed(indices: list[int]) -> str:
    """``"waypoint 3"`` or ``"waypoints 3, 4, …"`` (the first ten)."""
    return f"waypoint{'s' if len(indices) > 1 else ''} {_first_ten(indices)}"


def _first_ten(indices: list[int]) -> str:
    """``"3, 4, 5"``: the first ten indices, ``…`` after them when there are more."""
    return ", ".join(str(i) for i in indices[:10]) + (" …" if len(indices) > 10 else "")


def _missed_reasons(
    ctx: _Context, graph: _Graph, q: FloatArray, missed: list[int]
) -> tuple[list[str], str | None]:
    """What the reason says of the waypoints ``missed`` (before the cut): those proven to
    have no solution are "unreachable", with the proof (the pose beyond the frame's reach, a
    goal proven unreachable, the pose's whole closed-form set outside the limits or rejected
    by the other goals, goals whose pins conflict); the others are "not reached" (a search
    that found nothing, or the budget that ended it), with what is known of them.  With the
    status word this implies (:attr:`PathResult.status`): ``"unreachable"`` where a pose is
    beyond reach or its closed-form set outside the limits, else ``"conflicting_goals"``
    where goals are proven contradictory or pull against each other, else ``"unreachable"``
    where the other goals reject every branch of a complete set; None where nothing is
    known."""
    out_of_reach = {i: _beyond_reach(ctx, i) for i in missed}
    beyond = [i for i in missed if out_of_reach[i] is not None]
    blocked = [i for i in missed if i < len(graph.blocked) and graph.blocked[i] is not None]
    closed = [  # (each one's own closed-form set, whole, held no solution)
        i
        for i in missed
        if i not in blocked
        and out_of_reach[i] is None
        and ctx.wps.pose_only(i) is not None
        and i < len(graph.closed)
        and graph.closed[i]
        and i not in ctx.cut_layers
    ]
    conflicts, conflict_at = _conflicts(ctx, missed, q)
    proofs = set(beyond) | set(closed) | {i for i in blocked if graph.certified[i]}
    if conflict_at is not None:
        proofs.add(conflict_at)
    proven = [i for i in missed if i in proofs]
    rest = [i for i in missed if i not in proofs]
    parts = []
    if proven:
        blocked_p = [i for i in blocked if i in proofs]
        why = "no IK solution found"
        if blocked_p:
            why = _blocked_reason(ctx, graph, proven, blocked_p)
        if beyond:
            why += f"; {out_of_reach[beyond[0]]}: {beyond[:10]}"
        if closed:
            at = "" if closed == proven else f": {closed[:10]}"
            why += f" (closed form: none meets it within the joint limits{at})"
        why += _inside_reason(ctx, proven)
        if conflict_at is not None:
            why += conflicts
        parts.append(f"{_listed(proven)} unreachable: {why}")
    if rest:
        blocked_r = [i for i in blocked if i not in proofs]
        found = _blocked_reason(ctx, graph, rest, blocked_r) if blocked_r else ""
        known = _inside_reason(ctx, rest) + (conflicts if conflict_at is None else "")
        if ctx.timed_out:  # (tracked with what the limit left: not a proof)
            within = "max_evals" if ctx.spent else "the time limit"
            head = f"{_listed(rest)} not reached within {within}"
            parts.append(head + (f"; {found}" if found else "") + known)
        else:  # (a search that found nothing: no proof that nothing exists)
            found = found or "no IK solution found"
            parts.append(f"{_listed(rest)} not reached: {found}{known}")
    word = None
    if beyond or closed:  # (a pose no configuration within the limits meets)
        word = "unreachable"
    elif conflicts:  # (proven contradictory, or pulling against each other: as solve says)
        word = "conflicting_goals"
    elif proven:  # (every branch of a pose rejected by the other goals: a proof)
        word = "unreachable"
    return parts, word


def _blocked_reason(ctx: _Context, graph: _Graph, missed: list[int], blocked: list[int]) -> str:
    """Why the waypoints ``blocked`` (of ``missed``) are not reached: the closed form gave
    their poses branches within the joint limits, and their other goals (collisions, …)
    rejected every one; a proof where each set was certified complete."""
    from swarm_ik.goals import AvoidCollisions

    failed: dict[str, bool] = {}  # label → a collision goal
    for i in blocked:
        goals = ctx.wps.problem(i).goals
        for k in graph.blocked[i] or ():
            label = "the joint bounds" if k < 0 else goals[k].describe()
            failed[label] = k >= 0 and isinstance(goals[k], AvoidCollisions)
    collisions = all(failed.values())
    what = (
        "collision-free IK solution"
        if collisions
        else f"IK solution meeting {', '.join(sorted(failed))}"
    )
    fails = "collides" if collisions else "fails it" if len(failed) == 1 else "fails them"
    listed = _first_ten(blocked)
    complete = all(graph.certified[i] for i in blocked)
    sets = "each set complete: a proof" if complete else "the sets not certified complete"
    how = f"(closed form: every branch within the joint limits {fails}; {sets})"
    if len(blocked) == len(missed):
        why = f"no {what} {how}"
    else:
        why = f"no IK solution found; at {listed} no {what} {how}"
    return why


def _inside_reason(ctx: _Context, missed: list[int]) -> str:
    """``"; the target point of waypoints … lies inside obstacle …"`` for the waypoints of
    ``missed`` whose target point an obstacle of their collision goals holds, else ``""``."""
    inside: dict[str, list[int]] = {}
    for i in missed:
        name = _inside_obstacle(ctx, i)
        if name is not None:
            inside.setdefault(name, []).append(i)
    out = ""
    for name, at in inside.items():
        plural = "s" if len(at) > 1 else ""
        where = _first_ten(at)
        out += f"; the target point of waypoint{plural} {where} lies inside obstacle {name!r}"
    return out


def _inside_obstacle(ctx: _Context, i: int) -> str | None:
    """The obstacle of waypoint ``i``'s collision goals whose inside holds its target point
    (the pose's, or the point a primary goal holds its frame's origin to:
    :meth:`swarm_ik.goals.Goal.pin`), if any (:meth:`AvoidCollisions.obstacle_containing`)."""
    problem = ctx.wps.problem(i)
    avoid = problem.collision_goal
    if avoid is None:
        return None
    points = [ctx.wps.poses[i][:3, 3]] if ctx.wps.poses is not None else []
    for g in problem.goals:
        held = goals_base.pin_of(g, problem.robot) if g.is_primary else None
        if held is not None and held.point is not None:
            points.append(held.point)
    for point in points:
        name = avoid.obstacle_containing(point)
        if name is not None:
            return str(name)
    return None


def _beyond_reach(ctx: _Context, i: int) -> str | None:
    """Why no solution of waypoint ``i`` can exist, if that is proven: its pose beyond the
    frame's reach, or a goal of it unreachable as ``solve`` proves it
    (:func:`swarm_ik.api.unreachable_goal`: a point beyond its frame's reach, a goal's own
    ``infeasible``); else None."""
    if ctx.wps.poses is not None:
        limit = reach_limit(ctx.robot.reach_radius(ctx.wps.frame), ctx.tol_pos)
        if float(np.linalg.norm(ctx.wps.poses[i][:3, 3])) > limit:
            return "beyond the frame's reach"
    why = unreachable_goal(ctx.wps.problem(i), ctx.tol_pos, ctx.tol_rot)
    return None if why is None else f"proven unreachable ({why})"


__all__ = [
    "DEFAULT_MAX_JOINT_STEP",
    "InvalidWaypointError",
    "PathResult",
    "interpolate_pose",
    "solve_path",
]
