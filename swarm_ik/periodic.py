"""The 2π period of revolute joints: which joints repeat with period 2π within their limits,
and the in-limit copies of a configuration (the model layer: numpy only, so that the solvers
and :mod:`swarm_ik.branches` above them share one definition)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from swarm_ik._types import BoolArray, FloatArray

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel

TWO_PI = 2.0 * np.pi
_LIMIT_SLACK = 1e-9
"""A copy counts as within the limits when it exceeds them by at most this (rad)."""


def periodic_mask(robot: RobotModel, lower: Any = None, upper: Any = None) -> BoolArray:
    """Joints on which solutions repeat with period 2π within the limits.

    Continuous joints, and revolute joints whose range ``upper − lower`` is at least 2π (a range
    of exactly 2π counts: its two ends are the same angle).

    Args:
        robot: The robot.
        lower: Bounds to use instead of the joint limits, shape ``(nq,)`` (e.g. a problem's).
        upper: Upper bounds, shape ``(nq,)``.

    Returns:
        Mask, shape ``(nq,)``.
    """
    lo = robot.lower if lower is None else np.asarray(lower, dtype=float)
    hi = robot.upper if upper is None else np.asarray(upper, dtype=float)
    kinds = np.array(robot.joint_kinds)
    wide = (kinds == "revolute") & (hi - lo >= TWO_PI - _LIMIT_SLACK)
    return np.asarray((kinds == "continuous") | wide, dtype=bool)


def winding_bounds(
    q: Any, lower: Any, upper: Any, revolute: BoolArray
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Smallest and largest ``m`` with ``q + 2π·m`` within ``[lower, upper]``, per joint.

    Non-revolute (prismatic) joints get ``m = 0`` when within the limits.  A joint with no
    in-limit copy has ``m_min > m_max``.

    Args:
        q: Joint vectors, shape ``(..., nq)``.
        lower, upper: Bounds, shape ``(nq,)``.
        revolute: Joints with a 2π period, shape ``(nq,)``.

    Returns:
        ``(m_min, m_max)``, integer arrays of the shape of ``q``.
    """
    q = np.asarray(q, dtype=float)
    lo = np.asarray(lower, dtype=float) - _LIMIT_SLACK
    hi = np.asarray(upper, dtype=float) + _LIMIT_SLACK
    m_min = np.ceil((lo - q) / TWO_PI)
    m_max = np.floor((hi - q) / TWO_PI)
    inside = (q >= lo) & (q <= hi)
    m_min = np.where(revolute, m_min, np.where(inside, 0.0, 1.0))
    m_max = np.where(revolute, m_max, 0.0)
    return m_min.astype(np.int64), m_max.astype(np.int64)


def nearest_winding(
    q: Any, lower: Any, upper: Any, revolute: BoolArray, ref: Any
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """The in-limit 2π copy of each configuration nearest to ``ref``.

    The joints are independent, so the nearest copy (Euclidean) takes, joint by joint, the
    in-limit copy nearest to ``ref``; the result is clipped into the bounds (it exceeds them by
    at most 1e-9 rad).

    Args:
        q: Joint vectors, shape ``(k, nq)`` or ``(nq,)``.
        lower, upper: Bounds, shape ``(nq,)``.
        revolute: Joints with a 2π period, shape ``(nq,)``.
        ref: Reference, shape ``(nq,)`` (``q0``, else the middle of the ranges).

    Returns:
        ``(copies, ok)``: the copies (shape of ``q``) and whether each has an in-limit copy at
        all (``(k,)`` or a 0-d array).
    """
    q = np.asarray(q, dtype=float)
    m_min, m_max = winding_bounds(q, lower, upper, revolute)
    ok = np.all(m_min <= m_max, axis=-1)
    m = np.clip(np.rint((np.asarray(ref, dtype=float) - q) / TWO_PI), m_min, m_max)
    out = np.clip(q + TWO_PI * m * revolute, lower, upper)
    return out, ok
