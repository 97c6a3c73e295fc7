"""IK branches: when two solutions are the same, and the in-limit copies of a solution.

A revolute joint turned by 2π puts every link back where it was, so ``q`` and ``q + 2π·e_j``
reach the same pose.  For a joint whose range is shorter than 2π at most one copy lies within
the limits, but a *periodic* joint (continuous, or revolute with a range of at least 2π, as the
±2π joints of the UR arms) has several in-limit copies of one configuration.  Counting them as
different solutions inflates the "solution set" of a UR5 from 8 to up to 8 × 2⁵.

This module defines:

* :func:`periodic_mask`: the joints on which distances are taken modulo 2π;
* :func:`branch_distance`: the joint-space distance with those differences wrapped to
  ``[-π, π)``;
* :func:`same_branch` / :class:`BranchSet`: two solutions are one branch when, polished to
  round-off, their wrapped distance is below :data:`BRANCH_TOL`;
* :func:`windings` and :func:`nearest_winding`: the in-limit 2π copies of a configuration and
  the one nearest to a reference (``q0``, else the middle of the ranges);
* :func:`spread_select` and :func:`covering_radius`: farthest-point selection on the
  self-motion manifolds of redundant arms, and how well a selection covers a pool.

Why ``BRANCH_TOL = 1e-6`` rad: a solution polished to round-off (pose error ~1e-15) is within
``~1e-15 / σ_min(J)`` of the exact solution; even at ``σ_min = 1e-6`` (a configuration a
micro-radian from a singularity) that is 1e-9 rad, three orders below the tolerance.  Two
*distinct* branches of a 6R arm are at least 1e-6 rad apart unless the target lies within
~1e-12 (in the squared distance to the singular set) of the singularity where they meet, where
they are numerically the same configuration anyway.  A coarser threshold merges real branches:
near a straight elbow two branches of a UR5 are only 0.065 rad apart.
"""

from __future__ import annotations

import itertools
import math
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from swarm_ik._types import BoolArray, FloatArray
from swarm_ik.errors import InvalidArgumentError
from swarm_ik.kernels import lie
from swarm_ik.periodic import (  # noqa: F401 (the names this module's users import from it)
    _LIMIT_SLACK,
    TWO_PI,
    nearest_winding,
    periodic_mask,
    winding_bounds,
)
from swarm_ik.problem import largest_errors

if TYPE_CHECKING:
    from swarm_ik.problem import IKProblem
    from swarm_ik.robot import RobotModel


BRANCH_TOL = 1e-6
"""Two solutions polished to round-off are one branch when their wrapped joint distance
(Euclidean, rad / m) is below this (see the module docstring for why 1e-6)."""
ROUNDOFF_TOL = 1e-12
"""Pose error (m and rad) a solution is polished to before it is compared."""
SINGULAR_SIGMA = 1e-4
"""A configuration whose frame Jacobian's smallest singular value (:func:`sigma_min`) is
below this lies at a singularity, where a continuum of solutions may be: a closed-form set
holding such a solution is not taken as complete (:mod:`swarm_ik.solvers.analytic`,
:func:`swarm_ik.path.solve_path`'s certificate)."""


def sigma_min(robot: RobotModel, q: Any) -> float:
    """The smallest singular value of the first goal frame's Jacobian at ``q`` (Pinocchio)."""
    return float(np.linalg.svd(robot.jacobian_pinocchio(q), compute_uv=False)[-1])


def revolute_mask(robot: RobotModel) -> BoolArray:
    """Revolute and continuous joints (the ones with a 2π period), shape ``(nq,)``."""
    return np.array([k != "prismatic" for k in robot.joint_kinds], dtype=bool)


def wrapped_delta(a: Any, b: Any, periodic: BoolArray) -> FloatArray:
    """``a − b`` with the periodic joints' differences wrapped to ``[-π, π)``.

    Args:
        a: Joint vectors, shape ``(..., nq)``.
        b: Joint vector(s), broadcastable to ``a``.
        periodic: Mask, shape ``(nq,)``.
    """
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    if periodic.any():
        d[..., periodic] = (d[..., periodic] + np.pi) % TWO_PI - np.pi
    return d


def branch_distance(a: Any, b: Any, periodic: BoolArray) -> FloatArray:
    """Euclidean joint distance modulo 2π on the periodic joints: ``(..., nq) → (...)``."""
    d = wrapped_delta(a, b, periodic)
    return np.asarray(np.sqrt(np.einsum("...i,...i->...", d, d)))


def windings(q: Any, lower: Any, upper: Any, periodic: BoolArray) -> FloatArray:
    """Every in-limit 2π copy of one configuration.

    Args:
        q: Joint vector, shape ``(nq,)``.
        lower, upper: Bounds, shape ``(nq,)``.
        periodic: Joints with a 2π period (:func:`periodic_mask`, or all revolute joints),
            shape ``(nq,)``; other joints keep their value.

    Returns:
        The copies, shape ``(c, nq)``, in lexicographic order of the shifts (``(0, nq)`` when
        some joint has no in-limit value).  A UR5 configuration has up to 2⁵ copies: five joints
        with ±2π limits, the elbow within ±π.
    """
    q = np.asarray(q, dtype=float)
    m_min, m_max = winding_bounds(q, lower, upper, periodic)
    if np.any(m_min > m_max):
        return np.empty((0, q.shape[0]))
    ranges = [range(int(a), int(b) + 1) for a, b in zip(m_min, m_max, strict=True)]
    shifts = np.array(list(itertools.product(*ranges)), dtype=float).reshape(-1, q.shape[0])
    return np.clip(q + TWO_PI * shifts, lower, upper)


# --------------------------------------------------------------------- verification
def pose_errors(problem: IKProblem, qs: Any) -> tuple[FloatArray, FloatArray]:
    """Largest primary position [m] and angular [rad] errors of each row of ``qs`` with
    Pinocchio's own FK, as :func:`swarm_ik.verify` reports them.

    A single-pose problem (one primary :class:`~swarm_ik.goals.Pose` or
    :class:`~swarm_ik.goals.Position` goal) takes the direct route:
    ``pinocchio.forwardKinematics`` + ``updateFramePlacement`` of the goal frame per row
    (≈ 1.3 µs each on a UR5) and the errors of all rows in a few vectorised NumPy operations;
    any other problem calls :func:`swarm_ik.verify` row by row.

    Args:
        problem: The IK problem.
        qs: Joint vectors, shape ``(k, nq)``.

    Returns:
        ``(dp (k,), dr (k,))``; ``dr`` is 0 for a position-only goal.
    """
    from swarm_ik.goals import Pose, Position

    qs = np.asarray(qs, dtype=float).reshape(-1, problem.nq)
    goal = problem.goals[0] if len(problem.goals) == 1 else None
    if not isinstance(goal, (Pose, Position)) or not goal.primary:
        errs = np.array([largest_errors(problem.verify(q)) for q in qs]).reshape(-1, 2)
        return errs[:, 0].copy(), errs[:, 1].copy()
    m = problem.robot.fk_pinocchio_many(qs, goal.frame)
    return pose_errors_of(m, goal)


def pose_errors_of(m: FloatArray, goal: Any) -> tuple[FloatArray, FloatArray]:
    """Errors of the poses ``m`` ``(k, 4, 4)`` against one Pose / Position goal, bit for bit
    as the goal's own ``errors`` computes them for one pose (a Pose: the offset's norm as the
    in-order sum of squares, :func:`swarm_ik.kernels.lie.relative_angles`, the batched twin of
    ``Pose.errors``' :func:`~swarm_ik.kernels.lie.angle_between`), so that a
    :class:`Result`'s errors equal :func:`swarm_ik.verify`'s.
    """
    k = m.shape[0]
    if not goal.exact:
        return goal.pose_errors(m)  # type: ignore[no-any-return]  # (the bounded forms' own)
    if not hasattr(goal, "target"):  # a Position goal
        d = m[:, :3, 3] - goal.point
        return np.array([math.sqrt(x.dot(x)) for x in d]), np.zeros(k)
    target = goal.target
    d = m[:, :3, 3] - target[:3, 3]
    dp = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2])  # (Pose.errors')
    return dp, lie.relative_angles(target[:3, :3], m[:, :3, :3])


# ----------------------------------------------------------------------- polishing
def refine(
    problem: IKProblem, q: Any, *, iters: int = 8, tol: float = ROUNDOFF_TOL
) -> tuple[FloatArray, float, float]:
    """Gauss–Newton on Pinocchio's FK until the pose error reaches round-off.

    Minimum-norm steps (``lstsq`` of the ``LOCAL`` frame Jacobian against ``log6``), so it also
    works on redundant arms and converges quadratically near (not at) singularities, where a
    damped polish crawls.  A step that would leave the bounds or not reduce the error ends it.

    Args:
        problem: The IK problem (its robot, target, bounds).
        q: Start, shape ``(nq,)``, close to a solution.
        iters: Most Gauss–Newton steps.
        tol: Stop when both errors are below this (m, rad).

    Returns:
        ``(q, position error [m], rotation error [rad])`` of the best point.
    """
    robot = problem.robot
    model, data, fid = robot.model, robot.model.createData(), robot.ee_frame_id
    target = problem.target
    if target is None:
        raise InvalidArgumentError("refine needs a single-pose problem (one target)")
    o_m_t = pin.SE3(target[:3, :3].copy(), target[:3, 3].copy())
    lo, hi = problem.lower, problem.upper
    best = np.array(q, dtype=float)

    def errors(qq: FloatArray) -> tuple[float, float, Any, FloatArray]:
        qp = robot.to_pinocchio(qq)
        pin.forwardKinematics(model, data, qp)
        pin.updateFramePlacement(model, data, fid)
        m = data.oMf[fid]
        dp = float(np.linalg.norm(m.translation - o_m_t.translation))
        dr = (
            0.0
            if problem.position_only
            else float(np.linalg.norm(pin.log3(m.rotation.T @ o_m_t.rotation)))
        )
        return dp, dr, m, qp

    dp, dr, m, qp = errors(best)
    for _ in range(iters):
        if dp <= tol and dr <= tol:
            break
        jac = np.asarray(pin.computeFrameJacobian(model, data, qp, fid, pin.ReferenceFrame.LOCAL))
        jac = jac.reshape(6, model.nv)
        err = pin.log6(m.actInv(o_m_t)).vector
        if problem.position_only:
            err = m.rotation.T @ (o_m_t.translation - m.translation)
            jac = jac[:3]
        step = np.linalg.lstsq(jac, err, rcond=None)[0]
        cand = robot.wrap(robot.from_pinocchio(pin.integrate(model, qp, step)))
        if np.any(cand < lo - _LIMIT_SLACK) or np.any(cand > hi + _LIMIT_SLACK):
            break
        cand = np.clip(cand, lo, hi)
        dp2, dr2, m2, qp2 = errors(cand)
        if max(dp2, dr2) >= max(dp, dr):
            break
        best, dp, dr, m, qp = cand, dp2, dr2, m2, qp2
    return best, dp, dr


def polish_to_roundoff(problem: IKProblem, q: Any) -> tuple[FloatArray, float, float]:
    """Polish one solution to round-off: the compiled LM of ``swarm`` at tolerance
    :data:`ROUNDOFF_TOL`, then :func:`refine` if it stopped short.

    Args:
        problem: The IK problem.
        q: A solution (or near-solution), shape ``(nq,)``, within the bounds.

    Returns:
        ``(q, position error [m], rotation error [rad])``, errors from Pinocchio's FK.
    """
    from swarm_ik.solvers.hybrid import Polisher

    pol = Polisher.from_problem(
        problem, problem.lower, problem.upper, tol_pos=ROUNDOFF_TOL, tol_rot=ROUNDOFF_TOL
    )
    out = pol.polish(np.asarray(q, dtype=float)[None], 64, stop_first=True)
    return refine(problem, out.q[0])


def same_branch(
    problem: IKProblem,
    qa: Any,
    qb: Any,
    *,
    tol: float = BRANCH_TOL,
    periodic: BoolArray | None = None,
) -> bool:
    """Whether two solutions of ``problem`` are the same IK branch.

    Both are polished to round-off (:func:`polish_to_roundoff`), then compared with
    :func:`branch_distance` modulo 2π on the periodic joints (default
    :func:`periodic_mask` of the problem's bounds) against ``tol``.

    Args:
        problem: The IK problem both solve.
        qa, qb: Solutions, shape ``(nq,)``.
        tol: Branch tolerance (rad / m); see :data:`BRANCH_TOL`.
        periodic: Mask of the periodic joints, shape ``(nq,)``.
    """
    mask = (
        periodic_mask(problem.robot, problem.lower, problem.upper) if periodic is None else periodic
    )
    a = polish_to_roundoff(problem, qa)[0]
    b = polish_to_roundoff(problem, qb)[0]
    return bool(branch_distance(a, b, mask) < tol)


class BranchSet:
    """Distinct branches found so far (solutions already polished to round-off).

    Args:
        periodic: Periodic joints, shape ``(nq,)``.
        tol: Branch tolerance (:data:`BRANCH_TOL`).
        min_distance: Optional coarser filter: a solution within this wrapped distance of a
            kept one is dropped as well (``None``: branches only).
    """

    def __init__(
        self, periodic: BoolArray, tol: float = BRANCH_TOL, min_distance: float | None = None
    ) -> None:
        self.periodic = periodic
        self.tol = float(tol)
        self.min_distance = None if min_distance is None else float(min_distance)
        self.q: list[FloatArray] = []

    def __len__(self) -> int:
        return len(self.q)

    def nearest(self, q: FloatArray) -> tuple[int, float]:
        """Index of and distance to the nearest kept branch (``(-1, inf)`` when empty)."""
        if not self.q:
            return -1, float("inf")
        d = branch_distance(np.asarray(self.q), q, self.periodic)
        i = int(np.argmin(d))
        return i, float(d[i])

    def add(self, q: FloatArray) -> bool:
        """Keep ``q`` if it is a new branch (and farther than ``min_distance``); returns
        whether it was kept."""
        _i, d = self.nearest(q)
        limit = self.tol if self.min_distance is None else max(self.tol, self.min_distance)
        if d < limit:
            return False
        self.q.append(np.array(q, dtype=float))
        return True


# ------------------------------------------------------------------ redundant arms
def spread_select(pool: Any, k: int, periodic: BoolArray, ref: Any) -> list[int]:
    """Farthest-point selection of ``k`` of the ``pool`` solutions.

    The first pick is the solution nearest to ``ref`` (``q0``, else the middle of the ranges);
    each next pick is the pool solution whose wrapped distance to the nearest pick is largest.
    This greedy rule covers the pool within twice the best covering radius possible with ``k``
    points (Gonzalez 1985).

    Args:
        pool: Solutions, shape ``(m, nq)``.
        k: How many to pick.
        periodic: Periodic joints, shape ``(nq,)``.
        ref: Reference configuration, shape ``(nq,)``.

    Returns:
        Indices into ``pool``, in pick order (``min(k, m)`` of them).
    """
    pool = np.asarray(pool, dtype=float)
    if pool.shape[0] == 0 or k <= 0:
        return []
    first = int(np.argmin(branch_distance(pool, ref, periodic)))
    picks = [first]
    dmin = branch_distance(pool, pool[first], periodic)
    while len(picks) < min(k, pool.shape[0]):
        nxt = int(np.argmax(dmin))
        if dmin[nxt] <= 0.0:
            break
        picks.append(nxt)
        dmin = np.minimum(dmin, branch_distance(pool, pool[nxt], periodic))
    return picks


def covering_radius(selected: Any, pool: Any, periodic: BoolArray) -> float:
    """Largest wrapped distance from a ``pool`` solution to its nearest ``selected`` one
    (rad): how far the selection leaves any known solution uncovered."""
    sel = np.asarray(selected, dtype=float)
    pool = np.asarray(pool, dtype=float)
    if pool.shape[0] == 0:
        return 0.0
    if sel.shape[0] == 0:
        return float("inf")
    d = branch_distance(pool[:, None, :], sel[None, :, :], periodic)
    return float(np.max(np.min(d, axis=1)))


def through_one_point(points: Any, axes: Any, tol: float = 1e-9) -> bool:
    """Whether the lines ``points[i] + t·axes[i]`` (unit axes, 3-vectors) meet in one point,
    each passing within ``tol`` [m] of the least-squares meeting point (a spherical wrist;
    used by :mod:`swarm_ik.many` and :mod:`swarm_ik.path` for their branch bounds)."""
    a = np.zeros((3, 3))
    b = np.zeros(3)
    projs = []
    for p, h in zip(points, axes, strict=True):
        proj = np.eye(3) - np.outer(h, h)
        projs.append((proj, p))
        a += proj
        b += proj @ p
    if np.linalg.matrix_rank(a) < 3:
        return False  # parallel lines: no single point
    x = np.linalg.solve(a, b)
    return all(np.linalg.norm(proj @ (x - p)) < tol for proj, p in projs)
