"""``JointGoal``: the base of the joint-space goals, ``r = w_j·(q_ref − q)``."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numba
import numpy as np

from swarm_ik.goals.base import Encoded, FloatArray, Goal, State

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel


@numba.njit(cache=True)
def joint_kernel(par, ipar, q, f_pos, f_rot, f_jac, want_jac, res, jac, err, work):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Rows ``w_j (q_ref − q)`` (continuous joints wrapped); ``par = [q_ref, w_j, continuous,
    prismatic]``, each ``(nq,)`` (the masks as 0/1).  Errors: the largest weighted joint's
    ``|q_ref − q|``, prismatic [m] and others [rad]."""
    nq = q.shape[0]
    e_lin = np.nan
    e_ang = np.nan
    for j in range(nq):
        d = par[j] - q[j]
        if par[2 * nq + j] != 0.0:
            d = (d + math.pi) % (2.0 * math.pi) - math.pi
        wj = par[nq + j]
        res[j] = wj * d
        if wj > 0.0:
            ad = abs(d)
            if par[3 * nq + j] != 0.0:
                if math.isnan(e_lin) or ad > e_lin:
                    e_lin = ad
            elif math.isnan(e_ang) or ad > e_ang:
                e_ang = ad
        if want_jac:
            for k in range(nq):
                jac[j, k] = 0.0
            jac[j, j] = wj
    err[0] = e_lin
    err[1] = e_ang


def encode_joint(ref: FloatArray, jw: FloatArray, continuous: Any, prismatic: Any) -> Encoded:
    """The parameter block of :func:`joint_kernel`: reference and weights ``(nq,)`` each,
    with the continuous and prismatic joint masks."""
    par = np.concatenate(
        [ref, jw, np.asarray(continuous, dtype=float), np.asarray(prismatic, dtype=float)]
    )
    return Encoded(par.astype(float), np.zeros(0, dtype=np.int64), int(np.size(ref)))


def joint_errors(
    ref: FloatArray, jw: FloatArray, q: FloatArray, robot: RobotModel
) -> tuple[float, float]:
    """Largest ``|q_ref − q|`` over the weighted joints: (prismatic [m], others [rad])."""
    d = np.abs(robot.wrap(ref - q) if robot.continuous_mask.any() else ref - q)
    on = jw > 0
    pri = on & robot.prismatic_mask
    rev = on & ~robot.prismatic_mask
    return (
        float(d[pri].max()) if pri.any() else float("nan"),
        float(d[rev].max()) if rev.any() else float("nan"),
    )


@dataclass(frozen=True)
class JointGoal(Goal):
    """Base of the joint-space goals: ``r = w_j·(q_ref − q)`` with the reference and the
    per-joint weights of :meth:`reference`."""

    primary: bool = field(default=False, kw_only=True)
    kernel: ClassVar[Any] = joint_kernel

    def reference(self, robot: RobotModel, q0: FloatArray | None) -> tuple[FloatArray, FloatArray]:
        """``(q_ref (nq,), joint weights (nq,))`` of the goal on ``robot`` (``q0``: the
        solve's start)."""
        raise NotImplementedError

    def encode(self, robot: RobotModel, q0: FloatArray | None) -> Encoded:
        ref, jw = self.reference(robot, q0)
        return encode_joint(ref, jw, robot.continuous_mask, robot.prismatic_mask)

    def residual(self, state: State) -> FloatArray:
        ref, jw = self.reference(state.robot, state.q0)
        return np.asarray(jw * state.robot.wrap(ref - state.q))

    def jacobian(self, state: State) -> FloatArray:
        _, jw = self.reference(state.robot, state.q0)
        return -np.diag(jw)

    def errors(self, state: State) -> tuple[float, float]:
        ref, jw = self.reference(state.robot, state.q0)
        return joint_errors(ref, jw, state.q, state.robot)
