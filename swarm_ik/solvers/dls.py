"""``dls``: Pinocchio damped least squares with random restarts — the baseline.

The classical Pinocchio IK loop (the "inverse kinematics" example of Pinocchio's
documentation): the error twist ``e = log6(oMf⁻¹ · oM_target)`` in the end-effector frame,
the frame Jacobian ``J`` (``LOCAL``), the damped step ``v = Jᵀ (J Jᵀ + λ I)⁻¹ e``, and
``q ← integrate(q, step·v)``, then the joint limits enforced by clipping (continuous joints
wrapped).  When the error stops decreasing or a restart has used its iterations, it restarts
from a point drawn uniformly within the limits, until the budget ends or the tolerance is met.

It solves one goal: an exact ``Pose`` or ``Position`` goal of any goal frame (the target
of ``IKProblem(robot, target)`` is one; with ``w_rot=0`` its position alone).  Any other
problem (a collision goal, several goals or frames, a tolerance band) is refused before the
first step, with what it holds (:func:`support`); the default solver ``swarm`` takes any
goal set.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from swarm_ik.errors import InvalidArgumentError
from swarm_ik.goals import AvoidCollisions, Pose, Position
from swarm_ik.solvers.base import Evaluator, register

if TYPE_CHECKING:
    from swarm_ik.problem import IKProblem

TAKES = "one exact Pose or Position goal of one frame"
"""What ``dls`` solves, for the messages that refuse other problems."""


def support(problem: IKProblem | None) -> str:
    """Why ``dls`` cannot solve ``problem``, in words naming what the problem holds (e.g.
    ``"an AvoidCollisions goal"``); the empty string when it can: one exact ``Pose`` or
    ``Position`` goal, on any goal frame (the target of ``IKProblem(robot, target)`` is one).

    Args:
        problem: The IK problem (``None``: a plain objective, as ``swarm_ik.optimize`` has).
    """
    if problem is None:
        return "no IK problem (a plain objective), and dls steps along a frame's Jacobian"
    goals = problem.goals
    if any(isinstance(g, AvoidCollisions) for g in goals):
        return "an AvoidCollisions goal (obstacles or self-collision)"
    if len(goals) > 1:
        return f"{len(goals)} goals ({', '.join(g.describe() for g in goals)})"
    goal = goals[0]
    if not isinstance(goal, (Pose, Position)):
        return f"a {goal.describe()} goal, not a pose"
    if not goal.exact:
        return f"a {goal.describe()} goal with a tolerance band"
    return ""


def refusal(problem: IKProblem | None) -> InvalidArgumentError | None:
    """The error ``dls`` raises for a problem it cannot solve (:func:`support`), or None."""
    reason = support(problem)
    if not reason:
        return None
    return InvalidArgumentError(
        f"solver 'dls' solves {TAKES}, and this problem has {reason}; use the default solver "
        "'swarm', which takes any goal set"
    )


def run(
    ev: Evaluator,
    rng: np.random.Generator,
    *,
    iterations: int = 1000,
    iters_per_restart: int = 100,
    damping: float = 1e-6,
    step: float = 1.0,
    stall_tol: float = 1e-9,
    stall_iters: int = 10,
) -> None:
    """Damped least squares on Pinocchio, restarted from random points within the limits.

    Every iteration is one forward kinematics + Jacobian evaluation, counted as one
    evaluation.  The first restart starts from ``q0`` when given, else from the middle of the
    joint ranges (as TRAC-IK's benchmark does); later ones from uniform random points.

    Args:
        ev: The evaluator (must wrap an IK problem that :func:`support` accepts).
        rng: Random generator (restart points).
        iterations: Total DLS iterations when no ``max_evals``/``time_limit`` is given.
        iters_per_restart: Iterations before a restart.
        damping: λ added to ``J Jᵀ`` (units of the twist squared); small values give
            Gauss–Newton steps, large values slow gradient steps.
        step: Scale of the step ``v`` (1 = full damped Gauss–Newton step).
        stall_tol: A restart also happens when the fitness improves by less than this…
        stall_iters: …over this many consecutive iterations.

    Raises:
        InvalidArgumentError: a problem :func:`support` refuses (a collision goal, several
            goals, a tolerance band…), before any evaluation; the message says what dls
            solves and what the problem holds.
    """
    problem = ev.problem
    refused = refusal(problem)
    if refused is not None:  # (before the first step: nothing is evaluated)
        raise refused
    assert problem is not None  # (support's check)
    goal = problem.goals[0]
    by_pose = problem.target is not None  # (else a Position goal of a goal list)
    if problem.target is not None:
        target = problem.target
    else:
        assert isinstance(goal, Position)  # (support's check)
        target = np.eye(4)
        target[:3, 3] = np.asarray(goal.point, dtype=float)
    robot = problem.robot
    model = robot.model
    data = model.createData()
    fid = robot.frame_ids[robot.frame_index(goal.frame_name())]  # (any goal frame)
    o_m_target = pin.SE3(target[:3, :3].copy(), target[:3, 3].copy())
    rows = slice(0, 3) if problem.position_only else slice(0, 6)
    q = ev.q0.copy() if ev.q0 is not None else 0.5 * (ev.lower + ev.upper)
    it_restart = 0
    best_restart = np.inf
    stall = 0
    for _ in range(iterations if ev.max_evals is None and ev.time_limit is None else 2**62):
        if ev.done:
            break
        q_pin = robot.to_pinocchio(q)
        pin.forwardKinematics(model, data, q_pin)
        pin.updateFramePlacements(model, data)
        pose = data.oMf[fid]
        fit = (
            problem.fitness_of_poses(np.asarray(pose.homogeneous)[None])
            if by_pose
            else problem.fitness(q[None])
        )
        f = ev.record(q[None], fit)[0]
        ev.end_iteration()
        if ev.done:
            break
        err = pin.log6(pose.actInv(o_m_target)).vector
        jac = np.asarray(
            pin.computeFrameJacobian(model, data, q_pin, fid, pin.ReferenceFrame.LOCAL)
        ).reshape(6, robot.nq)
        if problem.position_only:  # position error and Jacobian in world axes
            err = np.concatenate([o_m_target.translation - pose.translation, np.zeros(3)])
            jac = np.vstack([pose.rotation @ jac[:3], np.zeros_like(jac[3:])])
        e = err[rows]
        j = jac[rows]
        v = j.T @ np.linalg.solve(j @ j.T + damping * np.eye(j.shape[0]), e)
        q_new = robot.from_pinocchio(pin.integrate(model, q_pin, step * v))
        q = ev.clip(q_new)
        it_restart += 1
        if f < best_restart - stall_tol:
            best_restart = f
            stall = 0
        else:
            stall += 1
        if it_restart >= iters_per_restart or stall >= stall_iters:
            q = ev.uniform(rng, 1)[0]
            it_restart = 0
            best_restart = np.inf
            stall = 0


CONSTRAINTS = {
    "iters_per_restart": "int>=1",
    "damping": "positive",
    "step": "positive",
    "stall_tol": "nonnegative",
    "stall_iters": "int>=1",
}
"""What each parameter accepts (checked by the registry: ``solvers.base.Constraint``)."""

register(
    "dls",
    run,
    paper="DLS",
    evals_per_iteration=1,
    constraints=CONSTRAINTS,
    description="Pinocchio damped least squares with random restarts (baseline)",
    needs_jacobian=True,
)
