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
solutions is kept when it is exact (not a least-squares one), brought into the limits by a
2π shift (the in-limit copy nearest to ``q0``, else to the middle of the ranges) and verified
with Pinocchio's FK against the tolerances; duplicates modulo 2π (branches that meet at a
singularity) are merged.  Chains eaik cannot decompose (7 joints, prismatic joints, generic
offsets) are refused with :class:`AnalyticUnsupportedError` naming the reason; without eaik
installed with :class:`AnalyticUnavailableError` naming the extra.

>>> import swarm_ik
>>> from swarm_ik.solvers import analytic
>>> robot = swarm_ik.load_robot("ur5")
>>> problem = swarm_ik.IKProblem.from_q(robot, [0.3, -1.0, 1.2, -0.5, 1.1, 0.2])
>>> q, dp, dr = analytic.solve_all(problem)  # doctest: +SKIP
>>> q.shape  # doctest: +SKIP
(8, 6)
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from swarm_ik.branches import BRANCH_TOL, TWO_PI
from swarm_ik.errors import SwarmIKError
from swarm_ik.solvers.base import Evaluator, register

if TYPE_CHECKING:
    from swarm_ik.problem import IKProblem
    from swarm_ik.robot import RobotModel

FloatArray = NDArray[np.float64]

EXTRA_HINT = "pip install 'swarm_ik[analytic]' (or pip install eaik)"


class AnalyticUnavailableError(SwarmIKError, ImportError):
    """The analytic path needs eaik, which is not installed."""


class AnalyticUnsupportedError(SwarmIKError, ValueError):
    """The chain or problem has no analytic solution with eaik (the message says why)."""


def eaik_available() -> bool:
    """Whether eaik can be imported."""
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

    The same computation as :meth:`swarm_ik.robot.RobotModel.fk_pinocchio` followed by
    :func:`swarm_ik.api.verify` (``forwardKinematics`` + ``updateFramePlacement`` of the
    end-effector frame), without the per-call overheads.

    Args:
        problem: The IK problem (its robot and target).
        qs: Joint vectors, shape ``(k, nq)``.

    Returns:
        ``(dp (k,), dr (k,))``.
    """
    robot = problem.robot
    model, fid = robot.model, robot.ee_frame_id
    data = robot._data()  # the robot's per-thread Pinocchio Data (as fk_pinocchio uses)
    qs = np.asarray(qs, dtype=float)
    direct = model.nq == robot.nq
    fk, upd = pin.forwardKinematics, pin.updateFramePlacement
    poses = []
    for q in qs:
        fk(model, data, q if direct else robot.to_pinocchio(q))
        poses.append(upd(model, data, fid).homogeneous)
    m = np.array(poses).reshape(-1, 4, 4)
    target = problem.target
    d = m[:, :3, 3] - target[:3, 3]
    dp = np.sqrt(np.einsum("ki,ki->k", d, d))
    rel = target[:3, :3].T @ m[:, :3, :3]
    sx = rel[:, 2, 1] - rel[:, 1, 2]
    sy = rel[:, 0, 2] - rel[:, 2, 0]
    sz = rel[:, 1, 0] - rel[:, 0, 1]
    cos_t = rel[:, 0, 0] + rel[:, 1, 1] + rel[:, 2, 2] - 1.0
    dr = np.arctan2(np.sqrt(sx * sx + sy * sy + sz * sz), cos_t)
    return dp, dr


def solve_all(
    problem: IKProblem,
    *,
    ref: Any = None,
    tol_pos: float = 1e-5,
    tol_rot: float = 1e-5,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Every branch of ``problem`` within its bounds, one in-limit representative each.

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
    reason = support(problem)
    if reason:
        raise AnalyticUnsupportedError(f"no analytic IK for this problem: {reason}")
    chain = analytic_chain(problem.robot)
    lo, hi = problem.lower, problem.upper
    nq = lo.shape[0]
    center = 0.5 * (lo + hi) if ref is None else np.asarray(ref, dtype=float)
    sol = chain.solver.calculate_IK(problem.target)
    qs = np.asarray(sol.Q, dtype=float).reshape(-1, nq)
    if qs.shape[0]:
        qs = qs[~np.asarray(sol.is_LS, dtype=bool)]
    # every joint is revolute: the in-limit 2π copy nearest to the reference, joint by joint
    m_min = np.ceil((lo - 1e-9 - qs) / TWO_PI)
    m_max = np.floor((hi + 1e-9 - qs) / TWO_PI)
    m = np.minimum(np.maximum(np.rint((center - qs) / TWO_PI), m_min), m_max)
    qs = np.minimum(np.maximum(qs + TWO_PI * m, lo), hi)[np.all(m_min <= m_max, axis=1)]
    if qs.shape[0] == 0:
        return np.empty((0, nq)), np.empty(0), np.empty(0)
    dp, dr = pinocchio_errors(problem, qs)
    good = (dp <= tol_pos) & (dr <= tol_rot)
    d = qs - center
    order = np.argsort(np.einsum("ki,ki->k", d, d)[good], kind="stable")
    qs, dp, dr = qs[good][order], dp[good][order], dr[good][order]
    if qs.shape[0] > 1:  # branches meeting at a singularity come out twice
        diff = (qs[:, None, :] - qs[None, :, :] + np.pi) % TWO_PI - np.pi
        close = np.einsum("abi,abi->ab", diff, diff) < BRANCH_TOL**2
        dup = np.any(np.tril(close, -1), axis=1)
        if dup.any():
            qs, dp, dr = qs[~dup], dp[~dup], dr[~dup]
    return qs, dp, dr


def run(ev: Evaluator, rng: np.random.Generator) -> None:
    """Solver ``analytic``: all branches with eaik; the answer is the one nearest to ``q0``
    (else to the middle of the bounds).  One evaluation per branch verified.

    Raises:
        AnalyticUnavailableError: eaik is not installed.
        AnalyticUnsupportedError: the chain or problem is not solvable analytically.
    """
    problem = ev.problem
    if problem is None:
        raise AnalyticUnsupportedError("solver 'analytic' needs an IK problem, not an objective")
    tol_pos, tol_rot = ev.tolerance if ev.tolerance is not None else (1e-5, 1e-5)
    qs, _dp, _dr = solve_all(problem, ref=ev.q0, tol_pos=tol_pos, tol_rot=tol_rot)
    if qs.shape[0]:
        f = problem.fitness(qs[:1])
        ev.record(qs[:1], f)
        if qs.shape[0] > 1 and ev.remaining > 0:
            ev.add_evals(min(qs.shape[0] - 1, ev.remaining))
    ev.end_iteration()


register(
    "analytic",
    run,
    description="closed-form IK of decomposable 6R arms with eaik (extra 'analytic')",
    needs_jacobian=True,
    closed_form=True,
)
