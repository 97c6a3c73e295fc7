"""Goal terms: what an IK problem asks of the robot, each a residual with its Jacobian.

A goal is a small frozen object: a frame (for frame goals), its data (a pose, a point, an
axis…), a ``weight`` and whether it is ``primary``.  Primary goals must be met to tolerance
(success = every primary goal within tolerance and the joints within limits); secondary goals
(the default for :class:`Posture`, :class:`CenterJoints` and :class:`MinimalDisplacement`) are
optimised lexicographically *after* the primary ones: once the primary residual is within
tolerance, the solver moves in the null space of the primary Jacobian to reduce the secondary
cost and accepts a step only when every primary goal stays within tolerance
(:func:`swarm_ik.kernels.lm.secondary_descent`), so a secondary goal never costs primary
accuracy.

Each goal class gives

* ``encode(robot, q0)``: its row of the compiled goal table
  (:class:`swarm_ik.kernels.lm.GoalTable`): a residual code of :mod:`swarm_ik.kernels.lm`,
  the goal frame's index and 12 parameters,
  plus a joint reference and per-joint weights for joint-space goals;
* ``residual(pose, jac, q)``: the numpy twin of the compiled residual ``r`` and its step
  Jacobian ``J`` (``r(q + δ) ≈ r(q) − J δ``), used by the tests;
* ``errors(pose, q)``: ``(position error [m], angular error [rad])`` (NaN where the goal has
  none), the quantities the tolerances judge.

Adding a goal type is one class here plus ``@register_goal``; a goal whose residual is not one
of the kernel's residual codes also needs its branch in :func:`swarm_ik.kernels.lm.goal_rows`.

>>> import numpy as np, swarm_ik
>>> from swarm_ik import goals
>>> robot = swarm_ik.load_robot("panda")
>>> down = goals.Axis("panda_hand_tcp", axis=[0, 0, 1], direction=[0, 0, -1])
>>> at = goals.Position("panda_hand_tcp", [0.5, 0, 0.3])
>>> problem = swarm_ik.IKProblem(robot, goals=[at, down])
>>> swarm_ik.solve(problem).success
True
"""

from __future__ import annotations

import json
import os
import reprlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import MISSING, Field, dataclass, field, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, TypeVar

import numpy as np
from numpy.typing import NDArray

from swarm_ik.errors import InvalidArgumentError, InvalidTargetError, UnknownNameError, unknown
from swarm_ik.kernels import lie
from swarm_ik.kernels.lm import (
    AXIS,
    COLLISION,
    JOINT,
    LOOK_AT,
    N_PAR,
    ORIENTATION,
    POSE,
    POSITION,
)
from swarm_ik.pose import as_pose

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel

FloatArray = NDArray[np.float64]


def _vec3(value: Any, what: str, *, unit: bool = False) -> FloatArray:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InvalidArgumentError(f"{what} must be 3 numbers, got {reprlib.repr(value)}") from None
    if arr.shape != (3,):
        raise InvalidArgumentError(f"{what} must be 3 numbers, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InvalidArgumentError(f"{what} must be finite, got {arr.tolist()}")
    if unit:
        scale = np.max(np.abs(arr))
        if scale == 0.0:
            raise InvalidArgumentError(f"{what} must not be the zero vector")
        arr = arr / scale
        arr = arr / np.linalg.norm(arr)
    return arr


def _weight(value: Any, what: str = "weight") -> float:
    try:
        w = float(value)
    except (TypeError, ValueError):
        raise InvalidArgumentError(f"{what} must be a positive number, got {value!r}") from None
    if not (np.isfinite(w) and w > 0.0):
        raise InvalidArgumentError(f"{what} must be a positive finite number, got {value!r}")
    return w


def _skew(v: FloatArray) -> FloatArray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


@dataclass(frozen=True)
class Goal:
    """Base of every goal term.

    Attributes:
        weight: Weight of the goal's residual rows (dimensionless; a Pose's rotation rows are
            in radians, its position rows in metres); keyword-only, positive.
        primary: Must be met to tolerance (True) or optimised after the primary goals in
            their null space (False); keyword-only (default True, False for the joint-space
            preferences).
    """

    weight: float = field(default=1.0, kw_only=True)
    primary: bool = field(default=True, kw_only=True)
    code: ClassVar[int] = -1
    frame_goal: ClassVar[bool] = True
    units: ClassVar[tuple[str, ...]] = ()
    """Fields that are directions: 3 finite numbers, not zero, stored normalised."""
    vectors: ClassVar[tuple[str, ...]] = ()
    """Fields that are points or vectors: 3 finite numbers, stored as a float array."""

    def __post_init__(self) -> None:
        name = type(self).__name__
        for label in self.units:
            value = _vec3(getattr(self, label), f"{name}.{label}", unit=True)
            object.__setattr__(self, label, value)
        for label in self.vectors:
            object.__setattr__(self, label, _vec3(getattr(self, label), f"{name}.{label}"))
        object.__setattr__(self, "weight", _weight(self.weight))

    @property
    def is_primary(self) -> bool:
        """The goal's ``primary`` field."""
        return bool(self.primary)

    @property
    def residual_weight(self) -> float:
        """The goal's ``weight`` field."""
        return float(self.weight)

    def frame_name(self) -> str | None:
        """The goal frame (None for joint-space goals)."""
        return getattr(self, "frame", None)

    def encode(self, robot: RobotModel, q0: FloatArray | None) -> GoalRow:
        """The goal's row of the compiled goal table."""
        raise NotImplementedError

    def residual(
        self, pose: FloatArray, jac: FloatArray, q: FloatArray, robot: RobotModel
    ) -> tuple[FloatArray, FloatArray]:
        """Numpy twin of the compiled residual: ``(r (rows,), J (rows, nq))`` with
        ``r(q + δ) ≈ r − J δ``; ``pose (4, 4)`` and ``jac (6, nq)`` of the goal frame."""
        raise NotImplementedError

    def errors(self, pose: FloatArray, q: FloatArray, robot: RobotModel) -> tuple[float, float]:
        """``(position error [m], angular error [rad])``, NaN where the goal has none."""
        raise NotImplementedError

    def describe(self) -> str:
        """Short label for reports, e.g. ``Pose(left_gripper)``."""
        f = self.frame_name()
        return f"{type(self).__name__}({f})" if f else type(self).__name__

    def extra_frames(self, robot: RobotModel) -> tuple[Any, Any, Any] | None:
        """Frames the goal needs beyond the robot's goal frames (appended to the problem's
        tree): ``(joint ids of robot.model, rotations, translations)``, or None."""
        return None

    def check(
        self, poses: FloatArray, q: FloatArray, robot: RobotModel, tol_pos: float,
        tol_rot: float, q0: FloatArray | None = None,
    ) -> tuple[float, float, bool, Any]:  # fmt: skip
        """The independent check: ``(position error, angular error, met, details)`` with
        Pinocchio's poses ``(nf, 4, 4)`` of the goal frames."""
        frame = self.frame_name()
        pose = poses[robot.frames.index(frame)] if frame is not None else np.eye(4)
        if self.frame_goal:
            dp, dr = self.errors(pose, q, robot)
        else:
            dp, dr = self.errors(pose, q, robot, q0)  # type: ignore[call-arg]
        met = not (dp > tol_pos) and not (dr > tol_rot)
        return float(dp), float(dr), bool(met), None


@dataclass(frozen=True)
class GoalRow:
    """One goal encoded for the kernel (see :class:`swarm_ik.kernels.lm.GoalTable`)."""

    code: int
    frame: int
    weight: float
    primary: bool
    par: FloatArray
    jref: FloatArray
    jw: FloatArray
    rows: int | None = None
    col: Any = None


GOALS: dict[str, type[Goal]] = {}
"""Goal types by name (the ``type`` field of the JSON schema)."""

G = TypeVar("G", bound=type[Goal])


def register_goal(cls: G) -> G:
    """Class decorator: make a goal type known by its class name (JSON, CLI).

    Raises:
        InvalidArgumentError: a goal type of that name is already registered.
    """
    name = cls.__name__
    if name in GOALS:
        raise InvalidArgumentError(f"goal type {name!r} is already registered")
    GOALS[name] = cls
    return cls


def _frame_row(goal: Goal, robot: RobotModel, head: Any = (), point: Any = None) -> GoalRow:
    """The kernel row of a frame goal: ``head`` fills the first parameters (a row-major
    rotation, or two 3-vectors), ``point`` the last three (see :mod:`swarm_ik.kernels.lm`)."""
    par = np.zeros(N_PAR)
    flat = np.ravel(head)
    par[: flat.size] = flat
    if point is not None:
        par[9:12] = point
    frame = goal.frame_name()
    if frame not in robot.frames:
        raise UnknownNameError(
            f"{goal.describe()}: {frame!r} is not a goal frame of this robot; goal frames: "
            f"{', '.join(robot.frames)} (load the robot with every goal frame: "
            "load_robot(name, ee_frame=[...]))"
        )
    return GoalRow(
        goal.code,
        robot.frames.index(frame),
        goal.residual_weight,
        goal.is_primary,
        par,
        np.zeros(robot.nq),
        np.zeros(robot.nq),
    )


# --------------------------------------------------------------------------- frame goals
@register_goal
@dataclass(frozen=True)
class Pose(Goal):
    """The frame at a full pose: ``r = w·[p* − p; log(R* Rᵀ)]`` (world axes).

    Args:
        frame: Goal frame name.
        target: ``(4, 4)`` pose [m], ``(position, quaternion xyzw)``, 7 numbers, or SE3.
        orth_tol: Tolerance on the orthonormality of the target rotation (keyword-only).
        weight, primary: As :class:`Goal` (keyword-only).
    """

    frame: str
    target: Any
    orth_tol: float = field(default=1e-6, kw_only=True)
    code: ClassVar[int] = POSE

    def __post_init__(self) -> None:
        object.__setattr__(self, "target", as_pose(self.target, orth_tol=self.orth_tol))
        super().__post_init__()

    @classmethod
    def checked(cls, frame: str, target: FloatArray) -> Pose:
        """A Pose of a target already validated by :func:`swarm_ik.pose.as_pose` (no second
        check: the hot path of :class:`swarm_ik.IKSolver`)."""
        goal = object.__new__(cls)
        goal.__dict__.update(frame=frame, target=target, weight=1.0, primary=True, orth_tol=1e-6)
        return goal

    def encode(self, robot: RobotModel, q0: FloatArray | None) -> GoalRow:
        return _frame_row(self, robot, self.target[:3, :3], self.target[:3, 3])

    def residual(self, pose, jac, q, robot):  # type: ignore[no-untyped-def]
        phi = lie.log3(self.target[:3, :3] @ pose[:3, :3].T)
        r = np.concatenate([self.target[:3, 3] - pose[:3, 3], phi])
        jr = np.vstack([jac[:3], lie.jr_inv(phi) @ jac[3:]])
        return self.weight * r, self.weight * jr

    def errors(self, pose, q, robot):  # type: ignore[no-untyped-def]
        dp = float(np.linalg.norm(pose[:3, 3] - self.target[:3, 3]))
        return dp, float(lie.angle(self.target[:3, :3].T @ pose[:3, :3]))


@register_goal
@dataclass(frozen=True)
class Position(Goal):
    """The frame origin at a world point: ``r = w·(p* − p)`` [m].

    Args:
        frame: Goal frame name.
        point: World point [m], 3 numbers.
        weight, primary: As :class:`Goal` (keyword-only).
    """

    frame: str
    point: Any
    code: ClassVar[int] = POSITION
    vectors: ClassVar[tuple[str, ...]] = ("point",)

    def encode(self, robot: RobotModel, q0: FloatArray | None) -> GoalRow:
        return _frame_row(self, robot, point=self.point)

    def residual(self, pose, jac, q, robot):  # type: ignore[no-untyped-def]
        return self.weight * (self.point - pose[:3, 3]), self.weight * jac[:3].copy()

    def errors(self, pose, q, robot):  # type: ignore[no-untyped-def]
        return float(np.linalg.norm(pose[:3, 3] - self.point)), float("nan")


@register_goal
@dataclass(frozen=True)
class Orientation(Goal):
    """The frame at a world orientation: ``r = w·log(R* Rᵀ)`` [rad].

    Args:
        frame: Goal frame name.
        rotation: ``(3, 3)`` rotation matrix or a quaternion ``(x, y, z, w)``.
        orth_tol: As :class:`Pose` (keyword-only).
        weight, primary: As :class:`Goal` (keyword-only).
    """

    frame: str
    rotation: Any
    orth_tol: float = field(default=1e-6, kw_only=True)
    code: ClassVar[int] = ORIENTATION

    def __post_init__(self) -> None:
        r = np.asarray(self.rotation, dtype=float) if _is_array(self.rotation) else None
        if r is not None and r.shape == (3, 3):
            pose = np.eye(4)
            pose[:3, :3] = r
            rot = as_pose(pose, orth_tol=self.orth_tol)[:3, :3]
        else:
            rot = as_pose((np.zeros(3), self.rotation), orth_tol=self.orth_tol)[:3, :3]
        object.__setattr__(self, "rotation", rot)
        super().__post_init__()

    def encode(self, robot: RobotModel, q0: FloatArray | None) -> GoalRow:
        return _frame_row(self, robot, self.rotation)

    def residual(self, pose, jac, q, robot):  # type: ignore[no-untyped-def]
        phi = lie.log3(self.rotation @ pose[:3, :3].T)
        return self.weight * phi, self.weight * (lie.jr_inv(phi) @ jac[3:])

    def errors(self, pose, q, robot):  # type: ignore[no-untyped-def]
        return float("nan"), float(lie.angle(self.rotation.T @ pose[:3, :3]))


def _is_array(v: Any) -> bool:
    try:
        np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        return False
    return True


@dataclass(frozen=True)
class _FrameAxis(Goal):
    """Base of the goals on one axis ``a`` of a frame, the rotation about it free
    (:class:`Axis`, :class:`LookAt`): its fields ``frame`` and ``axis`` (normalised)."""

    frame: str
    axis: Any
    units: ClassVar[tuple[str, ...]] = ("axis",)


@register_goal
@dataclass(frozen=True)
class Axis(_FrameAxis):
    """A frame axis along a world direction, the rotation about it free.

    ``u = R·a`` (the frame axis ``a`` in world axes), ``r = w·(d − u)``: zero only when the
    axis points along ``d`` (not against it).  Error: the angle between ``u`` and ``d``.

    Args:
        frame: Goal frame name.
        axis: The axis in the frame's own coordinates (normalised; not zero).
        direction: The world direction (normalised; not zero).
        weight, primary: As :class:`Goal` (keyword-only).
    """

    direction: Any
    code: ClassVar[int] = AXIS
    units: ClassVar[tuple[str, ...]] = ("axis", "direction")

    def encode(self, robot: RobotModel, q0: FloatArray | None) -> GoalRow:
        return _frame_row(self, robot, (self.axis, self.direction))

    def residual(self, pose, jac, q, robot):  # type: ignore[no-untyped-def]
        u = pose[:3, :3] @ self.axis
        # du = ω × u = −[u]× ω; r = d − u  =>  J = −[u]× J_ω
        return self.weight * (self.direction - u), self.weight * (-_skew(u) @ jac[3:])

    def errors(self, pose, q, robot):  # type: ignore[no-untyped-def]
        u = pose[:3, :3] @ self.axis
        return float("nan"), _angle_between(u, self.direction)


def _angle_between(u: FloatArray, v: FloatArray) -> float:
    return float(np.arctan2(np.linalg.norm(np.cross(u, v)), float(np.dot(u, v))))


@register_goal
@dataclass(frozen=True)
class LookAt(_FrameAxis):
    """A frame axis pointing at a world point (a camera looking at a target).

    ``u = R·a``, ``d = (t − p)/‖t − p‖``, ``r = w·(d − u)``.  Error: the angle between them.

    Args:
        frame, axis: As :class:`Axis` (``axis``: the viewing axis).
        point: The world point to look at [m].
        weight, primary: As :class:`Goal` (keyword-only).
    """

    point: Any
    code: ClassVar[int] = LOOK_AT
    vectors: ClassVar[tuple[str, ...]] = ("point",)

    def encode(self, robot: RobotModel, q0: FloatArray | None) -> GoalRow:
        return _frame_row(self, robot, (self.axis, self.point))

    def residual(self, pose, jac, q, robot):  # type: ignore[no-untyped-def]
        u = pose[:3, :3] @ self.axis
        e = self.point - pose[:3, 3]
        dist = max(float(np.linalg.norm(e)), 1e-9)
        d = e / dist
        # dd = −(I − d dᵀ)/L · dp ; du = −[u]× ω ; r = d − u  =>  J = du − dd
        jd = -(np.eye(3) - np.outer(d, d)) / dist @ jac[:3]
        ju = -_skew(u) @ jac[3:]
        return self.weight * (d - u), self.weight * (ju - jd)

    def errors(self, pose, q, robot):  # type: ignore[no-untyped-def]
        u = pose[:3, :3] @ self.axis
        return float("nan"), _angle_between(u, self.point - pose[:3, 3])


# --------------------------------------------------------------------------- joint goals
def _joint_rows(
    goal: Goal, robot: RobotModel, ref: FloatArray, jw: FloatArray, primary: bool
) -> GoalRow:
    return GoalRow(
        JOINT,
        -1,
        goal.residual_weight,
        primary,
        np.zeros(N_PAR),
        ref.astype(float),
        jw.astype(float),  # type: ignore[attr-defined]
    )


def _joint_residual(
    goal: Goal, ref: FloatArray, jw: FloatArray, q: FloatArray, robot: RobotModel
) -> tuple[FloatArray, FloatArray]:
    d = ref - q
    m = robot.continuous_mask
    d[m] = (d[m] + np.pi) % (2 * np.pi) - np.pi
    w = goal.residual_weight * jw
    return w * d, np.diag(w)


def _joint_errors(
    ref: FloatArray, jw: FloatArray, q: FloatArray, robot: RobotModel
) -> tuple[float, float]:
    d = ref - q
    m = robot.continuous_mask
    d[m] = (d[m] + np.pi) % (2 * np.pi) - np.pi
    d = np.abs(d)
    on = jw > 0
    pri = on & robot.prismatic_mask
    rev = on & ~robot.prismatic_mask
    return (
        float(d[pri].max()) if pri.any() else float("nan"),
        float(d[rev].max()) if rev.any() else float("nan"),
    )


def _joint_vector(value: Any, robot: RobotModel, what: str) -> FloatArray:
    return robot.check_q(value, what)


@dataclass(frozen=True)
class JointGoal(Goal):
    """Base of the joint-space goals: ``r = w·w_j·(q_ref − q)`` with the reference and the
    per-joint weights of :meth:`reference` (``JOINT`` rows of the kernel)."""

    primary: bool = field(default=False, kw_only=True)
    code: ClassVar[int] = JOINT
    frame_goal: ClassVar[bool] = False

    def reference(self, robot: RobotModel, q0: FloatArray | None) -> tuple[FloatArray, FloatArray]:
        """``(q_ref (nq,), joint weights (nq,))`` of the goal on ``robot`` (``q0``: the
        solve's start)."""
        raise NotImplementedError

    def encode(self, robot: RobotModel, q0: FloatArray | None) -> GoalRow:
        ref, jw = self.reference(robot, q0)
        return _joint_rows(self, robot, ref, jw, self.is_primary)

    def residual(self, pose, jac, q, robot, q0=None):  # type: ignore[no-untyped-def]
        ref, jw = self.reference(robot, q0)
        return _joint_residual(self, ref, jw, q, robot)

    def errors(self, pose, q, robot, q0=None):  # type: ignore[no-untyped-def]
        ref, jw = self.reference(robot, q0)
        return _joint_errors(ref, jw, q, robot)


@register_goal
@dataclass(frozen=True)
class Posture(JointGoal):
    """Joints near a reference posture: ``r = w·(q_ref − q)`` (continuous joints wrapped).

    Secondary by default (optimised in the null space of the primary goals).

    Args:
        q_ref: Reference joint vector ``(nq,)`` (rad / m).
        joint_weights: Optional per-joint weights ``(nq,)`` (default all 1; keyword-only).
        weight, primary: As :class:`Goal` (keyword-only; ``primary`` default False).
    """

    q_ref: Any
    joint_weights: Any = field(default=None, kw_only=True)

    def reference(self, robot: RobotModel, q0: FloatArray | None) -> tuple[FloatArray, FloatArray]:
        ref = _joint_vector(self.q_ref, robot, "Posture.q_ref")
        jw = (
            np.ones(robot.nq)
            if self.joint_weights is None
            else _joint_vector(self.joint_weights, robot, "Posture.joint_weights")
        )
        if np.any(jw < 0):
            raise InvalidArgumentError("Posture.joint_weights must be non-negative")
        return ref, jw


@register_goal
@dataclass(frozen=True)
class CenterJoints(JointGoal):
    """Joints near the middle of their ranges (BioIK's CenterJoints): a :class:`Posture` at
    the mid-range, each joint's row scaled by ``2/range`` so every joint counts alike.

    Args:
        weight, primary: As :class:`Goal` (keyword-only; ``primary`` default False).
    """

    def reference(self, robot: RobotModel, q0: FloatArray | None) -> tuple[FloatArray, FloatArray]:
        width = robot.upper - robot.lower
        jw = np.where(width > 0, 2.0 / np.where(width > 0, width, 1.0), 0.0)
        jw[robot.continuous_mask] = 0.0  # no centre on a circle
        return robot.mid_q(), jw


@register_goal
@dataclass(frozen=True)
class MinimalDisplacement(JointGoal):
    """Joints near the start ``q0`` of the solve (BioIK's MinimalDisplacement): a
    :class:`Posture` at ``q0`` (at the mid-range when the solve has no ``q0``).

    Args:
        weight, primary: As :class:`Goal` (keyword-only; ``primary`` default False).
    """

    def reference(self, robot: RobotModel, q0: FloatArray | None) -> tuple[FloatArray, FloatArray]:
        ref = robot.mid_q() if q0 is None else np.asarray(q0, dtype=float)
        return ref, np.ones(robot.nq)


@register_goal
@dataclass(frozen=True)
class JointValue(JointGoal):
    """One joint at a value: ``r = w·(v − q_j)``.  Primary by default.

    Args:
        joint: Joint name (one of ``robot.joint_names``).
        value: The value (rad or m).
        weight, primary: As :class:`Goal` (keyword-only).
    """

    joint: str
    value: float
    primary: bool = field(default=True, kw_only=True)

    def __post_init__(self) -> None:
        try:
            v = float(self.value)
        except (TypeError, ValueError):
            raise InvalidArgumentError(
                f"JointValue.value must be a number, got {self.value!r}"
            ) from None
        if not np.isfinite(v):
            raise InvalidArgumentError(f"JointValue.value must be finite, got {self.value!r}")
        object.__setattr__(self, "value", v)
        super().__post_init__()

    def describe(self) -> str:
        return f"JointValue({self.joint})"

    def reference(self, robot: RobotModel, q0: FloatArray | None) -> tuple[FloatArray, FloatArray]:
        if self.joint not in robot.joint_names:
            raise unknown("joint", self.joint, robot.joint_names)
        j = robot.joint_names.index(self.joint)
        ref = np.zeros(robot.nq)
        ref[j] = self.value
        jw = np.zeros(robot.nq)
        jw[j] = 1.0
        return ref, jw


# --------------------------------------------------------------------------- collisions
@register_goal
@dataclass(frozen=True)
class AvoidCollisions(Goal):
    """No contact between the robot's collision bodies (self-collision) nor with a scene.

    A primary constraint.  In the search, every collision body is covered by spheres
    (conservative: spheres apart ⇒ bodies apart, :mod:`swarm_ik.kernels.spheres`) and each
    active sphere pair contributes a row ``r = −w·max(0, margin + r_i + r_j − ‖c_i − c_j‖)``
    (obstacles: their exact signed distance) with its Jacobian, up to ``max_rows`` rows (the
    deepest first).  The answer is judged by the exact check with coal on the URDF's collision
    geometry (:meth:`swarm_ik.collision.RobotCollision.check`): success only without contact
    closer than ``margin``; ``Result.collision`` gives the clearance and the pairs in contact.
    At most one per problem.

    Args:
        scene: Obstacles: a :class:`swarm_ik.scene.Scene`, a list of shapes, a scene JSON
            file, or None (self-collision only).
        self_collision: Check the robot against itself (pairs: all link pairs minus adjacent
            links minus the SRDF's disabled pairs, see :mod:`swarm_ik.collision`).
        margin: Wanted clearance [m], ``>= 0``.
        max_rows: Most penetration rows per evaluation (keyword-only).
        tolerance: Sphere fitting tolerance [m] (how far a sphere may stick out of its body;
            keyword-only).
        weight, primary: As :class:`Goal` (keyword-only).
    """

    scene: Any = None
    self_collision: bool = True
    margin: float = 0.0
    max_rows: int = field(default=24, kw_only=True)
    tolerance: float = field(default=0.02, kw_only=True)
    code: ClassVar[int] = COLLISION
    frame_goal: ClassVar[bool] = False

    def __post_init__(self) -> None:
        from swarm_ik.scene import as_scene

        object.__setattr__(self, "scene", as_scene(self.scene))
        super().__post_init__()
        m = float(self.margin) if _is_array(self.margin) else float("nan")
        if not (np.isfinite(m) and m >= 0.0):
            raise InvalidArgumentError(
                f"AvoidCollisions.margin must be >= 0 [m], got {self.margin!r}"
            )
        object.__setattr__(self, "margin", m)
        if (
            isinstance(self.max_rows, bool)
            or not isinstance(self.max_rows, int)
            or self.max_rows < 1
        ):
            raise InvalidArgumentError(
                f"AvoidCollisions.max_rows must be a positive integer, got {self.max_rows!r}"
            )
        object.__setattr__(self, "tolerance", _weight(self.tolerance, "AvoidCollisions.tolerance"))

    def describe(self) -> str:
        return "AvoidCollisions"

    def obstacle_containing(self, point: Any) -> str | None:
        """Name of a scene obstacle whose inside holds the world ``point`` [m], if any (coal's
        signed distance of a point-sized probe)."""
        if len(self.scene) == 0:
            return None
        import coal

        from swarm_ik.scene import coal_object

        p = np.asarray(point, dtype=float)
        probe = coal.CollisionObject(coal.Sphere(1e-9), coal.Transform3s(np.eye(3), p))
        for name, shape in zip(self.scene.names, self.scene, strict=True):
            req, res = coal.DistanceRequest(), coal.DistanceResult()
            if coal.distance(coal_object(shape), probe, req, res) < 0.0:
                return str(name)
        return None

    def spheres(self, robot: RobotModel) -> Any:
        """The sphere model of the robot and the scene (cached on the robot)."""
        from swarm_ik.kernels.spheres import SphereModel

        key = ("spheres", self.scene, bool(self.self_collision), self.tolerance)
        sm = robot._cache.get(key)
        if sm is None:
            sm = SphereModel.from_collision(
                robot.collision_model(), self.scene, tolerance=self.tolerance,
                self_collision=bool(self.self_collision),
            )  # fmt: skip
            robot._cache[key] = sm
        return sm

    def extra_frames(self, robot: RobotModel) -> tuple[Any, Any, Any] | None:
        sm = self.spheres(robot)
        return sm.body_joint, sm.body_frame_rot, sm.body_frame_pos

    def encode_cached(self, robot: RobotModel) -> tuple[Any, Any]:
        """The problem's tree with the body frames and this goal's row, cached on the robot
        per scene (building them takes about a millisecond)."""
        key = ("avoid-encoded", self.scene, bool(self.self_collision), self.tolerance,
               self.margin, self.max_rows, self.weight, self.primary)  # fmt: skip
        hit = robot._cache.get(key)
        if hit is None:
            fj, fr, fp = robot.canonical_frames(*self.extra_frames(robot))  # type: ignore[misc]
            t = robot.tree
            tree = t.with_frames(
                np.concatenate([t.frame_joint, fj]),
                np.concatenate([t.frame_rot, fr]),
                np.concatenate([t.frame_pos, fp]),
            )
            hit = robot._cache[key] = (tree, self.encode(robot, None))
        return hit

    def encode(self, robot: RobotModel, q0: FloatArray | None) -> GoalRow:
        from swarm_ik.kernels.lm import CollisionArrays

        sm = self.spheres(robot)
        col = CollisionArrays(
            len(robot.frames), int(sm.body_joint.shape[0]), sm.arrays, float(self.margin),
            sm.scratch(), np.zeros((self.max_rows, 2), dtype=np.int64),
        )  # fmt: skip
        return GoalRow(
            COLLISION, -1, self.weight, self.primary, np.zeros(N_PAR), np.zeros(robot.nq),
            np.zeros(robot.nq), rows=self.max_rows, col=col,
        )  # fmt: skip

    def errors(self, pose, q, robot, q0=None):  # type: ignore[no-untyped-def]
        depth, nan, _met, _report = self.check(None, q, robot, 0.0, 0.0)
        return depth, nan

    def check(self, poses, q, robot, tol_pos, tol_rot, q0=None):  # type: ignore[no-untyped-def]
        rep = robot.collision_model().check(q, self.scene, self.margin, bool(self.self_collision))
        depth = 0.0 if rep.collision_free else max(0.0, self.margin - rep.clearance)
        return depth, float("nan"), bool(rep.collision_free), rep

    def residual(self, pose, jac, q, robot):  # type: ignore[no-untyped-def]
        raise InvalidArgumentError("AvoidCollisions has no numpy twin: see SphereModel.evaluate")


# --------------------------------------------------------------------------- JSON
def goal_from_dict(data: Mapping[str, Any]) -> Goal:
    """One goal from its JSON form ``{"type": "Pose", "frame": ..., ...}``.

    Raises:
        UnknownNameError: unknown ``type`` (the goal types listed).
        InvalidArgumentError: missing or unknown fields (the valid ones listed), bad values.
    """
    if not isinstance(data, Mapping):
        raise InvalidArgumentError(
            f"a goal must be a JSON object with a 'type', got {reprlib.repr(data)}"
        )
    kind = data.get("type")
    if kind not in GOALS:
        raise unknown("goal type", kind, GOALS)
    cls = GOALS[str(kind)]
    valid = [f.name for f in _init_fields(cls)]
    given = {k: v for k, v in data.items() if k != "type"}
    bad = sorted(set(given) - set(valid))
    if bad:
        raise InvalidArgumentError(
            f"goal {kind}: unknown field(s) {bad}; valid fields: {', '.join(valid)}"
        )
    required = [
        f.name for f in _init_fields(cls) if f.default is MISSING and f.default_factory is MISSING
    ]
    missing = [name for name in required if name not in given]
    if missing:
        raise InvalidArgumentError(f"goal {kind}: missing field(s) {missing}")
    if "target" in given and isinstance(given["target"], Mapping):
        t = given["target"]
        extra = sorted(set(t) - {"position", "quaternion"})
        if extra or "position" not in t or "quaternion" not in t:
            raise InvalidTargetError(
                f"goal {kind}: target must be a 4x4 matrix, 7 numbers (x y z qx qy qz qw) or "
                '{"position": [x, y, z], "quaternion": [qx, qy, qz, qw]}'
            )
        given["target"] = (t["position"], t["quaternion"])
    try:
        return cls(**given)
    except TypeError as exc:
        raise InvalidArgumentError(f"goal {kind}: {exc}") from None


def _init_fields(cls: type[Goal]) -> list[Field[Any]]:
    """The goal type's constructor fields in the order of its signature (the keyword-only
    ``weight`` and ``primary`` last)."""
    init = [f for f in fields(cls) if f.init]
    return sorted(init, key=lambda f: bool(f.kw_only))


def goal_to_dict(goal: Goal) -> dict[str, Any]:
    """JSON form of a goal (inverse of :func:`goal_from_dict`)."""
    out: dict[str, Any] = {"type": type(goal).__name__}
    for f in _init_fields(type(goal)):
        v = getattr(goal, f.name)
        out[f.name] = v.tolist() if isinstance(v, np.ndarray) else v
    return out


def load_goals(source: str | os.PathLike[str] | Sequence[Mapping[str, Any]]) -> list[Goal]:
    """Goals from a JSON file (a list of goal objects, or ``{"goals": [...]}``) or from the
    already-parsed list.

    Raises:
        InvalidArgumentError: unreadable file, not a list of goal objects, bad goals.
    """
    if isinstance(source, (str, os.PathLike)):
        p = Path(source)
        try:
            data = json.loads(p.read_text())
        except FileNotFoundError:
            raise InvalidArgumentError(f"goals file not found: {str(p)!r}") from None
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise InvalidArgumentError(f"{p}: not a readable JSON goals file ({exc})") from None
    else:
        data = source
    if isinstance(data, Mapping) and "goals" in data:
        data = data["goals"]
    if not isinstance(data, Sequence) or isinstance(data, (str, bytes)) or not data:
        raise InvalidArgumentError("goals must be a non-empty JSON list of goal objects")
    return [goal_from_dict(d) for d in data]


GoalFactory = Callable[..., Goal]

__all__ = [
    "GOALS",
    "AvoidCollisions",
    "Axis",
    "CenterJoints",
    "Goal",
    "GoalRow",
    "JointGoal",
    "JointValue",
    "LookAt",
    "MinimalDisplacement",
    "Orientation",
    "Pose",
    "Position",
    "Posture",
    "goal_from_dict",
    "goal_to_dict",
    "load_goals",
    "register_goal",
]
