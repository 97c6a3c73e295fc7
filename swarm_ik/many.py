"""``solve_many``: every distinct IK branch of one target, each once.

A 6-joint arm reaches a generic pose in up to 8 (wrist, elbow, shoulder) configurations; a
joint with a range beyond 2π repeats each of them every 2π, and a 7-joint arm reaches it along
one-dimensional self-motion manifolds.  :func:`solve_many` returns

* for a non-redundant chain: each **branch** once (distinct modulo 2π on the periodic joints,
  see :mod:`swarm_ik.branches`), as its in-limit copy nearest to ``q0`` (else to the middle of
  the ranges); the other in-limit 2π copies of each branch come from :func:`windings_of`;
* for a redundant chain (more joints than pose constraints): ``n`` solutions spread over the
  self-motion manifolds by farthest-point selection in joint space.

Two paths: ``method="analytic"`` uses eaik (:mod:`swarm_ik.solvers.analytic`) on the 6R
chains it decomposes (UR, z1, spherical wrists), ``method="numerical"`` polishes starts with
the compiled Levenberg–Marquardt kernel of ``swarm``, ``"auto"`` (default) takes the analytic
path when it applies and eaik is installed, else the numerical one, and adds the numerical
path's solutions where the closed form is known to miss some (a singular target with a
continuum of solutions, as a UR wrist at ``q5 = 0``).  At such a target no path returns the
whole set: the solutions returned are samples of the continuum.

>>> import swarm_ik
>>> robot = swarm_ik.load_robot("yumi_left")
>>> problem = swarm_ik.IKProblem.from_q(robot, [0.1, -0.5, 0.2, 0.3, -0.2, 0.4, 0.1])
>>> sols = swarm_ik.solve_many(problem, n=4, seed=0)
>>> len(sols), all(s.success for s in sols)
(4, True)
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
import weakref
from collections.abc import Callable, Iterable, Mapping
from typing import Any, NamedTuple

import numba
import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from swarm_ik._validate import check_seed, count, keywords_checked, positive_float
from swarm_ik.api import DEFAULT_SOLVER, prepare_q0, proven_failure, route_for, warm_up
from swarm_ik.branches import (
    BRANCH_TOL,
    ROUNDOFF_TOL,
    TWO_PI,
    BranchSet,
    branch_distance,
    periodic_mask,
    pose_errors,
    revolute_mask,
    spread_select,
    through_one_point,
)
from swarm_ik.branches import (
    windings as _windings,
)
from swarm_ik.errors import InvalidArgumentError, unknown
from swarm_ik.goals import base as goals_base
from swarm_ik.goals.base import reuse_goal_values
from swarm_ik.kernels import counts_ctrl_c, joints, raise_lost_ctrl_c
from swarm_ik.optimize import check_budget, make_rng, rising_estimate
from swarm_ik.problem import GoalError, IKProblem, largest_errors
from swarm_ik.result import Result, Solutions
from swarm_ik.solvers import analytic
from swarm_ik.solvers.hybrid import CONVERGED, Polisher

SOLVER_NAME = "swarm"
"""Solver name recorded in the numerical path's results (its polish is ``swarm``'s)."""
METHODS = ("auto", "numerical", "analytic")
"""Values of ``solve_many(method=...)``."""
MAX_BATCH = 65536
"""Most starts :func:`solve_many` polishes per compiled call (``batch``; its default 16: a
larger batch only holds more scratch, about ``batch × nq`` floats per array)."""

MAX_SOLUTIONS = 10_000
"""Most solutions one :func:`solve_many` call returns (``n``): the branch set is compared
pairwise as it grows (Panda: n = 1,600 took 1.2 s, 20,000 took 76 s, and n = 10¹² ran on for
hours without a budget)."""

PATIENCE = 48
"""Default ``patience``: random starts in a row without a new branch that end the search."""
POOL_FACTOR = 4
"""A redundant arm's search collects ``POOL_FACTOR · n`` distinct solutions, then spreads."""
_HOP_SKIP = 0.05
"""A hop start within this wrapped distance (rad) of a known branch is not polished."""
FINISH_PER_SOLUTION = 2.5e-5
"""Seconds per solution asked for (``n``) that the numerical search of :func:`solve_many`
keeps out of its ``time_limit`` (up to half of it) for what follows its rounds: the spread
of a redundant arm's pool and each answer's ``Result`` (1–2 ms for 64 Panda solutions
measured) — the first call's estimate; each call then measures what its finish took per
solution, and the robot's next calls keep the larger of that and 0.9 × the last estimate
(:func:`_finish_per_solution`): on a loaded machine a finish of 256 Panda solutions took
8–25 ms, against the 6.4 ms the constant kept, and the call overran its limit by 20–60 %."""


def _finish_per_solution(robot: Any, measured: float | None = None) -> float:
    """The robot's estimate of :data:`FINISH_PER_SOLUTION` [s], updated with ``measured``
    (rising at once, falling by a tenth per call)."""
    cache = robot._cache
    est = float(cache.get("many_finish_s", FINISH_PER_SOLUTION))
    if measured is not None:
        est = rising_estimate(est, measured)
        cache["many_finish_s"] = est
    return est


_MAX_WALKS = 8
"""Most near-singular valleys walked per call (:func:`_valley_roots`)."""
_WALK_ERR = 1e-3
"""A start that stalled with pose errors below this (m, rad)…"""
_WALK_SIGMA = 1e-3
"""…and a smallest Jacobian singular value below this lies on a near-singular valley."""
_WALK_NEAR = 0.1
"""A stalled start within this distance (rad) of a valley already walked starts no walk."""
_WALK_STEP = 0.08
"""Arc step (rad) of the valley walk."""
_WALK_STEPS = 80
"""Most arc steps of the valley walk in each direction."""

FloatArray = np.ndarray


# ------------------------------------------------------------------------ branch hops
@numba.njit(cache=True)
def _mirror_angles(
    h: FloatArray, a: FloatArray, b: FloatArray, c: FloatArray
) -> tuple[bool, float, float]:  # pragma: no cover - compiled
    """Turns ``(φ₁, φ₂)`` of the first two of three parallel joints (axis ``h``, origins
    ``a``, ``b``, ``c``) that reflect the middle origin across the line through the outer two
    while the third stays put; ``ok`` False when the outer origins coincide (projected)."""
    ab = b - a
    ac = c - a
    ab = ab - (ab @ h) * h
    ac = ac - (ac @ h) * h
    norm = math.sqrt(ac @ ac)
    if norm < 1e-12:
        return False, 0.0, 0.0
    u = ac / norm
    ab_m = 2.0 * (ab @ u) * u - ab
    phi1 = math.atan2(h @ np.cross(ab, ab_m), ab @ ab_m)
    bc = ac - ab
    co, si = math.cos(phi1), math.sin(phi1)
    bc_rot = bc * co + np.cross(h, bc) * si + h * (h @ bc) * (1.0 - co)
    want = ac - ab_m
    phi2 = math.atan2(h @ np.cross(bc_rot, want), bc_rot @ want)
    return True, phi1, phi2


class _Hops:
    """Starts that map one branch of a 6R-like chain onto its neighbours.

    * **elbow mirror** (exact) for three consecutive parallel axes ``j, j+1, j+2``: the middle
      joint's origin is reflected across the line through the outer two, the first two joints
      turn to follow it and the third keeps the distal orientation;
    * **wrist flip** ``(q_j + π, −q_{j+1}, q_{j+2} + π)`` (exact for a spherical wrist with
      perpendicular axes, a good start otherwise);
    * **shoulder flip** ``(q_j + π, π − q_{j+1}, −q_{j+2}, π − q_{j+3})`` (a start);
    * each joint turned by π.

    The polish then lands on the neighbouring branch (or back on a known one).
    """

    def __init__(self, robot: Any) -> None:
        self.robot = robot
        model = robot.model
        data = model.createData()
        q_pin = robot.to_pinocchio(np.zeros(robot.nq))
        jac = np.asarray(pin.computeJointJacobians(model, data, q_pin)).reshape(6, model.nv)
        axes = jac[3:].T
        self.local = [np.array(data.oMi[j + 1].rotation).T @ axes[j] for j in range(robot.nq)]
        self.revolute = revolute_mask(robot)
        n = robot.nq
        self.parallel: list[tuple[int, tuple[float, float, float]]] = []
        for j in range(n - 2):
            if not self.revolute[j : j + 3].all():
                continue
            h = axes[j]
            if all(np.linalg.norm(np.cross(h, axes[k])) < 1e-9 for k in (j + 1, j + 2)):
                signs = tuple(float(np.sign(h @ axes[k])) for k in (j, j + 1, j + 2))
                self.parallel.append((j, signs))  # type: ignore[arg-type]
        self._bound: int | None = None
        if n == 6 and self.revolute.all():
            origins = np.array([data.oMi[j + 1].translation for j in range(n)])
            spherical = any(through_one_point(origins[k : k + 3], axes[k : k + 3]) for k in (0, 3))
            self._bound = 8 if (self.parallel or spherical) else 16
        self._flips()

    def elbow(self, q: FloatArray) -> list[FloatArray]:
        """Exact elbow mirrors of ``q`` (one per parallel triple)."""
        if not self.parallel:
            return []
        # (the robot's Data of this thread: the object is shared by the robot's calls, and a
        # Data of its own let two threads read each other's frames: answers differed in bits,
        # order and evaluations from the same call made alone, review 132)
        data = self.robot._data("hops")
        pin.forwardKinematics(self.robot.model, data, self.robot.to_pinocchio(q))
        out = []
        frames = data.oMi
        for j, (s0, s1, s2) in self.parallel:
            h = frames[j + 1].rotation @ self.local[j]
            ok, phi1, phi2 = _mirror_angles(
                h, frames[j + 1].translation, frames[j + 2].translation, frames[j + 3].translation
            )
            if not ok:
                continue
            hop = q.copy()
            hop[j] += s0 * phi1
            hop[j + 1] += s1 * phi2
            hop[j + 2] -= s2 * (phi1 + phi2)
            out.append(hop)
        return out

    def _flips(self) -> None:
        """The flips as ``q·S + O`` rows: sign ``S`` and offset ``O`` matrices per tier."""
        n = self.robot.nq
        rev = self.revolute
        rows: list[list[tuple[FloatArray, FloatArray]]] = [[], []]
        for j in range(n - 2):  # wrist flips (q_j + π, −q_{j+1}, q_{j+2} + π)
            if rev[j : j + 3].all():
                sg, off = np.ones(n), np.zeros(n)
                sg[j + 1] = -1.0
                off[j] = off[j + 2] = np.pi
                rows[0 if j == n - 3 else 1].append((sg, off))
        for j in range(n - 3):  # shoulder flips (q_j + π, π − q_{j+1}, −q_{j+2}, π − q_{j+3})
            if rev[j : j + 4].all():
                sg, off = np.ones(n), np.zeros(n)
                sg[j + 1 : j + 4] = -1.0
                off[j] = off[j + 1] = off[j + 3] = np.pi
                rows[0 if j == 0 else 1].append((sg, off))
        for j in map(int, np.flatnonzero(rev)):  # each joint turned by π
            sg, off = np.ones(n), np.zeros(n)
            off[j] = np.pi
            rows[1].append((sg, off))
        self.sign = [np.array([r[0] for r in t]).reshape(-1, n) for t in rows]
        self.offset = [np.array([r[1] for r in t]).reshape(-1, n) for t in rows]

    def __call__(self, qs: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Hop starts from the branches ``qs`` ``(b, nq)``: ``(first, second)``, each
        ``(k, nq)``.

        ``first``: the elbow mirrors, the wrist flip of the last three joints and the shoulder
        flip of the first four (on a UR5 they land on a new branch 78–100 % of the time);
        ``second``: the other flips and the π turns (9–86 %), tried only when the first ones
        are spent.
        """
        n = qs.shape[1]
        elbows = [h for q in qs for h in self.elbow(q)]
        first = (qs[:, None, :] * self.sign[0] + self.offset[0]).reshape(-1, n)
        second = (qs[:, None, :] * self.sign[1] + self.offset[1]).reshape(-1, n)
        if elbows:
            first = np.vstack([np.array(elbows), first])
        return first, second

    def bound(self) -> int | None:
        """Most branches of a full pose (modulo 2π), from the chain's structure: 8 for a 6R
        chain with three consecutive parallel axes or a spherical wrist (the first or last
        three axes through one point), 16 for another 6R chain (Raghavan & Roth), ``None``
        otherwise (no bound: the patience rule alone ends the search)."""
        return self._bound


_HOPS: weakref.WeakKeyDictionary[Any, _Hops] = weakref.WeakKeyDictionary()


def _hops_for(robot: Any) -> _Hops | None:
    """The robot's :class:`_Hops` (made once), or None where its joint vector is not one joint
    of the model per entry, as the hops read it (a floating base: its six entries are one
    free-flyer joint, and a drone's hops read past its frames, review 131)."""
    if robot.floating_base:
        return None
    h = _HOPS.get(robot)
    if h is None:
        h = _HOPS[robot] = _Hops(robot)
    return h


# ------------------------------------------------------------------------------ API
@goals_base.names_kernel_errors(
    lambda *a, **kw: list((a[0] if a else kw["problem"]).compiled_goals)
)
@counts_ctrl_c  # (outside keywords_checked: a bad keyword is the call's own TypeError there)
@keywords_checked
def solve_many(
    problem: IKProblem,
    n: int = 16,
    *,
    method: str = "auto",
    min_distance: float | None = None,
    q0: Any = None,
    tol_pos: float = 1e-5,
    tol_rot: float = 1e-5,
    seed: int | np.random.Generator | None = 0,
    max_evals: int | None = None,
    time_limit: float | None = None,
    batch: int = 16,
    max_starts: int | None = None,
    max_iters: int = 30,
    patience: int = PATIENCE,
) -> Solutions:
    """Find the distinct IK solutions of a target: every branch once, or a spread for
    redundant arms.

    **Branches.** Two solutions, polished to round-off (pose error ≤ 1e-12), are one branch
    when their joint distance modulo 2π on the periodic joints (continuous ones and revolute
    ones with a range ≥ 2π) is below :data:`swarm_ik.branches.BRANCH_TOL` (1e-6 rad).  Each
    branch is returned once, as its in-limit copy nearest to ``q0`` (else to the middle of the
    ranges).  ``min_distance`` (optional) additionally drops a solution closer than that to a
    kept one.

    **Numerical path.** Rounds of one compiled call each of the Levenberg–Marquardt kernel of
    ``swarm``, polishing to round-off (:data:`~swarm_ik.branches.ROUNDOFF_TOL`): the first
    round ``q0`` (or the middle of the ranges) and ``batch − 1`` random starts; then the
    pending *hop* starts of the branches found so far, first tier before second (first: the
    exact elbow mirror over three parallel axes, the wrist flip of the last three joints, the
    shoulder flip of the first four; second: the other flips and each joint turned by π),
    else ``batch`` new random starts.  Only starts polished to round-off count: a point that
    meets the tolerances but stalls above round-off lies on the valley floor of a
    near-singular target, not on an exact solution (such points were the "extra branches"
    of earlier versions).  When such a stalled point has a nearly singular Jacobian
    (σ_min < 1e-3) the valley is walked by continuation for the exact roots on it
    (:func:`_valley_roots`, at most 8 valleys a call).  The new branches of a round are
    checked with Pinocchio's FK at once (``time_limit`` covers that check; each compiled
    call is capped to the time left).  The search stops at ``n`` branches, at the chain's
    structural bound (8 for a 6R arm with three parallel axes or a spherical wrist, 16 for
    another 6R arm: the set is then complete, except at a singular target with a continuum of
    solutions, e.g. a UR wrist at ``q5 = 0``, where the 8 are samples of it), when every hop
    start is spent and ``patience`` random starts in a row gave no new branch, or at the
    budget (``max_starts``, ``max_evals``, ``time_limit``).  When no start reached
    round-off but the one that ended nearest meets the tolerances (a target at the edge of
    reach, beyond the exact roots), that point is the one solution returned.  At a target on a
    singularity
    where two branches merge into one double root (a straight elbow) the polish may stop on
    both sides of it, a few 1e-6 rad apart, and report it twice.  A search that ends by its
    patience or its budget proves nothing: the set is what its starts reached.  A held-out
    review found such misses where eaik (or a brute-force search) found more: branches lying
    exactly on a joint limit (kinova, q3 at its limit: 4 of 8, even with ``patience=10_000``),
    the branch of a straight elbow's double root (UR5, q3 = 0: 9 of 40 targets missed one),
    and on a generic 6R arm without a closed form 2 of 6 random targets at the default
    patience (``patience=2000`` found it).  Where eaik applies, ``method="auto"`` has none of
    these misses.

    **Redundant arms** (more joints than constrained pose coordinates: 7-joint arms, or a
    position-only problem with more than 3 joints): random starts are polished until
    ``4 · n`` distinct solutions (:data:`POOL_FACTOR`) are pooled or the budget ends, then ``n``
    are picked by farthest-point selection in wrapped joint space, starting from the one
    nearest to ``q0`` / mid-range (:func:`swarm_ik.branches.spread_select`).

    **Analytic path.** eaik's closed form (:func:`swarm_ik.solvers.analytic.closed_form_set`):
    the complete set of a generic target at once, verified with Pinocchio.  eaik's
    least-squares points are polished into solutions where they lead to one: at a singular
    target eaik may return no exact solution at all (a UR wrist at ``q5 = 0``: ``q6`` is
    free), and the set then holds the representatives the polish reached (near such a target,
    ``q5 = 1e-9``, a point within the tolerances where the polish stalled above round-off)
    and is marked incomplete.  With ``method="auto"`` the numerical path then runs as well (as with
    ``method="numerical"``, its budget less the polish's evaluations) and the closed form's
    solutions it did not find join its own: never fewer solutions than the numerical path
    alone, up to ``n``.

    Args:
        problem: The IK problem.
        n: Most solutions (branches) returned, in ``[1,`` :data:`MAX_SOLUTIONS` ``]``.
        method: ``"auto"`` (analytic when eaik is installed and decomposes the chain, with the
            numerical path added where the closed form is marked incomplete; else numerical),
            ``"numerical"`` or ``"analytic"`` (refused with the reason when it does not apply).
        min_distance: Optional coarser filter (rad / m, ``> 0``): drop a solution closer than
            this to a kept one.  Default ``None``: branches only.
        q0: Optional reference and first start, shape ``(nq,)`` (clipped into the limits with a
            warning).
        tol_pos: Position tolerance [m] of every solution.
        tol_rot: Rotation tolerance [rad] of every solution.
        seed: Seed or Generator for the random starts.
        max_evals: Most FK + Jacobian evaluations in total: the closed form's polish of
            eaik's least-squares points (analytic path) and the numerical search (on
            ``"auto"``'s fallback both, from one budget).
        time_limit: Most wall-clock seconds, verification included (numerical path).
        batch: Starts polished per compiled call (1 to :data:`MAX_BATCH`).
        max_starts: Most starts; default ``64 · n`` when neither ``max_evals`` nor
            ``time_limit`` is given, else unlimited.
        max_iters: Evaluations per start before it is abandoned.
        patience: Random starts in a row without a new branch that end the search once the
            hop starts are spent (not on a redundant arm, whose solutions are a continuum:
            there the budget ends it) (default :data:`PATIENCE` = 48: with it the numerical path
            found every one of eaik's branches on 50 + 150 + 150 targets each of UR5, UR10
            and z1 in ``swarm-ik bench many`` and its seeds 7 and 11).

    Returns:
        The solutions, nearest to the reference first (the Euclidean distance of each
        returned ``q`` to it, whichever ``method``), each verified with Pinocchio's FK
        (``success`` True; ``goal_errors`` each primary goal's errors, as
        :func:`swarm_ik.solve`'s).  ``n_evals`` and ``time_s`` are the totals spent when
        each was found (on the analytic path the evaluations of the polish of eaik's
        least-squares points, 0 where it returned none).  ``solver`` is ``"swarm"``
        (numerical) or ``"analytic"`` (both on ``"auto"``'s fallback).  Empty when nothing
        was found: the target beyond reach, or the budget spent before a first solution.
        A :class:`~swarm_ik.result.Solutions` (a list) whose ``reason``, ``n_evals`` and
        ``time_s`` say why the search ended and what the whole call spent, in
        :func:`swarm_ik.solve`'s words (``"converged"``, ``"budget"``, ``"time_limit"``,
        ``"unreachable"``, …).  :func:`windings_of` adds each branch's other in-limit 2π
        copies.

    Raises:
        InvalidArgumentError: ``n``, ``min_distance``, ``batch``, ``patience``, a tolerance or
            the budget is out of range, or ``problem`` is not an :class:`IKProblem`.
        UnknownNameError: ``method`` is not one of :data:`METHODS`.
        swarm_ik.solvers.analytic.AnalyticUnavailableError: ``method="analytic"`` without eaik.
        swarm_ik.solvers.analytic.AnalyticUnsupportedError: ``method="analytic"`` on a chain
            or problem eaik cannot solve.
    """
    t_call = time.perf_counter()
    if not isinstance(problem, IKProblem):
        raise InvalidArgumentError(f"problem must be an IKProblem, got {type(problem).__name__}")
    n = count(n, "n", 1, MAX_SOLUTIONS)
    if method not in METHODS:
        raise unknown("method", method, METHODS)
    if min_distance is not None:
        min_distance = positive_float(min_distance, "min_distance (or None)")
    batch = count(batch, "batch", 1, MAX_BATCH)
    max_iters = count(max_iters, "max_iters", 2)
    max_starts = None if max_starts is None else count(max_starts, "max_starts (or None)")
    patience = count(patience, "patience")
    tol_pos = positive_float(tol_pos, "tol_pos")
    tol_rot = positive_float(tol_rot, "tol_rot")
    check_budget(max_evals, time_limit)
    start_q, ref = _start_and_reference(problem, q0)
    checked = check_seed(seed)  # (before any Generator is made)
    seed_label = None if isinstance(checked, np.random.Generator) else checked

    use_analytic = False
    if method == "analytic":
        reason = analytic.support(problem)  # raises AnalyticUnavailableError without eaik
        if reason:
            raise analytic.AnalyticUnsupportedError(f"method='analytic' refused: {reason}")
        use_analytic = True
    elif method == "auto" and analytic.eaik_available():
        use_analytic = not analytic.support(problem)
    proven = proven_failure(problem, tol_pos, tol_rot)
    if proven is not None:  # (no joint vector meets the goals: no budget is spent on them)
        return Solutions([], proven, 0, time.perf_counter() - t_call)

    searched: list[float] = []  # (when the numerical search ended: its finish measured)

    def search(evals: int | None, t0: float, limit: float | None) -> _Found:
        """The numerical search within ``evals`` and ``limit`` seconds from ``t0``."""
        found = _numerical(
            problem, int(n), ref, start_q, make_rng(seed), min_distance, evals, limit,
            tol_pos, tol_rot, batch, max_starts, max_iters, patience, t0,
        )  # fmt: skip
        searched.append(time.perf_counter())
        return found

    def loaded() -> float | None:
        """The compiled kernels loaded (a first call's compile or cache load), and the time
        limit left for the search: less all the call spent so far (the checks before any
        search, the loading), up to half of it (as :func:`solve` charges a first call's
        loading; the loading alone was charged, and a Panda call among obstacles took
        1.4-1.8 ms of a 1 ms limit).  The kernels are those of the problem's route, shared by
        the robot's problems of the same goal types (:func:`swarm_ik.api.route_for`: one made
        per call cost 0.25 ms)."""
        warm_up(route_for(problem, DEFAULT_SOLVER, {}))
        _warm_up()
        if time_limit is None:
            return None
        return max(time_limit - (time.perf_counter() - t_call), 0.5 * time_limit)

    def judged(
        found: list[Result], ended: str, evals: int, closest: FloatArray | None = None
    ) -> Solutions:
        """Each solution with its goals' errors from Pinocchio (:meth:`IKProblem.verify`),
        as :func:`swarm_ik.solve`'s result has them, and why the call ended
        (:attr:`Solutions.reason`).  With no exact solution found, the start that ended
        nearest to meeting the goals is the answer when it meets them to the tolerances (a
        target at the edge of reach has no exact root: what :func:`swarm_ik.solve` returns
        there)."""
        if not found and closest is not None and problem.is_success(closest, tol_pos, tol_rot):
            (dp,), (dr,) = pose_errors(problem, closest[None])
            fit = float(problem.fitness(closest[None])[0])
            spent = time.perf_counter() - t_call
            found = [_result(closest, dp, dr, evals, spent, fit, SOLVER_NAME, seed_label)]
            ended = "converged"
        out = [
            dataclasses.replace(r, goal_errors=problem.verify(r.q, tol_pos, tol_rot, q0=start_q))
            for r in found
        ]
        if len(out) >= n or (out and ended not in ("budget", "time_limit")):
            reason = "converged"
        elif out:
            reason = ended
        elif closest is not None and problem.opposing_goals(closest):
            reason = "conflicting_goals"  # (as solve says at its answer)
        else:  # (nothing proven before the search: see below)
            reason = _EMPTY_REASON[ended]
        t_end = time.perf_counter()
        if searched and out:  # (what the finish took per solution: the next call keeps it)
            _finish_per_solution(problem.robot, (t_end - searched[0]) / len(out))
        return Solutions(out, reason, evals, t_end - t_call)

    if not use_analytic:
        limit = loaded()
        t_search = time.perf_counter()
        numerical, found = _numerical_results(
            problem, lambda: search(max_evals, t_search, limit), ref, seed_label
        )
        return judged(numerical, found.ended, found.used, found.closest)
    t0 = time.perf_counter()
    cf = analytic.closed_form_set(problem, ref, tol_pos, tol_rot, max_evals)
    qs, dps, drs = cf.q, cf.position_error, cf.rotation_error
    periodic = periodic_mask(problem.robot, problem.lower, problem.upper)
    if min_distance is not None and qs.shape[0] > 1:
        distinct = BranchSet(periodic, BRANCH_TOL, min_distance)
        keep = [i for i in range(qs.shape[0]) if distinct.add(qs[i])]
        qs, dps, drs = qs[keep], dps[keep], drs[keep]
    qs, dps, drs = qs[:n], dps[:n], drs[:n]  # already nearest to the reference first
    fits = analytic.fitness_of_errors(problem, qs, dps, drs)
    k = qs.shape[0]
    elapsed = time.perf_counter() - t0
    results = _results(qs, dps, drs, [cf.evals] * k, [elapsed] * k, fits, "analytic", seed_label)
    if method == "analytic" or not cf.incomplete:
        cut = max_evals is not None and cf.evals >= max_evals  # (the polish's budget spent)
        return judged(results, "budget" if cut else "closed_form", cf.evals)
    # auto, and the closed form is known to miss solutions (a singular target, e.g. a UR
    # wrist at q5 = 0 with a continuum of them): the numerical search as method="numerical"
    # runs it (its compiled kernels loaded off the clock; the closed form's time and polish
    # evaluations count against the budget), and the closed form's solutions it did not find
    # join its own
    limit = loaded()
    left = None if max_evals is None else max(max_evals - cf.evals, 0)
    t_search = time.perf_counter() - elapsed
    numerical, found = _numerical_results(
        problem, lambda: search(left, t_search, limit), ref, seed_label, cf.evals
    )
    merged = _merged(numerical, results, periodic, min_distance, ref, int(n))
    return judged(merged, found.ended, cf.evals + found.used, found.closest)


_EMPTY_REASON = {
    "budget": "budget",
    "time_limit": "time_limit",
    "starts": "local_minima",  # (every start of the search's own count ended without one)
    "converged": "local_minima",
    "closed_form": "stopped",  # (the closed form returned none within the tolerances and
    # limits: not a proof, eaik's points polished to the tolerances may fall short)
}
""":attr:`Solutions.reason` of an empty answer by how the search ended (a goal proven
unreachable, or two contradictory, end the call before it: :func:`swarm_ik.api.proven_failure`)."""


class _Found(NamedTuple):
    """What the numerical search (:func:`_numerical`) ends with."""

    kept: list[tuple[FloatArray, float, float, int, float]]
    """The solutions: ``(q, dp, dr, evals when found, seconds when found)``."""
    ended: str
    """Why it ended: ``"converged"`` (``n`` found or no new branch in its patience),
    ``"budget"`` (evaluations, or the caller's ``max_starts``), ``"time_limit"`` or
    ``"starts"`` (its own count of starts, ``64 n``, where no budget was given)."""
    used: int
    """Evaluations spent."""
    closest: FloatArray | None = None
    """Where nothing was found: the start that ended nearest to meeting the goals, where
    goals pulling against each other are looked for (:meth:`IKProblem.opposing_goals`)."""


def _numerical_results(
    problem: IKProblem,
    search: Callable[[], _Found],
    ref: FloatArray,
    seed_label: int | None,
    evals_before: int = 0,
) -> tuple[list[Result], _Found]:
    """The numerical path of :func:`solve_many` (its compiled kernels already loaded): the
    ``search`` (:func:`_numerical`), the solutions as results nearest to the reference
    first, each one's ``n_evals`` counted from ``evals_before`` (evaluations spent before
    the search), and the search's end."""
    # (a Python goal's values at each point computed once: rows, errors, checks)
    with reuse_goal_values(bool(problem.python_goals)):
        found = search()
        reps = found.kept
        qs_all = np.array([r[0] for r in reps]).reshape(-1, problem.nq)
        fit_all = problem.fitness(qs_all) if reps else np.empty(0)
    order = _nearest_first(qs_all, ref)
    results = []
    for i in order:
        q_i, dp_i, dr_i, ev_i, t_i = reps[i]
        fit_i = float(fit_all[i])
        results.append(
            _result(q_i, dp_i, dr_i, evals_before + ev_i, t_i, fit_i, SOLVER_NAME, seed_label)
        )
    return results, found


def _merged(
    first: list[Result],
    extra: list[Result],
    periodic: Any,
    min_distance: float | None,
    ref: FloatArray,
    n: int,
) -> list[Result]:
    """``first`` (every one kept), then each of ``extra`` that is a new branch (and farther
    than ``min_distance`` from those kept), nearest to the reference first, at most ``n`` (at
    least ``min(n, len(first))``)."""
    found = BranchSet(periodic, BRANCH_TOL, min_distance)
    for r in first:
        found.q.append(np.array(r.q, dtype=float))
    out = list(first) + [r for r in extra if found.add(r.q)]
    if not out:
        return out
    return [out[i] for i in _nearest_first(np.array([r.q for r in out]), ref)[:n]]


def _nearest_first(qs: FloatArray, ref: FloatArray) -> np.ndarray:
    """The order of the rows of ``qs`` ``(k, nq)`` by their plain Euclidean distance to
    ``ref`` (each already its in-limit 2π copy nearest to it): the order of every path of
    :func:`solve_many`, as the distance ``|q − q0|`` of the returned ``q`` reads (the closed
    form's :func:`swarm_ik.solvers.analytic.closed_form_set` orders so too)."""
    return np.argsort(np.linalg.norm(qs - ref, axis=-1), kind="stable")


def windings_of(
    problem: IKProblem,
    results: list[Result],
    q0: Any = None,
    *,
    tol_pos: float = 1e-5,
    tol_rot: float = 1e-5,
) -> list[list[Result]]:
    """Each solution with its other in-limit 2π copies (joints whose range exceeds 2π).

    Args:
        problem: The problem the solutions are of.
        results: Solutions, e.g. of :func:`solve_many`.
        q0: The reference the copies are ordered by (default: the middle of the ranges), as
            given to :func:`solve_many`.
        tol_pos: Position tolerance the copies are judged by [m], as given to
            :func:`solve_many`.
        tol_rot: Rotation tolerance [rad], likewise.

    Returns:
        Per solution, a list of :class:`Result`: the solution first, then its copies by
        distance to the reference, each judged with Pinocchio (:meth:`IKProblem.verify`,
        ``goal_errors`` as :func:`solve_many`'s).  A copy that misses a goal reading the
        joints themselves (a ``JointValue`` whose joint winds) is left out.

    Raises:
        InvalidArgumentError: ``problem`` is not an :class:`IKProblem`, ``results`` not
            :class:`Result` objects, or a tolerance or ``q0`` is bad.

    >>> import numpy as np, swarm_ik
    >>> robot = swarm_ik.load_robot("ur5")
    >>> problem = swarm_ik.IKProblem.from_q(robot, [0.3, -1.0, 1.2, -0.5, 1.1, 0.2])
    >>> groups = swarm_ik.windings_of(problem, swarm_ik.solve_many(problem, n=2))
    >>> len(groups), len(groups[0])  # every copy of a UR5 branch fits its ±2π limits
    (2, 32)
    """
    if not isinstance(problem, IKProblem):
        raise InvalidArgumentError(f"problem must be an IKProblem, got {type(problem).__name__}")
    if isinstance(results, (str, bytes, Mapping)) or not isinstance(results, Iterable):
        raise InvalidArgumentError(
            f"results must be a list of Result objects (solve_many's), got {type(results).__name__}"
        )
    tol_pos = positive_float(tol_pos, "tol_pos")
    tol_rot = positive_float(tol_rot, "tol_rot")
    start_q, ref = _start_and_reference(problem, q0)
    out: list[list[Result]] = []
    for r in results:
        if not isinstance(r, Result):
            raise InvalidArgumentError(f"results must be Result objects, got {type(r).__name__}")
        if r.q.shape != (problem.nq,):
            raise InvalidArgumentError(
                f"results must be solutions of this problem's robot ({problem.nq} joints), got "
                f"a Result with {r.q.shape[0] if r.q.ndim == 1 else r.q.shape} joint values"
            )
        errors = problem.verify(r.q, tol_pos, tol_rot, q0=start_q)
        if not all(e.met for e in errors):
            raise InvalidArgumentError(
                f"results[{len(out)}] does not meet this problem's goals within the tolerances "
                "(a solution of another problem or robot?): "
                + ", ".join(f"{e.goal} off by {e.position_error:.3g} m, "
                            f"{e.rotation_error:.3g} rad" for e in errors if not e.met)
            )  # fmt: skip
        out.append(_with_windings(problem, r, ref, start_q, tol_pos, tol_rot))
    return out


# -------------------------------------------------------------------------- helpers
_RESULT_DEFAULTS = {
    f.name: f.default for f in dataclasses.fields(Result) if f.default is not dataclasses.MISSING
}


def _result(
    q: FloatArray,
    dp: float,
    dr: float,
    n_evals: int,
    t_found: float,
    fit: float,
    solver: str,
    seed: int | None,
    goal_errors: tuple[GoalError, ...] = (),
) -> Result:
    """One verified solution as a :class:`Result` (``goal_errors``: its check's)."""
    return _results(
        np.asarray(q, dtype=float)[None],
        [dp],
        [dr],
        [n_evals],
        [t_found],
        [fit],
        solver,
        seed,
        [goal_errors],
    )[0]


def _results(
    qs: FloatArray,
    dps: Any,
    drs: Any,
    evals: Any,
    times: Any,
    fits: Any,
    solver: str,
    seed: int | None,
    goal_errors: Any = None,
) -> list[Result]:
    """Verified solutions ``qs`` ``(k, nq)`` as :class:`Result` objects, each ``q`` a fresh
    copy (``goal_errors``: each one's check, else none yet)."""
    k = qs.shape[0]
    if k == 0:
        return []
    q_copy = np.array(qs, dtype=float)
    fit_l = [float(f) for f in fits]
    hist = np.array(fit_l).reshape(k, 1)
    base = {**_RESULT_DEFAULTS, "success": True, "within_limits": True, "solver": solver,
            "seed": seed, "reason": "converged"}  # fmt: skip
    out = []
    for i in range(k):
        kw = base.copy()
        kw["q"] = q_copy[i]
        kw["fitness"] = fit_l[i]
        kw["position_error"] = float(dps[i])
        kw["rotation_error"] = float(drs[i])
        kw["n_evals"] = int(evals[i])
        kw["time_s"] = float(times[i])
        kw["history"] = hist[i]
        if goal_errors is not None:
            kw["goal_errors"] = goal_errors[i]
        out.append(Result(**kw))
    return out


def _start_and_reference(problem: IKProblem, q0: Any) -> tuple[FloatArray | None, FloatArray]:
    """``q0`` validated (:func:`swarm_ik.api.prepare_q0`) and the reference the solutions are
    ordered by: ``q0``, else the middle of the ranges."""
    start_q = prepare_q0(problem, q0)
    return start_q, start_q if start_q is not None else 0.5 * (problem.lower + problem.upper)


def _with_windings(
    problem: IKProblem,
    rep: Result,
    ref: FloatArray,
    start_q: FloatArray | None,
    tol_pos: float,
    tol_rot: float,
) -> list[Result]:
    """The representative and its other in-limit 2π copies, each judged with Pinocchio
    (:meth:`IKProblem.verify`; copies that miss a goal are left out)."""
    copies = _windings(rep.q, problem.lower, problem.upper, revolute_mask(problem.robot))
    if copies.shape[0] == 0:
        return [rep]
    periodic = np.zeros(problem.nq, dtype=bool)  # order by the plain distance to the reference
    copies = copies[np.argsort(branch_distance(copies, ref, periodic))]
    others = copies[branch_distance(copies, rep.q, periodic) > 1e-9]
    if others.shape[0] == 0:
        return [rep]
    fits = problem.fitness(others)
    out = [rep]
    for q, f in zip(others, fits, strict=True):
        errors = problem.verify(q, tol_pos, tol_rot, q0=start_q)
        if all(e.met for e in errors):  # (its errors: the summary figures of the check)
            dp, dr = largest_errors(errors)
            out.append(
                _result(q, dp, dr, rep.n_evals, rep.time_s, float(f), rep.solver, rep.seed, errors)
            )
    return out


def _redundant(problem: IKProblem, rows: int | None = None) -> bool:
    """More joints than the pose constrains (7-joint arms; more than 3 joints, position
    only), or than the ``rows`` of the primary goals (a 6-joint arm with a point and a one-row
    goal: 4 rows; a self-motion, no isolated branches to hop between)."""
    task = 3 if problem.position_only else 6
    return problem.nq > task or (rows is not None and rows < problem.nq)


@numba.njit(cache=True)
def _fold_rows(
    qs: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    rev: NDArray[np.bool_],
    ref: FloatArray,
    out: FloatArray,
    ok: NDArray[np.bool_],
) -> None:  # pragma: no cover - compiled
    """Per row of ``qs``: the in-limit 2π copy nearest to ``ref``, joint by joint (revolute
    joints), clipped into the bounds; ``ok`` False when some joint has no in-limit copy."""
    inv = 1.0 / TWO_PI
    for s in range(qs.shape[0]):
        good = True
        for j in range(qs.shape[1]):
            q = qs[s, j]
            if rev[j]:
                m_min = math.ceil((lo[j] - 1e-9 - q) * inv)
                m_max = math.floor((hi[j] + 1e-9 - q) * inv)
                if m_min > m_max:
                    good = False
                m = min(max(round((ref[j] - q) * inv), m_min), m_max)
                q = q + TWO_PI * m
            elif q < lo[j] - 1e-9 or q > hi[j] + 1e-9:
                good = False
            out[s, j] = min(max(q, lo[j]), hi[j])
        ok[s] = good


@functools.cache
def _warm_up() -> None:
    """Compile (or load from numba's cache) this module's kernels once per process, before a
    solve's clock starts (their types do not depend on the robot)."""
    z, flags = np.zeros((1, 1)), np.ones(1, dtype=np.bool_)
    _fold_rows(z, z[0], z[0], flags, z[0], np.empty((1, 1)), np.empty(1, dtype=np.bool_))
    joints.min_dist2(z, z, flags, np.empty(1))
    joints.fresh_rows(z, z, flags, np.ones(1), 1.0, False, np.empty(1, dtype=np.int64))


class _Folder:
    """Nearest in-limit 2π copies (:func:`~swarm_ik.branches.nearest_winding`) for one problem
    and reference, and wrapped distances to the branches kept so far (compiled)."""

    def __init__(self, lower: FloatArray, upper: FloatArray, revolute: Any, periodic: Any,
                 ref: FloatArray) -> None:  # fmt: skip
        self.lo = np.ascontiguousarray(lower, dtype=float)
        self.hi = np.ascontiguousarray(upper, dtype=float)
        self.rev = np.ascontiguousarray(revolute, dtype=np.bool_)
        self.periodic = np.ascontiguousarray(periodic, dtype=np.bool_)
        self.ref = np.ascontiguousarray(ref, dtype=float)
        self.kept = np.empty((0, lower.shape[0]))

    def __call__(self, qs: FloatArray) -> tuple[FloatArray, Any]:
        """The in-limit copies nearest to the reference ``(k, nq)`` and whether each has one."""
        qs = np.ascontiguousarray(qs, dtype=float)
        out = np.empty_like(qs)
        ok = np.empty(qs.shape[0], dtype=np.bool_)
        _fold_rows(qs, self.lo, self.hi, self.rev, self.ref, out, ok)
        return out, ok

    def dist(self, qs: FloatArray) -> FloatArray:
        """Wrapped distance of each row of ``qs`` ``(m, nq)`` to its nearest kept branch."""
        out = np.full(qs.shape[0], np.inf)
        if self.kept.shape[0] and qs.shape[0]:
            joints.min_dist2(np.ascontiguousarray(qs, dtype=float), self.kept, self.periodic, out)
            np.sqrt(out, out=out)
        return out

    def new(self, qs: FloatArray, tol: float) -> list[int]:
        """Rows of ``qs`` that are new branches: farther than ``tol`` from every kept one
        and from every earlier new row (greedy, in order)."""
        if qs.shape[0] == 0:
            return []
        idx = np.empty(qs.shape[0], dtype=np.int64)
        unit = np.ones(qs.shape[1])
        c = joints.fresh_rows(np.ascontiguousarray(qs, dtype=float), self.kept, self.periodic,
                              unit, float(tol), False, idx)  # fmt: skip
        return idx[:c].tolist()


def _valley_roots(
    pol: Polisher,
    qv: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
    deadline: float | None,
    budget: int = 1 << 62,
) -> tuple[FloatArray, FloatArray, int]:
    """Exact roots on the near-singular valley through the stalled point ``qv``.

    Near a singular target (e.g. a UR wrist at ``q5 ≈ 3e-4`` rad, where four axes are almost
    parallel) the residual is tiny along a curved one-dimensional valley (the self-motion of
    the singular configuration), and the exact solutions are isolated points on it with
    basins far narrower than the valley's curvature: the damped polish and Gauss–Newton stall
    on the valley floor within the tolerances but above round-off.  This walks the valley by
    predictor–corrector continuation: a step of :data:`_WALK_STEP` along the near-null right
    singular vector of the Jacobian, then Gauss–Newton restricted to the other five singular
    directions back onto the floor.  The valley residual ``g = u_minᵀ r`` (its left singular
    vector, sign kept continuous) changes sign across a root, which regula falsi then pins
    down to round-off.  The walk stops at :data:`_WALK_STEPS` steps each way, where the valley
    ends (residual above 1e-3, or σ_min above 1e-2), at the deadline or when ``budget``
    evaluations are spent (never more).

    Returns:
        ``(roots (k, nq), the valley points visited (m, nq), evaluations used)``.
    """
    lo, hi = lower, upper
    evals = 0

    def late() -> bool:
        return deadline is not None and time.perf_counter() >= deadline

    def floor(x: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, float, FloatArray]:
        nonlocal evals
        for it in range(4):
            if it and (evals >= budget or late()):
                break
            r, jac, _dp, _dr = pol.residual(x)
            evals += 1
            u_m, s, vt = np.linalg.svd(jac)
            dx = vt[:-1].T @ ((u_m[:, :-1].T @ r) / s[:-1])
            if float(np.sqrt(dx @ dx)) < 1e-12:
                break
            x = np.minimum(np.maximum(x + dx, lo), hi)
        return x, r, u_m[:, -1], float(s[-1]), vt[-1]

    x0, r0, u0, _s0, v0 = floor(np.asarray(qv, dtype=float))
    roots: list[FloatArray] = []
    curve = [x0]
    for sgn in (1.0, -1.0):
        x, r, u, tan = x0, r0, u0, sgn * v0
        g = float(u @ r)
        for _ in range(_WALK_STEPS):
            if evals >= budget or late():
                break
            xn, rn, un, sn, vn = floor(x + _WALK_STEP * tan)
            if un @ u < 0:
                un = -un
            if vn @ tan < 0:
                vn = -vn
            if float(np.sqrt(rn @ rn)) > 1e-3 or sn > 1e-2:
                break  # out of the valley
            curve.append(xn)
            gn = float(un @ rn)
            if (gn > 0.0) != (g > 0.0):  # a root between x and xn: regula falsi on the arc
                a, ga, b, gb = x, g, xn, gn
                m = xn
                for _ in range(40):
                    if evals >= budget or late():
                        break
                    w = ga / (ga - gb)
                    m, rm, um, _sm, _vm = floor(a + w * (b - a))
                    if um @ un < 0:
                        um = -um
                    gm = float(um @ rm)
                    if abs(gm) < 1e-15:
                        break
                    if (gm > 0.0) == (ga > 0.0):
                        a, ga = m, gm
                    else:
                        b, gb = m, gm
                roots.append(m)
            x, r, u, tan, g = xn, rn, un, vn, gn
    n = x0.shape[0]
    return np.array(roots).reshape(-1, n), np.array(curve).reshape(-1, n), evals


def _numerical(
    problem: IKProblem,
    n: int,
    ref: FloatArray,
    start_q: FloatArray | None,
    rng: np.random.Generator,
    min_distance: float | None,
    max_evals: int | None,
    time_limit: float | None,
    tol_pos: float,
    tol_rot: float,
    batch: int,
    max_starts: int | None,
    max_iters: int,
    patience: int,
    t0: float,
) -> _Found:
    """The numerical search: its solutions ``(q, dp, dr, evals when found, seconds when
    found)``, why it ended and the evaluations it spent (:class:`_Found`).

    Rounds of one compiled polish call each: the pending first-tier hop starts of the new
    branches, else the second-tier ones, else ``batch`` random starts (the first round: the
    reference start and ``batch − 1`` random ones).  Only starts the kernel polished to
    round-off (:data:`~swarm_ik.branches.ROUNDOFF_TOL`) count: a point that meets the
    tolerances but stalls above round-off lies in the valley of a near-singular target, not
    on a solution of the exact equations (such valleys made spurious "branches" before).
    """
    robot = problem.robot
    nq = robot.nq
    lower, upper = problem.lower, problem.upper
    periodic = periodic_mask(robot, lower, upper)
    revolute = revolute_mask(robot)
    starts_end = "budget"  # (a count of starts the caller gave is part of the budget)
    if max_starts is None and max_evals is None and time_limit is None:
        max_starts = 64 * n
        starts_end = "starts"
    pol = Polisher.from_problem(
        problem, lower, upper, tol_pos=ROUNDOFF_TOL, tol_rot=ROUNDOFF_TOL,
        wrap=robot.continuous_mask, max_iters=max_iters,
    )  # fmt: skip
    first = start_q if start_q is not None else 0.5 * (lower + upper)
    used = 0
    rows = None
    if problem.python_goals:  # (their row counts: one evaluation, counted)
        rows = int(pol.residual(first)[0].shape[0])
        used += 1
    elif problem.compiled_goals:
        rows = int(problem.table(None).rows_primary)
    redundant = _redundant(problem, rows)
    # a Python goal with its own tolerance is met within it, not within tol_pos
    own_tolerances = isinstance(problem.position_tolerances(tol_pos), np.ndarray)
    target_count = POOL_FACTOR * n if redundant else n
    hops = None if redundant else _hops_for(robot)
    bound = None
    if hops is not None and not problem.position_only and problem.single_pose:
        bound = hops.bound()
    if bound is not None:
        target_count = min(target_count, bound)
    fold = _Folder(lower, upper, revolute, periodic, ref)
    merge = BRANCH_TOL if min_distance is None else max(BRANCH_TOL, float(min_distance))
    kept: list[tuple[FloatArray, float, float, int, float]] = []
    # pending starts: valley-walk roots, first-tier hops, second-tier hops
    tiers = [np.empty((0, nq)), np.empty((0, nq)), np.empty((0, nq))]
    walks = 0
    walked = np.empty((0, nq))  # points of the valleys walked so far
    deadline = None
    if time_limit is not None:  # (what follows the rounds: the answers' results, a spread)
        reserve = _finish_per_solution(robot) * n
        deadline = t0 + time_limit - min(reserve, 0.5 * time_limit)
    n_starts = 0
    since_new = 0
    # seconds per evaluation, for the cap of a round under a time limit: this robot's last
    # measure for problems of this kind (3 µs, a Panda pose, at first: among obstacles an
    # evaluation takes several times that, and a first round capped at 3 µs each overran a
    # 1 ms limit by half of it, every call)
    per_eval = robot._cache.setdefault("many_eval_s", {})
    kind = (problem.collision_goal is not None, bool(problem.python_goals))
    measured = kind != (False, False)  # (a plain pose's rounds start at 3 µs, as measured)
    sec_per_eval = per_eval.get(kind, 3e-6) if measured else 3e-6
    round_s = 0.0  # a round's own time besides its compiled call [s] (measured)
    ended = "converged"  # (n found, or no new branch in its patience)
    closest: FloatArray | None = None  # the failed start nearest to meeting the goals
    closest_err = math.inf
    while len(kept) < target_count:
        raise_lost_ctrl_c()  # (one a kernel lost, counted by solve_many: raised here)
        t_round = time.perf_counter()
        if max_evals is not None and used >= max_evals:
            ended = "budget"
            break
        if deadline is not None and t_round + round_s >= deadline:
            ended = "time_limit"
            break
        if max_starts is not None and n_starts >= max_starts:
            ended = starts_end
            break
        room = 1 << 30 if max_starts is None else max_starts - n_starts
        starts = None
        n_hop = 0
        for t in range(3):  # pending starts not yet next to a known branch
            pend = tiers[t]
            if pend.shape[0]:
                pend = pend[fold.dist(pend) >= (merge if t == 0 else _HOP_SKIP)]
                take = min(room, 2 * batch)
                tiers[t] = pend[take:]
                if pend.shape[0]:
                    starts = pend[:take]
                    n_hop = starts.shape[0]
                    break
        if starts is None:
            if kept and since_new >= patience and not redundant:  # (a redundant arm's set
                # is a continuum: starts that do not converge are no sign that it is found;
                # its search ends at 4·n solutions or at the budget, as documented)
                break
            k = min(batch, room)
            starts = rng.uniform(lower, upper, size=(k, nq))
            if n_starts == 0:
                starts[0] = first
                n_hop = 1  # the first start is not a random one
        cap = 1 << 62 if max_evals is None else max_evals - used
        if deadline is not None:  # keep the compiled call within the time left
            left = deadline - time.perf_counter() - round_s
            cap = min(cap, max(8, int(0.8 * left / sec_per_eval)))
        t1 = time.perf_counter()
        out = pol.polish(starts, cap, stop_first=False, deadline=deadline)
        polish_s = time.perf_counter() - t1
        if out.used > 16:
            sec_per_eval = 0.5 * sec_per_eval + 0.5 * polish_s / out.used
            if measured:
                per_eval[kind] = sec_per_eval
        used += out.used
        ran = int(np.count_nonzero(out.status))
        n_starts += ran
        conv = np.flatnonzero(out.status[:ran] == CONVERGED)
        if not kept and ran:  # (what an empty answer's reason is read at: see solve_many)
            miss = out.position_error[:ran] + np.nan_to_num(out.rotation_error[:ran])
            k_min = int(np.argmin(miss))
            if miss[k_min] < closest_err:
                closest, closest_err = out.q[k_min].copy(), float(miss[k_min])
        cand, ok = fold(out.q[conv])
        conv, cand = conv[ok], cand[ok]
        fresh = fold.new(cand, merge)
        last_new = -1
        if fresh:
            qs = cand[fresh]
            dp, dr = pose_errors(problem, qs)  # Pinocchio's FK, as swarm_ik.verify reports it
            if own_tolerances:  # (a Python goal's own tolerance: each goal by its own)
                good = np.array([problem.is_success(q, tol_pos, tol_rot) for q in qs])
            else:
                good = (dp <= tol_pos) & ((dr <= tol_rot) | problem.position_only)
            now = time.perf_counter() - t0
            took = np.flatnonzero(good)[: target_count - len(kept)]
            for i in took:  # (the kernel's check disagreeing with Pinocchio's: never reported)
                kept.append((qs[i], float(dp[i]), float(dr[i]), used, now))
                last_new = max(last_new, int(conv[fresh[i]]))
            if took.shape[0]:
                fold.kept = np.vstack([fold.kept, qs[took]])
                if hops is not None and len(kept) < target_count:
                    for t, h in enumerate(hops(qs[took])):
                        h, h_ok = fold(h)
                        tiers[t + 1] = np.vstack([tiers[t + 1], h[h_ok]])
        if hops is not None and walks < _MAX_WALKS and len(kept) < target_count:
            # starts that stalled above round-off on a near-singular valley floor (small
            # error, tiny σ_min): walk the valley for the exact roots on it (once per valley)
            stalled = np.flatnonzero(
                (out.status[:ran] != CONVERGED)
                & (out.position_error[:ran] <= _WALK_ERR)
                & ((out.rotation_error[:ran] <= _WALK_ERR) | problem.position_only)
            )
            for i in stalled[:4]:
                room_evals = 1 << 62 if max_evals is None else max_evals - used
                if room_evals < 8 or (deadline is not None and time.perf_counter() >= deadline):
                    break
                qv = out.q[i]
                if walked.shape[0] and np.min(branch_distance(walked, qv, periodic)) < _WALK_NEAR:
                    continue
                used += 1
                jac = pol.residual(qv)[1]
                if jac.shape[0] != jac.shape[1]:  # (the walk follows the one-dimensional valley
                    continue  # of a square problem: a 3-joint arm's pose is not one, and crashed)
                if np.linalg.svd(jac, compute_uv=False)[-1] >= _WALK_SIGMA:
                    continue  # an ordinary local minimum
                roots, curve, evals = _valley_roots(pol, qv, lower, upper, deadline, room_evals - 1)
                used += evals
                walks += 1
                walked = np.vstack([walked, curve])
                if roots.shape[0]:
                    tiers[0] = np.vstack([tiers[0], roots])
                break
        if last_new >= 0:
            since_new = max(0, ran - max(last_new + 1, n_hop))
        else:
            since_new += max(0, ran - n_hop)
        round_s = max(time.perf_counter() - t_round - polish_s, 0.5 * round_s)
    if redundant:
        picks = spread_select(np.array([k[0] for k in kept]).reshape(-1, nq), n, periodic, ref)
        kept = [kept[i] for i in picks]
    return _Found(kept, ended, used, closest)
