"""``Position``: a frame origin at a world point, or within a ball about it."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numba
import numpy as np

from swarm_ik._validate import nonnegative
from swarm_ik.goals.base import Encoded, FloatArray, Goal, Pin, State, frame_index
from swarm_ik.kernels.rows import ball_rows, position_rows

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel


@numba.njit(cache=True)
def position_kernel(par, ipar, q, f_pos, f_rot, f_jac, want_jac, res, jac, err, work):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Rows ``p* − p`` of frame ``ipar[0]``; ``par = p*`` (3).

    With a flag ``ipar[1] = 1`` (a :attr:`Position.radius`), ``par[3]`` is the radius and the
    rows are :func:`~swarm_ik.kernels.rows.ball_rows`."""
    if ipar.shape[0] > 1 and ipar[1] != 0:
        err[0] = ball_rows(par[0:3], par[3], ipar[0], f_pos, f_jac, want_jac, res, jac)
    else:
        err[0] = position_rows(par, ipar[0], f_pos, f_jac, want_jac, res, jac)
    err[1] = np.nan


def ball_radius(value: Any) -> float | None:
    """``Position.radius`` checked: None, or a finite number ``>= 0`` [m] as a float.

    Raises:
        InvalidArgumentError: anything else, naming ``Position.radius``.
    """
    r = nonnegative(value, "Position.radius must be a finite number >= 0 (metres)", ())
    if r is None:
        return None
    return float(r)


@dataclass(frozen=True)
class Position(Goal):
    """The frame origin at a world point, ``r = p* − p`` [m], or within a ball about it.

    With ``radius = ρ`` the goal is the ball ``‖p − p*‖ <= ρ``: the rows are the offset from
    the origin to the ball's nearest point, ``r = −max(0, ‖d‖ − ρ)·u`` [m] (``d = p − p*``,
    ``u = d/‖d‖``; zero inside, continuous at the sphere), judged by its norm, the distance
    outside the ball.  Step Jacobian (``r(q + δ) ≈ r − J δ``):
    ``J = [(1 − ρ/‖d‖)(I − uuᵀ) + uuᵀ] J_v`` outside, ``uuᵀ J_v`` inside (the radial rows
    hold the distance to first order; continuous at the sphere; zero at ``d = 0``);
    :meth:`jacobian` is ``−J``.  ``ρ = 0`` is the exact point's rows.  (Three rows, not the
    one row ``−max(0, ‖d‖ − ρ)``: its Gauss–Newton step leaves the sideways motion free and
    converged from 2–3× fewer random starts.)

    Args:
        frame: Goal frame name.
        point: World point [m], 3 numbers.
        radius: None (the exact point, the default) or the ball's radius ``>= 0`` [m]
            (keyword-only).
        weight, primary: As :class:`~swarm_ik.goals.Goal` (keyword-only).
    """

    frame: str
    point: Any
    radius: Any = field(default=None, kw_only=True)
    kernel: ClassVar[Any] = position_kernel
    vectors: ClassVar[tuple[str, ...]] = ("point",)

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", ball_radius(self.radius))
        super().__post_init__()

    @staticmethod
    def params(target: FloatArray) -> FloatArray:
        """The float parameters of a target pose ``(4, 4)`` (its position) or ``(N, 4, 4)``."""
        return np.asarray(target, dtype=float)[..., :3, 3].copy()

    @property
    def exact(self) -> bool:
        return self.radius is None

    def pin(self) -> Pin:
        """The point (within the ball's radius)."""
        slack = 0.0 if self.radius is None else float(self.radius)
        return Pin(self.frame, point=np.asarray(self.point, dtype=float), point_slack=slack)

    def encode(self, robot: RobotModel, q0: FloatArray | None) -> Encoded:
        f = frame_index(self, robot)
        if self.radius is None:
            return Encoded(np.array(self.point, dtype=float), np.array([f], dtype=np.int64), 3)
        par = np.append(np.asarray(self.point, dtype=float), self.radius)
        return Encoded(par, np.array([f, 1], dtype=np.int64), 3)

    def pose_errors(self, poses: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The errors judged of poses ``(..., 4, 4)``: ``(distance [m], 0)`` each ``(...)``,
        the distance to the point, or beyond the ball with a radius."""
        d = np.hypot.reduce(np.asarray(poses, dtype=float)[..., :3, 3] - self.point, axis=-1)
        if self.radius is not None:
            d = np.maximum(d - self.radius, 0.0)
        return d, np.zeros_like(d)

    def residual(self, state: State) -> FloatArray:
        if self.radius is not None:
            d = state.pose(self.frame)[:3, 3] - self.point
            n = float(np.linalg.norm(d))
            return -max(n - self.radius, 0.0) * (d / n if n > 1e-12 else np.zeros(3))
        return np.asarray(self.point - state.pose(self.frame)[:3, 3])

    def jacobian(self, state: State) -> FloatArray:
        if self.radius is not None:
            d = state.pose(self.frame)[:3, 3] - self.point
            n = float(np.linalg.norm(d))
            u = d / n if n > 1e-12 else np.zeros(3)
            out = max(n - self.radius, 0.0)
            s = out / n if out > 0.0 else (1.0 if self.radius == 0.0 else 0.0)
            m = s * np.eye(3) + (1.0 - s) * np.outer(u, u)
            return -m @ state.jacobian(self.frame)[:3]
        return -state.jacobian(self.frame)[:3]

    def errors(self, state: State) -> tuple[float, float]:
        if self.radius is not None:
            return float(self.pose_errors(state.pose(self.frame))[0]), float("nan")
        return math.hypot(*self.residual(state).tolist()), float("nan")  # (no overflow)
