"""IKProblem: a robot, a target pose, a fitness and the search bounds."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from swarm_ik.errors import InvalidArgumentError, unknown
from swarm_ik.fitness import FITNESS, get_fitness
from swarm_ik.pose import as_pose, is_finite_nonneg, rotation_angle
from swarm_ik.robot import RobotModel

FloatArray = NDArray[np.float64]


def _log3_world(m: FloatArray) -> FloatArray:
    """Rotation vectors ``(pop, 3)`` of rotations ``(pop, 3, 3)``, accurate up to π."""
    theta = rotation_angle(m)
    s = 0.5 * np.stack(
        [m[:, 2, 1] - m[:, 1, 2], m[:, 0, 2] - m[:, 2, 0], m[:, 1, 0] - m[:, 0, 1]], axis=-1
    )
    sin_t = np.sin(theta)
    scale = np.where(theta < 1e-8, 1.0 + theta**2 / 6.0, theta / np.where(sin_t == 0, 1.0, sin_t))
    out = s * scale[:, None]
    near_pi = theta > np.pi - 1e-4
    for i in np.flatnonzero(near_pi):  # rare: let Pinocchio handle the branch at π
        out[i] = pin.log3(m[i])
    return out


class IKProblem:
    """Inverse kinematics of one target pose.

    Args:
        robot: The robot (see :func:`swarm_ik.load_robot`).
        target: Target pose: ``(4, 4)`` array [m], ``(position, quaternion xyzw)``, 7 numbers
            ``x y z qx qy qz qw``, or a ``pinocchio.SE3``.
        fitness: ``"se3"`` (default), ``"paper-l1"``, ``"euler-zyz"`` or ``"paper-pso"``
            (see :mod:`swarm_ik.fitness`).
        w_rot: Weight of the rotation error in ``"se3"`` [m/rad]; 0 makes the problem
            position-only (success then ignores the rotation).
        lam: λ of ``"paper-l1"`` (per metre; 10 equals the paper's 1e-2 per millimetre).
        mu: μ of ``"euler-zyz"``.
        orth_tol: Tolerance on the orthonormality of the target rotation.
        lower: Optional narrower lower bounds, shape ``(nq,)``; default the joint limits.
        upper: Optional narrower upper bounds, shape ``(nq,)``.

    Attributes:
        robot, target, fitness_name, w_rot, lower, upper, nq.
    """

    def __init__(
        self,
        robot: RobotModel,
        target: Any,
        fitness: str = "se3",
        *,
        w_rot: float = 1.0,
        lam: float = 10.0,
        mu: float = 1.0,
        orth_tol: float = 1e-6,
        lower: Any = None,
        upper: Any = None,
    ) -> None:
        if not isinstance(robot, RobotModel):
            raise InvalidArgumentError(
                f"robot must be a RobotModel (see swarm_ik.load_robot), got {type(robot).__name__}"
            )
        self.robot = robot
        self.target = as_pose(target, orth_tol=orth_tol)
        if not isinstance(fitness, str):
            raise unknown("fitness", fitness, FITNESS)
        self.fitness_name = fitness
        self._fitness = get_fitness(fitness)
        for label, v in (("w_rot", w_rot), ("lam", lam), ("mu", mu)):
            if not is_finite_nonneg(v):
                raise InvalidArgumentError(
                    f"{label} must be a finite non-negative number, got {v!r}"
                )
        self.w_rot = float(w_rot)
        self._weights = {"w_rot": self.w_rot, "lam": float(lam), "mu": float(mu)}
        self.lower = robot.lower.copy() if lower is None else robot.check_q(lower, "lower")
        self.upper = robot.upper.copy() if upper is None else robot.check_q(upper, "upper")
        if np.any(self.lower > self.upper):
            raise InvalidArgumentError(
                "lower bounds exceed upper bounds at joints "
                f"{np.flatnonzero(self.lower > self.upper).tolist()}"
            )
        outside = np.flatnonzero((self.lower < robot.lower) | (self.upper > robot.upper))
        if outside.size:  # wider bounds would let a "success" break the joint limits
            j = int(outside[0])
            raise InvalidArgumentError(
                f"bounds may only narrow the joint limits; joint {robot.joint_names[j]!r}: "
                f"bounds [{self.lower[j]:g}, {self.upper[j]:g}] exceed its limits "
                f"[{robot.lower[j]:g}, {robot.upper[j]:g}]"
            )
        self.position_only = fitness == "se3" and self.w_rot == 0.0
        self._rot_target = np.ascontiguousarray(self.target[:3, :3])

    @property
    def nq(self) -> int:
        """Number of joints."""
        return self.robot.nq

    @classmethod
    def from_q(cls, robot: RobotModel, q: Any, fitness: str = "se3", **kwargs: Any) -> IKProblem:
        """The problem whose target is the FK of ``q`` (reachable by construction)."""
        return cls(robot, robot.fk(robot.check_q(q)), fitness, **kwargs)

    # --------------------------------------------------------------- hot path
    def fitness(self, q_batch: FloatArray) -> FloatArray:
        """Batched fitness: ``(pop, nq) -> (pop,)`` (the solvers' objective)."""
        poses = self.robot.fk(np.atleast_2d(q_batch))
        return self._fitness(poses, self.target, **self._weights)

    __call__ = fitness

    def fitness_of_poses(self, poses: FloatArray) -> FloatArray:
        """Fitness of given end-effector poses ``(pop, 4, 4)``."""
        return self._fitness(poses, self.target, **self._weights)

    def errors(self, q_batch: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Position error ‖Δp‖ [m] and rotation error θ [rad], each ``(pop,)``."""
        poses = self.robot.fk(np.atleast_2d(q_batch))
        return self.pose_errors(poses)

    def pose_errors(self, poses: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Position and rotation errors of poses ``(pop, 4, 4)`` against the target."""
        dp = np.linalg.norm(poses[:, :3, 3] - self.target[:3, 3], axis=-1)
        rot_err = np.einsum("ji,njk->nik", self._rot_target, poses[:, :3, :3])
        return dp, rotation_angle(rot_err)

    def residual_jacobian(self, q_batch: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Fitness, error twist and Jacobian for Gauss–Newton / DLS steps.

        Args:
            q_batch: Joint vectors, shape ``(pop, nq)``.

        Returns:
            ``fitness (pop,)``; ``err (pop, 6)`` = ``[p_target − p; log(R_target Rᵀ)]`` in world
            axes (rotation rows zero when position-only); ``jac (pop, 6, nq)``, the
            LOCAL_WORLD_ALIGNED frame Jacobian (rotation rows zero when position-only), so
            that ``q + pinv(jac) @ err`` is the Gauss–Newton step.
        """
        poses, jac = self.robot.fk_jacobian(np.atleast_2d(q_batch))
        f = self._fitness(poses, self.target, **self._weights)
        err = np.empty((poses.shape[0], 6))
        err[:, :3] = self.target[:3, 3] - poses[:, :3, 3]
        if self.position_only:
            err[:, 3:] = 0.0
            jac[:, 3:, :] = 0.0
        else:
            m = np.einsum("ij,nkj->nik", self._rot_target, poses[:, :3, :3])
            err[:, 3:] = _log3_world(m)
        return f, err, jac

    def is_success(self, q: FloatArray, tol_pos: float, tol_rot: float) -> bool:
        """Both errors within tolerance (rotation ignored when position-only), within limits."""
        q = np.asarray(q, dtype=float)
        if np.any(q < self.lower - 1e-12) or np.any(q > self.upper + 1e-12):
            return False
        pose = self.robot.fk(q)
        t = self.target
        dx, dy, dz = pose[0, 3] - t[0, 3], pose[1, 3] - t[1, 3], pose[2, 3] - t[2, 3]
        if math.sqrt(dx * dx + dy * dy + dz * dz) > tol_pos:
            return False
        if self.position_only:
            return True
        m = (self._rot_target.T @ pose[:3, :3]).tolist()  # scalar maths: one pose only
        sx, sy, sz = m[2][1] - m[1][2], m[0][2] - m[2][0], m[1][0] - m[0][1]
        cos_t = 0.5 * (m[0][0] + m[1][1] + m[2][2] - 1.0)
        return math.atan2(0.5 * math.sqrt(sx * sx + sy * sy + sz * sz), cos_t) <= tol_rot

    def __repr__(self) -> str:
        p = self.target[:3, 3]
        return (
            f"IKProblem(robot={self.robot.name!r}, fitness={self.fitness_name!r}, "
            f"target_position={np.round(p, 4).tolist()})"
        )
