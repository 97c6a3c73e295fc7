"""``analytic``: every IK branch of a decomposable 6R arm in microseconds, with eaik.

eaik (Ostermeier et al., "Automatic geometric decomposition for analytical inverse
kinematics", the ``eaik`` package; install the extra: ``pip install 'swarm_ik[analytic]'``)
solves 6R chains that reduce to geometric subproblems: a spherical wrist, three parallel axes
(UR arms, Unitree z1), two intersecting pairs, ….  The chain is handed to eaik in its
product-of-exponentials form, read from the reduced Pinocchio model at ``q = 0``:

* ``H`` (6, 3): the joint axes in the base frame (the angular rows of the WORLD joint
  Jacobian, so the URDF's axis signs and origins' rotations are taken as they are);
* ``P`` (7, 3): the offsets between consecutive joint origins in the base frame, the last one
  to the end-effector frame (the tool offset);
* ``R`` (3, 3): the end-effector orientation at ``q = 0``.

eaik then checks which decomposition applies (``has_known_decomposition``).  Each of its
solutions is brought into the limits by a 2π shift (the in-limit copy nearest to ``q0``, else
to the middle of the ranges) and kept when Pinocchio's FK meets the tolerances; duplicates
modulo 2π (branches that meet at a singularity) are merged.  A point of eaik's that misses the
pose (a least-squares one) is polished with the compiled Levenberg–Marquardt kernel, and
joins the set if that leads to a new solution: at a singular target eaik may return nothing
but such points (a UR wrist at ``q5 = 0`` has a continuum of solutions, ``q6`` free; eaik sets
it to 0 and misses the pose), and the set is then marked incomplete
(:attr:`ClosedFormSet.incomplete`; :func:`swarm_ik.solve_many` adds its numerical search
there).  For a generic target the set is eaik's complete one.  Chains eaik cannot decompose
(7 joints, prismatic joints, generic offsets) are refused with
:class:`AnalyticUnsupportedError` naming the reason; without eaik installed with
:class:`AnalyticUnavailableError` naming the extra.

>>> import swarm_ik
>>> from swarm_ik.solvers import analytic
>>> robot = swarm_ik.load_robot("ur5")
>>> problem = swarm_ik.IKProblem.from_q(robot, [0.3, -1.0, 1.2, -0.5, 1.1, 0.2])
>>> q, dp, dr = analytic.solve_all(problem)  # doctest: +SKIP
>>> q.shape  # doctest: +SKIP
(8, 6)
"""

from __future__ import annotations

import math
import sys
import weakref
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple

import numba
import numpy as np
import pinocchio as pin

from swarm_ik._types import BoolArray, FloatArray
from swarm_ik.branches import (
    BRANCH_TOL,
    ROUNDOFF_TOL,
    SINGULAR_SIGMA,
    TWO_PI,
    branch_distance,
    pose_errors,
    pose_errors_of,
    sigma_min,
    winding_bounds,
)
from swarm_ik.errors import SwarmIKError
from swarm_ik.kernels.joints import wrapped
from swarm_ik.solvers.base import Evaluator, register
from swarm_ik.solvers.hybrid import Polisher

if TYPE_CHECKING:
    from swarm_ik.problem import IKProblem
    from swarm_ik.robot import RobotModel


EXTRA_HINT = "pip install 'swarm_ik[analytic]' (or pip install eaik)"


class AnalyticUnavailableError(SwarmIKError, ImportError):
    """The analytic path needs eaik, which is not installed."""


class AnalyticUnsupportedError(SwarmIKError, ValueError):
    """The chain or problem has no analytic solution with eaik (the message says why)."""


def eaik_available() -> bool:
    """Whether eaik can be imported."""
    if "eaik.pybindings.EAIK" in sys.modules:
        return True
    try:
        import eaik.pybindings.EAIK  # noqa: F401
    except ImportError:
        return False
    return True


@dataclass(frozen=True, eq=False)
class AnalyticChain:
    """An eaik robot bound to one :class:`~swarm_ik.robot.RobotModel`.

    Attributes:
        solver: The ``eaik.pybindings.EAIK.Robot`` (``None`` when unsupported).
        reason: Why the chain is not supported (empty when it is).
        family: eaik's kinematic family, e.g. ``"6R-THREE_INNER_PARALLEL"``.
        H: Joint axes in the base frame at ``q = 0``, shape ``(nq, 3)``.
        P: Offsets between joint origins (and to the end effector), shape ``(nq + 1, 3)``.
        R: End-effector orientation at ``q = 0``, shape ``(3, 3)``.
    """

    solver: Any
    reason: str
    family: str
    H: FloatArray
    P: FloatArray
    R: FloatArray

    @property
    def supported(self) -> bool:
        """Whether eaik decomposes the chain."""
        return self.solver is not None


_CACHE: weakref.WeakKeyDictionary[Any, AnalyticChain] = weakref.WeakKeyDictionary()


def chain_geometry(robot: RobotModel) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(H, P, R)`` of the chain at ``q = 0``, in the base frame (see the module docstring).

    Args:
        robot: The robot.

    Returns:
        Axes ``(nq, 3)``, offsets ``(nq + 1, 3)`` [m], end-effector rotation ``(3, 3)``.
    """
    model = robot.model
    data = model.createData()
    q_pin = robot.to_pinocchio(np.zeros(robot.nq))
    jac = np.asarray(pin.computeJointJacobians(model, data, q_pin)).reshape(6, model.nv)
    pin.updateFramePlacements(model, data)
    axes = jac[3:].T.copy()
    origins = [np.zeros(3)] + [np.array(data.oMi[j].translation) for j in range(1, model.njoints)]
    ee = data.oMf[robot.ee_frame_id]
    origins.append(np.array(ee.translation))
    offsets = np.diff(np.asarray(origins), axis=0)
    return axes, offsets, np.array(ee.rotation)


def _describe(axes: FloatArray, offsets: FloatArray) -> str:
    """A short account of the chain's geometry for refusal messages."""
    n = axes.shape[0]
    par = [
        f"{i + 1}∥{j + 1}"
        for i in range(n)
        for j in range(i + 1, n)
        if np.linalg.norm(np.cross(axes[i], axes[j])) < 1e-9
    ]
    return "parallel axis pairs: " + (", ".join(par) if par else "none")


def analytic_chain(robot: RobotModel) -> AnalyticChain:
    """The (cached) eaik robot of ``robot``, or the reason it has none.

    Raises:
        AnalyticUnavailableError: eaik is not installed.
    """
    cached = _CACHE.get(robot)
    if cached is not None:
        return cached
    try:
        import eaik.pybindings.EAIK as eaik_core
    except ImportError:
        raise AnalyticUnavailableError(
            f"the analytic IK path needs eaik, which is not installed; {EXTRA_HINT}"
        ) from None
    empty = np.empty((0, 3))
    kinds = robot.joint_kinds
    if "prismatic" in kinds:
        j = kinds.index("prismatic")
        chain = AnalyticChain(
            None,
            f"joint {robot.joint_names[j]!r} is prismatic; eaik solves revolute chains only",
            "",
            empty,
            empty,
            np.eye(3),
        )
    elif robot.nq != 6:
        chain = AnalyticChain(
            None,
            f"{robot.name} has {robot.nq} joints; the analytic path solves 6-joint chains "
            "(a redundant arm has a continuum of solutions: use solve_many's numerical path)",
            "",
            empty,
            empty,
            np.eye(3),
        )
    elif robot.mimic or robot.model.nv != robot.nq:
        chain = AnalyticChain(
            None,
            f"{robot.name} has mimic joints that follow its solved ones; the analytic path "
            "solves chains of 6 independent joints (use solve_many's numerical path)",
            "",
            empty,
            empty,
            np.eye(3),
        )
    else:
        axes, offsets, rot = chain_geometry(robot)
        solver = eaik_core.Robot(axes.T.copy(), offsets.T.copy(), rot, [], True)
        family = str(solver.get_kinematic_family())
        if solver.has_known_decomposition():
            chain = AnalyticChain(solver, "", family, axes, offsets, rot)
        else:
            chain = AnalyticChain(
                None,
                f"eaik knows no decomposition of {robot.name}'s chain (family {family}; "
                f"{_describe(axes, offsets)}); it needs e.g. a spherical wrist or three "
                "parallel axes",
                family,
                axes,
                offsets,
                rot,
            )
    _CACHE[robot] = chain
    return chain


def support(problem: IKProblem) -> str:
    """Why ``problem`` cannot be solved analytically; the empty string when it can.

    Raises:
        AnalyticUnavailableError: eaik is not installed.
    """
    chain = analytic_chain(problem.robot)
    if not chain.supported:
        return chain.reason
    if getattr(problem, "target", None) is None:
        return "the problem has no single end-effector pose target"
    if problem.position_only:
        return "the problem is position-only; the analytic path solves full poses"
    from swarm_ik.goals import Pose

    goals = problem.goals
    if (
        len(goals) != 1
        or not isinstance(goals[0], Pose)
        or goals[0].frame != problem.robot.ee_frame
    ):
        return "the problem has goal terms beyond one end-effector pose"
    return ""


def pinocchio_errors(problem: IKProblem, qs: Any) -> tuple[FloatArray, FloatArray]:
    """Position [m] and rotation [rad] errors of each row of ``qs`` with Pinocchio's FK.

    The same computation as :func:`swarm_ik.verify` (``forwardKinematics`` +
    ``updateFramePlacement`` of the end-effector frame), without the per-call overheads: see
    :func:`swarm_ik.branches.pose_errors`.

    Args:
        problem: The IK problem (its robot and target).
        qs: Joint vectors, shape ``(k, nq)``.

    Returns:
        ``(dp (k,), dr (k,))``.
    """
    return pose_errors(problem, qs)


@numba.njit(cache=True)
def _fold_unique(
    qs: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    ref: FloatArray,
    tol2: float,
    out: FloatArray,
    key: FloatArray,
) -> int:  # pragma: no cover - compiled
    """The solutions' in-limit 2π copies nearest to ``ref``, joint by joint, without
    duplicates modulo 2π (squared wrapped distance below ``tol2``: the first one given is
    kept), sorted by squared distance to ``ref`` (into ``key``); returns how many were
    written to ``out``."""
    k, n = qs.shape
    c = 0
    inv = 1.0 / TWO_PI
    row = np.empty(n)
    for s in range(k):
        fits = True
        d2 = 0.0
        for j in range(n):
            q = qs[s, j]
            m_min = math.ceil((lo[j] - 1e-9 - q) * inv)
            m_max = math.floor((hi[j] + 1e-9 - q) * inv)
            if m_min > m_max:
                fits = False
                break
            m = min(max(round((ref[j] - q) * inv), m_min), m_max)
            v = min(max(q + TWO_PI * m, lo[j]), hi[j])
            row[j] = v
            d2 += (v - ref[j]) ** 2
        if not fits:
            continue
        dup = False
        for r in range(c):
            e2 = 0.0
            for j in range(n):
                e = wrapped(row[j] - out[r, j])
                e2 += e * e
            if e2 < tol2:
                dup = True
                break
        if dup:
            continue
        pos = c  # insertion by distance to the reference (stable)
        while pos > 0 and key[pos - 1] > d2:
            key[pos] = key[pos - 1]
            for j in range(n):
                out[pos, j] = out[pos - 1, j]
            pos -= 1
        key[pos] = d2
        for j in range(n):
            out[pos, j] = row[j]
        c += 1
    return c


def solve_all(
    problem: IKProblem,
    *,
    ref: Any = None,
    tol_pos: float = 1e-5,
    tol_rot: float = 1e-5,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The closed-form solutions of ``problem`` within its bounds, one in-limit representative
    of each branch: every branch for a generic target.

    eaik's solutions (exact ones first) are brought into the limits as their 2π copies nearest
    to ``ref``, joint by joint; duplicates modulo 2π (two branches meeting at a singularity,
    within :data:`~swarm_ik.branches.BRANCH_TOL`) are merged, and each one left is verified
    with Pinocchio's own FK (``forwardKinematics`` + ``updateFramePlacement``, ≈ 1.3 µs a
    solution) against the tolerances.  The folding, merging and sorting run in one compiled
    call, the eaik robot is cached per :class:`~swarm_ik.robot.RobotModel`.  eaik's points
    that fail the check (its least-squares ones) are polished into solutions where they lead
    to one (:func:`closed_form_set`): at a singular target with a continuum of solutions (a
    UR wrist at ``q5 = 0``) eaik returns only such points, and the set then holds the
    representatives the polish reached, not the whole continuum.

    Args:
        problem: A full-pose IK problem of a chain eaik decomposes.
        ref: Reference configuration ``(nq,)``: each branch is returned as its in-limit copy
            (modulo 2π) nearest to it; default the middle of the bounds.
        tol_pos: Position tolerance [m] a solution must meet (Pinocchio's FK).
        tol_rot: Rotation tolerance [rad].

    Returns:
        ``(q (k, nq), position errors (k,), rotation errors (k,))``, sorted by distance to
        ``ref``; ``k = 0`` when the pose is out of reach or no branch fits the limits.

    Raises:
        AnalyticUnavailableError: eaik is not installed.
        AnalyticUnsupportedError: the chain or problem is not solvable analytically.
    """
    cf = _checked_set(problem, ref, tol_pos, tol_rot)
    return cf.q, cf.position_error, cf.rotation_error


def _checked_set(
    problem: IKProblem, ref: Any, tol_pos: float, tol_rot: float, max_evals: int | None = None
) -> ClosedFormSet:
    """:func:`closed_form_set` after :func:`support`'s check (``ref`` None: the middle of the
    bounds)."""
    reason = support(problem)
    if reason:
        raise AnalyticUnsupportedError(f"no analytic IK for this problem: {reason}")
    lo, hi = problem.lower, problem.upper
    center = 0.5 * (lo + hi) if ref is None else np.asarray(ref, dtype=float)
    return closed_form_set(problem, center, tol_pos, tol_rot, max_evals)


def solve_supported(
    problem: IKProblem, ref: FloatArray, tol_pos: float, tol_rot: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """:func:`solve_all` without its checks, for a problem :func:`support` accepted;
    ``ref`` ``(nq,)`` is required.  :func:`closed_form_set` says more (whether the set is
    known to miss solutions)."""
    cf = closed_form_set(problem, ref, tol_pos, tol_rot)
    return cf.q, cf.position_error, cf.rotation_error


class ClosedFormSet(NamedTuple):
    """What :func:`closed_form_set` returns.

    Attributes:
        q: The solutions, shape ``(k, nq)``, each an in-limit copy, nearest to the reference
            first.
        position_error: Their position errors with Pinocchio's FK [m], ``(k,)``.
        rotation_error: Their rotation errors [rad], ``(k,)``.
        incomplete: True when the set cannot be taken as complete: a point eaik returned as
            a least-squares one (or an exact one that failed the check) was polished into a
            solution eaik did not give, at a singular configuration (smallest Jacobian
            singular value below :data:`SINGULAR_SIGMA`), as at a target with a continuum of
            solutions (a UR wrist at ``q5 = 0`` or ``π``), of which the set then holds only
            the representatives the polish reached; or none of eaik's points polished into
            a solution while one lay at a singular configuration (the joint limits of a
            ``ur5_joint_limited_robot`` can hold its polish back: the set then holds what
            the polish from points along the self-motion reached, if anything).  False
            does not prove the set complete: it is eaik's set (with any non-singular
            solution the polish recovered), complete for a generic target.
        evals: FK + Jacobian evaluations the polish spent (0 when eaik's points needed none).
    """

    q: FloatArray
    position_error: FloatArray
    rotation_error: FloatArray
    incomplete: bool
    evals: int


POLISH_ITERS = 30
"""Evaluations a polish of one of eaik's least-squares points may spend (:func:`closed_form_set`;
those that reach a solution took 3–10 on UR5 targets, those of an unreachable branch stalled
in 4–12)."""


def closed_form_set(
    problem: IKProblem,
    ref: FloatArray,
    tol_pos: float,
    tol_rot: float,
    max_evals: int | None = None,
) -> ClosedFormSet:
    """The closed-form set of a problem :func:`support` accepted (the per-call path of
    :func:`solve_all` and :func:`swarm_ik.solve_many`); ``ref`` ``(nq,)`` is required.

    eaik's solutions, exact ones first, are folded into the limits (their 2π copies nearest to
    ``ref``), merged modulo 2π and checked with Pinocchio's FK against the tolerances.  Each of
    eaik's points that is no solution so kept (a least-squares one, or an exact one that
    failed the check) is then polished with the compiled Levenberg–Marquardt kernel towards
    round-off (:data:`~swarm_ik.branches.ROUNDOFF_TOL`, at most :data:`POLISH_ITERS`
    evaluations each): at a singular target eaik may return only least-squares points (a UR
    wrist at ``q5 = 0``: ``q6`` is free, eaik sets it to 0 and the pose misses).  A polished
    point that meets the tolerances (checked with Pinocchio as well; near a singular target,
    ``q5 = 1e-9``, it may stall there above round-off) and is a new solution modulo 2π joins
    the set, which is then marked ``incomplete`` if that solution is singular.  An unreachable
    branch's least-squares point stalls within a few evaluations (the polish costs ≈ 45 µs
    where eaik returns such points: about a quarter of random UR5 targets).  ``max_evals``
    bounds the polish's evaluations in all (None: :data:`POLISH_ITERS` per point); points it
    leaves unpolished are not solutions.

    Returns:
        A :class:`ClosedFormSet`; empty when the pose is out of reach or no solution fits the
        limits.
    """
    robot = problem.robot
    chain = _CACHE.get(robot) or analytic_chain(robot)
    lo, hi = problem.lower, problem.upper
    target = problem.target
    assert target is not None  # support() accepted the problem: one pose target
    sol = chain.solver.calculate_IK(target)
    nq = lo.shape[0]
    qs = np.asarray(sol.Q, dtype=float).reshape(-1, nq)
    k = qs.shape[0]
    if k == 0:
        return ClosedFormSet(np.empty((0, nq)), np.empty(0), np.empty(0), False, 0)
    out = np.empty((k, nq))
    key = np.empty(k)
    # eaik's exact solutions first, then its least-squares ones: at a singularity (UR5's
    # straight elbow, its home pose among them) two branches merge and eaik calls the exact
    # solution least squares (solve_many found none there); one that folds onto an exact
    # solution is its duplicate, and the check below drops those that miss the pose
    order = np.argsort(np.asarray(sol.is_LS, dtype=bool).reshape(-1), kind="stable")
    c = _fold_unique(
        np.ascontiguousarray(qs[order]), lo, hi, ref, BRANCH_TOL * BRANCH_TOL, out, key
    )
    # the check: Pinocchio's own FK of each branch left
    m = robot.fk_pinocchio_many(out[:c])
    dp, dr = pose_errors_of(m, problem.goals[0])  # bit for bit as swarm_ik.verify
    good = (dp <= tol_pos) & (dr <= tol_rot)
    if c == k and good.all():  # (the generic target: eaik's exact set, nothing to polish)
        return ClosedFormSet(out, dp, dr, False, 0)
    cf = _polished_set(problem, qs, out[:c], good, dp, dr, ref, tol_pos, tol_rot, max_evals)
    return _with_continuum(problem, cf, ref, tol_pos, tol_rot, max_evals)


def _polished_set(
    problem: IKProblem,
    qs: FloatArray,
    folded: FloatArray,
    good: BoolArray,
    dp: FloatArray,
    dr: FloatArray,
    ref: FloatArray,
    tol_pos: float,
    tol_rot: float,
    max_evals: int | None,
) -> ClosedFormSet:
    """The set of a target whose eaik points are not all exact solutions (:func:`closed_form_set`):
    ``folded`` the distinct in-limit copies of eaik's points ``qs``, ``good`` (with errors
    ``dp``, ``dr``) those that met the check; the others, and eaik's points with no in-limit
    copy, polished into solutions."""
    robot = problem.robot
    lo, hi = problem.lower, problem.upper
    sols, dps, drs = folded[good], dp[good], dr[good]
    # the polish's starts: the points that failed the check, and those with no in-limit copy
    # (clipped into the limits: a continuum may reach into them elsewhere)
    starts = folded[~good]
    if folded.shape[0] < qs.shape[0]:
        starts = np.vstack([starts, _clipped_misfits(qs, lo, hi, ref)])
    if starts.shape[0] == 0:
        return ClosedFormSet(sols, dps, drs, False, 0)
    found, evals = _polish(problem, starts, tol_pos, tol_rot, max_evals)
    # no solution at all, and eaik's points at a singular configuration (held back by the
    # limits, say): a continuum may hide solutions there (a generic target's least-squares
    # points, its branches out of reach, often lie at the straight elbow too: they mark
    # nothing while the set holds solutions)
    missed = (
        sols.shape[0] == 0
        and found.shape[0] == 0
        and any(sigma_min(robot, q) < SINGULAR_SIGMA for q in starts)
    )
    if missed:  # the polish again from points along each singular start's self-motion
        moved = _self_motion_starts(robot, starts, lo, hi, ref)
        if moved.shape[0]:
            left = None if max_evals is None else max_evals - evals
            found, more = _polish(problem, moved, tol_pos, tol_rot, left)
            evals += more
    if found.shape[0] == 0:
        return ClosedFormSet(sols, dps, drs, missed, evals)
    cf = _joined(
        problem, ClosedFormSet(sols, dps, drs, missed, evals), found, ref, tol_pos, tol_rot
    )
    incomplete = cf.incomplete or any(  # a new solution at a singular configuration (a
        sigma_min(robot, q) < SINGULAR_SIGMA  # sample of a continuum?)
        for q in cf.q
        if not _is_among(q, sols)
    )
    return cf._replace(incomplete=incomplete)


def _joined(
    problem: IKProblem,
    cf: ClosedFormSet,
    found: FloatArray,
    ref: FloatArray,
    tol_pos: float,
    tol_rot: float,
) -> ClosedFormSet:
    """``cf`` with the polished points ``found`` ``(m, nq)`` that are new solutions modulo 2π
    (folded into the limits nearest ``ref``, checked with Pinocchio's FK against the
    tolerances)."""
    lo, hi = problem.lower, problem.upper
    both = np.vstack([cf.q, found])
    out = np.empty_like(both)
    c = _fold_unique(both, lo, hi, ref, BRANCH_TOL * BRANCH_TOL, out, np.empty(both.shape[0]))
    if c == cf.q.shape[0]:  # every polished point a known solution
        return cf
    dp, dr = pose_errors_of(problem.robot.fk_pinocchio_many(out[:c]), problem.goals[0])
    ok = (dp <= tol_pos) & (dr <= tol_rot)
    return cf._replace(q=out[:c][ok], position_error=dp[ok], rotation_error=dr[ok])


CONTINUUM_GAP = 1e-2
"""Joint distance [rad / m, modulo 2π] from every solution of a closed-form set beyond which a
point polished from a step along a singular solution's self-motion is a new sample of a
continuum (:func:`_with_continuum`); nearer, it is the polish stopping beside an isolated
double root (a straight elbow: a few 1e-6 rad from it)."""


def _with_continuum(
    problem: IKProblem,
    cf: ClosedFormSet,
    ref: FloatArray,
    tol_pos: float,
    tol_rot: float,
    max_evals: int | None,
) -> ClosedFormSet:
    """``cf``, or, where one of its solutions lies at a singular configuration from which a
    step along the self-motion (:func:`_self_motion_starts`) polishes into a new solution, a
    sample of a continuum (exact to round-off and farther than :data:`CONTINUUM_GAP` from
    each solution): ``cf``
    with the new ones joined and marked incomplete.  A UR arm's
    home pose (wrist and elbow straight at once) is such a target: eaik returns two exact
    points of the wrist's continuum there and nothing else marks the set.  Run where eaik's
    set was not taken as it came (a least-squares point, or one that failed the check)."""
    if cf.incomplete or cf.q.shape[0] == 0:
        return cf
    moved = _self_motion_starts(problem.robot, cf.q, problem.lower, problem.upper, ref)
    if moved.shape[0] == 0:
        return cf
    left = None if max_evals is None else max_evals - cf.evals
    found, more = _polish(problem, moved, tol_pos, tol_rot, left)
    cf = cf._replace(evals=cf.evals + more)
    if found.shape[0]:  # (exact points only: beside a near-singular target the polish
        # stalls on a valley floor within the tolerances, no solution of a continuum)
        dp, dr = pose_errors_of(problem.robot.fk_pinocchio_many(found), problem.goals[0])
        found = found[(dp <= 10 * ROUNDOFF_TOL) & (dr <= 10 * ROUNDOFF_TOL)]
    every = np.ones(cf.q.shape[1], dtype=bool)
    new = [q for q in found if float(branch_distance(cf.q, q, every).min()) > CONTINUUM_GAP]
    if not new:
        return cf
    return _joined(problem, cf, np.array(new), ref, tol_pos, tol_rot)._replace(incomplete=True)


SELF_MOTION_SHIFTS = (-1.5, -1.0, -0.5, 0.5, 1.0, 1.5)
"""Shifts [π rad on the joint that moves most] along a singular start's self-motion from
which :func:`closed_form_set` polishes again when no start led to a solution."""


def _self_motion_starts(
    robot: Any, starts: FloatArray, lo: FloatArray, hi: FloatArray, ref: FloatArray
) -> FloatArray:
    """Starts moved along the self-motion of each singular start: ``q + t·π·n`` for ``t`` in
    :data:`SELF_MOTION_SHIFTS`, ``n`` the right singular vector of the frame Jacobian's
    smallest singular value (below :data:`SINGULAR_SIGMA`), scaled to a largest entry of 1,
    each folded into the limits as its 2π copy nearest ``ref`` (or clipped where it has
    none), duplicates merged: ``(m, nq)``.

    At a straight UR wrist (``q5 = 0``) ``n`` turns joints 4 and 6 against each other, the
    continuum of solutions; eaik sets ``q6 = 0`` there and the polish from that point can be
    held back by the limits (``ur5_joint_limited_robot``: every start stalled, where a point
    of the continuum half a turn away lies within them)."""
    moved: list[FloatArray] = []
    for q in starts:
        _, sv, vt = np.linalg.svd(robot.jacobian_pinocchio(q))
        if sv[-1] >= SINGULAR_SIGMA:
            continue
        n = vt[-1] / np.abs(vt[-1]).max()
        moved.extend(q + (t * math.pi) * n for t in SELF_MOTION_SHIFTS)
    if not moved:
        return np.empty((0, lo.shape[0]))
    qs = np.ascontiguousarray(moved)
    out = np.empty_like(qs)
    c = _fold_unique(qs, lo, hi, ref, BRANCH_TOL * BRANCH_TOL, out, np.empty(qs.shape[0]))
    return np.ascontiguousarray(np.vstack([out[:c], _clipped_misfits(qs, lo, hi, ref)]))


def _is_among(q: FloatArray, qs: FloatArray) -> bool:
    """Whether ``q`` is a row of ``qs`` modulo 2π on every joint (within
    :data:`~swarm_ik.branches.BRANCH_TOL`)."""
    every = np.ones(q.shape[0], dtype=bool)
    return bool(qs.shape[0]) and float(branch_distance(qs, q, every).min()) < BRANCH_TOL


def _clipped_misfits(qs: FloatArray, lo: FloatArray, hi: FloatArray, ref: FloatArray) -> FloatArray:
    """The rows of ``qs`` with no in-limit 2π copy (on some joint), each as its copy nearest
    to ``ref`` clipped into the limits, ``(m, nq)``."""
    m_min, m_max = winding_bounds(qs, lo, hi, np.ones(qs.shape[1], dtype=bool))  # (revolute)
    misfit = (m_min > m_max).any(axis=1)
    if not misfit.any():
        return np.empty((0, qs.shape[1]))
    rows = qs[misfit]
    return np.clip(rows + TWO_PI * np.round((ref - rows) / TWO_PI), lo, hi)


def _polish(
    problem: IKProblem,
    starts: FloatArray,
    tol_pos: float,
    tol_rot: float,
    max_evals: int | None = None,
) -> tuple[FloatArray, int]:
    """``starts`` ``(m, nq)`` polished towards round-off with the compiled LM kernel within
    the problem's bounds: ``(the points that ended within the tolerances (k, nq), evaluations
    spent)``.  Near a singular target a start may stall on the floor of a valley of tiny
    residual above round-off (a UR wrist at ``q5 = 1e-9``), within the tolerances: such a
    point is kept too (the caller checks each one with Pinocchio).  At most ``max_evals``
    evaluations in all (None: :data:`POLISH_ITERS` per start)."""
    budget = POLISH_ITERS * starts.shape[0]
    if max_evals is not None:
        budget = min(budget, max_evals)
    if budget <= 0:
        return np.empty((0, starts.shape[1])), 0
    pol = Polisher.from_problem(
        problem, tol_pos=ROUNDOFF_TOL, tol_rot=ROUNDOFF_TOL,
        wrap=problem.robot.continuous_mask, max_iters=POLISH_ITERS,
    )  # fmt: skip
    res = pol.polish(starts, budget, stop_first=False)
    met = (res.position_error <= tol_pos) & (res.rotation_error <= tol_rot)
    return np.ascontiguousarray(res.q[met]), int(res.used)


def fitness_of_errors(
    problem: IKProblem, qs: FloatArray, dp: FloatArray, dr: FloatArray
) -> list[float]:
    """The fitness of each solution: for the ``"se3"`` fitness of one pose goal (the analytic
    path's problems) ``dp + w_rot·dr`` from the given Pinocchio errors (the compiled cost
    computes the same sum from its own FK, equal to round-off), else :meth:`IKProblem.fitness`.
    """
    goals = problem.goals
    if problem.fitness_name == "se3" and len(goals) == 1 and bool(problem.primary[0]):
        return (dp + problem.w_rot * dr).tolist()
    return problem.fitness(qs).tolist() if qs.shape[0] else []


def run(ev: Evaluator, rng: np.random.Generator) -> None:
    """Solver ``analytic``: the closed-form branches with eaik (:func:`closed_form_set`, its
    least-squares points polished where they lead to a solution); the answer is the one
    nearest to ``q0`` (else to the middle of the bounds).  One evaluation per branch verified,
    plus the polish's (within the budget).

    Raises:
        AnalyticUnavailableError: eaik is not installed.
        AnalyticUnsupportedError: the chain or problem is not solvable analytically.
    """
    problem = ev.problem
    if problem is None:
        raise AnalyticUnsupportedError("solver 'analytic' needs an IK problem, not an objective")
    tol_pos, tol_rot = ev.tolerance if ev.tolerance is not None else (1e-5, 1e-5)
    # (the polish within the budget, less the evaluation that records the answer)
    polish = None if ev.max_evals is None else max(ev.remaining - 1, 0)
    cf = _checked_set(problem, ev.q0, tol_pos, tol_rot, polish)
    qs, dp, dr = cf.q, cf.position_error, cf.rotation_error
    if qs.shape[0]:
        ev.record(qs[:1], np.array(fitness_of_errors(problem, qs[:1], dp[:1], dr[:1])))
    more = max(qs.shape[0] - 1, 0) + cf.evals
    if more and ev.remaining > 0:
        ev.add_evals(min(more, ev.remaining))
    ev.end_iteration()


register(
    "analytic",
    run,
    description="closed-form IK of decomposable 6R arms with eaik (extra 'analytic')",
    needs_jacobian=True,
    closed_form=True,
)
