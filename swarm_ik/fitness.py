"""Batched fitness functions: end-effector poses ``(pop, 4, 4)`` against a target → ``(pop,)``.

Positions in metres, angles in radians.  Lower is better, zero at the target.

* ``"se3"``: ``‖Δp‖ + w_rot·θ`` with ``θ = ‖log(R_targetᵀ R)‖`` the geodesic rotation error.
* ``"paper-l1"``: eq. 3 of [HLFOA], ``λ·(|Δx|+|Δy|+|Δz|) + Σ|ΔR_ij|`` over the 9
  rotation entries.  The paper uses millimetres with ``λ = 1e-2``; in metres ``λ = 10`` gives
  the same values.
* ``"euler-zyz"``: eq. 15 of [MGWO], ``μ·(|Δx|+|Δy|+|Δz|) + |Δα|+|Δβ|+|Δγ|`` with
  ZYZ Euler angles, ``μ = 1``.  Two departures from the printed equation (ours, named here):
  the angle differences are wrapped to ``(−π, π]`` (eq. 15 subtracts them plainly, so
  ``α = π − ε`` and ``−π + ε`` would count as ``2π`` apart), and at ``β = 0`` or ``π``, where
  the split between ``α`` and ``γ`` is arbitrary, ``α = 0`` (the whole yaw in ``γ``).
* ``"paper-pso"``: eqs. 3–5 of [PSO-IK], ``|Δp|² + (N·N* + O·O* + A·A* − 3)²``.  The paper
  prints the orientation term legibly as ``(N·N* + O·O* + A·A* − 1)²`` (eq. 4, and its
  derivative eq. 11), which is wrong: ``N·N* + O·O* + A·A* = 1 + 2·cos θ`` for a rotation
  error ``θ``, so the printed term is zero at ``θ = 90°`` and 4 when the frames agree; ``− 3``
  makes it zero when the frames agree.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from swarm_ik._types import FloatArray
from swarm_ik.errors import unknown
from swarm_ik.kernels.lie import angle as rotation_angle


def wrap_angle(a: FloatArray) -> FloatArray:
    """Angles wrapped to ``(−π, π]``."""
    return np.pi - np.mod(np.pi - a, 2.0 * np.pi)


def zyz_euler(rot: FloatArray) -> FloatArray:
    """ZYZ Euler angles ``(α, β, γ)`` of rotations ``(..., 3, 3)`` → ``(..., 3)``; β ∈ [0, π]."""
    r13, r23, r33 = rot[..., 0, 2], rot[..., 1, 2], rot[..., 2, 2]
    r31, r32 = rot[..., 2, 0], rot[..., 2, 1]
    sin_b = np.hypot(r31, r32)
    beta = np.arctan2(sin_b, r33)
    alpha = np.arctan2(r23, r13)
    gamma = np.arctan2(r32, -r31)
    # At β = 0 (R = Rz(α+γ)) or β = π (R = Rz(α)·Ry(π)·Rz(γ), only α−γ matters) the split
    # between α and γ is arbitrary: take α = 0 so the whole yaw lands in γ and is not lost.
    singular = sin_b < 1e-12
    if np.any(singular):
        r10, r00, r11 = rot[..., 1, 0], rot[..., 0, 0], rot[..., 1, 1]
        gamma_sing = np.where(r33 > 0, np.arctan2(r10, r00), np.arctan2(r10, r11))
        alpha = np.where(singular, 0.0, alpha)
        gamma = np.where(singular, gamma_sing, gamma)
    return np.stack([alpha, beta, gamma], axis=-1)


def se3_fitness(
    poses: FloatArray, target: FloatArray, *, w_rot: float = 1.0, **_: Any
) -> FloatArray:
    """``‖Δp‖ [m] + w_rot·θ [rad]`` for poses ``(pop, 4, 4)``."""
    dp = np.linalg.norm(poses[:, :3, 3] - target[:3, 3], axis=-1)
    if w_rot == 0.0:
        return dp
    rot_err = np.einsum("ji,njk->nik", target[:3, :3], poses[:, :3, :3])
    return dp + w_rot * rotation_angle(rot_err)


def paper_l1_fitness(
    poses: FloatArray, target: FloatArray, *, lam: float = 10.0, **_: Any
) -> FloatArray:
    """Eq. 3 of [HLFOA]: ``λ·L1(Δp [m]) + Σ|R − R_target|`` (λ = 10 per metre)."""
    dp = np.abs(poses[:, :3, 3] - target[:3, 3]).sum(axis=-1)
    dr = np.abs(poses[:, :3, :3] - target[:3, :3]).sum(axis=(-1, -2))
    return lam * dp + dr


def euler_zyz_fitness(
    poses: FloatArray, target: FloatArray, *, mu: float = 1.0, **_: Any
) -> FloatArray:
    """Eq. 15 of [MGWO]: ``μ·L1(Δp [m]) + L1(wrapped ΔZYZ [rad])``."""
    dp = np.abs(poses[:, :3, 3] - target[:3, 3]).sum(axis=-1)
    de = wrap_angle(zyz_euler(poses[:, :3, :3]) - zyz_euler(target[:3, :3]))
    return mu * dp + np.abs(de).sum(axis=-1)


def paper_pso_fitness(poses: FloatArray, target: FloatArray, **_: Any) -> FloatArray:
    """Eqs. 3–5 of [PSO-IK]: ``|Δp|² + (tr(R_targetᵀR) − 3)²``."""
    dp2 = np.sum((poses[:, :3, 3] - target[:3, 3]) ** 2, axis=-1)
    tr = np.einsum("ij,nij->n", target[:3, :3], poses[:, :3, :3])
    return dp2 + (tr - 3.0) ** 2


FITNESS: dict[str, Callable[..., FloatArray]] = {
    "se3": se3_fitness,
    "paper-l1": paper_l1_fitness,
    "euler-zyz": euler_zyz_fitness,
    "paper-pso": paper_pso_fitness,
}
"""Fitness functions by name."""


def get_fitness(name: str) -> Callable[..., FloatArray]:
    """The fitness function called ``name``; the error lists the valid names."""
    try:
        return FITNESS[name]
    except KeyError:
        raise unknown("fitness", name, FITNESS) from None
