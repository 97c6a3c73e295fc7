"""Batched forward kinematics and frame Jacobian of a serial chain, derived from Pinocchio.

The chain is read off a (reduced, serial) Pinocchio model: for each joint its placement in the
parent joint frame (``model.jointPlacements``), its kind and its axis (from the joint's motion
subspace), and the end-effector frame placement in the last joint's frame.  The kernels are
compiled with numba (``cache=True``) and loop over the population and the joints with no
allocation inside, so a population of 1000 costs a fraction of a millisecond and a single pose
about a microsecond, against several microseconds per call of Pinocchio from Python
(``docs/performance.md`` gives the measured ratios).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

REVOLUTE = 0
PRISMATIC = 1
CONTINUOUS = 2
KIND_NAMES = ("revolute", "prismatic", "continuous")


@numba.njit(cache=True, fastmath=False)
def _rodrigues(ax: FloatArray, angle: float, out: FloatArray) -> None:  # pragma: no cover
    c = np.cos(angle)
    s = np.sin(angle)
    t = 1.0 - c
    x, y, z = ax[0], ax[1], ax[2]
    out[0, 0] = t * x * x + c
    out[0, 1] = t * x * y - s * z
    out[0, 2] = t * x * z + s * y
    out[1, 0] = t * x * y + s * z
    out[1, 1] = t * y * y + c
    out[1, 2] = t * y * z - s * x
    out[2, 0] = t * x * z - s * y
    out[2, 1] = t * y * z + s * x
    out[2, 2] = t * z * z + c


def _rotation_z_to(axis: FloatArray) -> FloatArray:
    """A rotation matrix taking the z axis onto the unit vector ``axis``."""
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    if np.array_equal(a, [0.0, 0.0, 1.0]):
        return np.eye(3)
    if a[2] < 0.0:  # a half turn about x first keeps the formula below well conditioned
        half = np.diag([1.0, -1.0, -1.0])
        return half @ _rotation_z_to(half @ a)
    v = np.cross([0.0, 0.0, 1.0], a)  # sin θ · unit rotation axis
    k = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + k + k @ k / (1.0 + float(a[2]))


@dataclass(frozen=True)
class ChainKinematics:
    """A serial chain as arrays, with batched FK and Jacobian.

    Attributes:
        kinds: Joint kind codes (``REVOLUTE``, ``PRISMATIC``, ``CONTINUOUS``), shape ``(nq,)``.
        axes: Unit joint axes in each joint's own frame, shape ``(nq, 3)``.
        rot_p: Rotation of each joint's placement in its parent joint frame, ``(nq, 3, 3)``.
        pos_p: Translation of each joint's placement [m], ``(nq, 3)``.
        rot_f: Rotation of the end-effector frame in the last joint frame, ``(3, 3)``.
        pos_f: Translation of the end-effector frame [m], ``(3,)``.
    """

    kinds: NDArray[np.int64]
    axes: FloatArray
    rot_p: FloatArray
    pos_p: FloatArray
    rot_f: FloatArray
    pos_f: FloatArray

    @classmethod
    def canonical(
        cls,
        kinds: NDArray[np.int64],
        axes: FloatArray,
        rot_p: FloatArray,
        pos_p: FloatArray,
        rot_f: FloatArray,
        pos_f: FloatArray,
    ) -> ChainKinematics:
        """The same chain with every joint axis turned onto z (so FK needs no Rodrigues).

        With ``B_j`` a rotation taking z onto axis ``a_j``, the motion about (along) ``a_j`` is
        ``B_j · motion_z · B_jᵀ``; the ``B``'s are folded into the placements:
        ``R'_j = B_{j-1}ᵀ R_j B_j``, ``p'_j = B_{j-1}ᵀ p_j`` and the end-effector frame
        ``(B_nᵀ R_f, B_nᵀ p_f)``.  Poses and Jacobians are unchanged (joint origins and world
        axes are the same); each revolute step costs a 2-column update instead of a 3x3
        product.

        Args:
            kinds, axes, rot_p, pos_p, rot_f, pos_f: As the attributes, any unit axes.
        """
        n = kinds.shape[0]
        basis = np.empty((n, 3, 3))
        for j in range(n):
            basis[j] = _rotation_z_to(axes[j])
        new_rot = np.empty((n, 3, 3))
        new_pos = np.empty((n, 3))
        prev = np.eye(3)
        for j in range(n):
            new_rot[j] = prev.T @ rot_p[j] @ basis[j]
            new_pos[j] = prev.T @ pos_p[j]
            prev = basis[j]
        z = np.zeros((n, 3))
        z[:, 2] = 1.0
        return cls(
            kinds=np.ascontiguousarray(kinds, dtype=np.int64),
            axes=z,
            rot_p=np.ascontiguousarray(new_rot),
            pos_p=np.ascontiguousarray(new_pos),
            rot_f=np.ascontiguousarray(prev.T @ rot_f),
            pos_f=np.ascontiguousarray(prev.T @ pos_f),
        )

    @property
    def nq(self) -> int:
        """Number of joints."""
        return int(self.kinds.shape[0])

    def _prep(self, q: FloatArray) -> tuple[FloatArray, bool]:
        q = np.asarray(q, dtype=np.float64)
        single = q.ndim == 1
        q2 = np.ascontiguousarray(q.reshape(1, -1) if single else q)
        if q2.ndim != 2 or q2.shape[1] != self.nq:
            from swarm_ik.errors import InvalidArgumentError

            raise InvalidArgumentError(
                f"joint vector(s) must have shape (nq,) or (pop, nq) with nq = {self.nq}; "
                f"got {q.shape}"
            )
        return q2, single

    def fk(self, q: FloatArray) -> FloatArray:
        """End-effector pose(s).

        Args:
            q: Joint values (rad or m), shape ``(nq,)`` or ``(pop, nq)``.

        Returns:
            Poses, shape ``(4, 4)`` or ``(pop, 4, 4)``.
        """
        q2, single = self._prep(q)
        out = np.empty((q2.shape[0], 4, 4))
        _chain(
            q2,
            self.kinds,
            self.axes,
            self.rot_p,
            self.pos_p,
            self.rot_f,
            self.pos_f,
            out,
            np.empty((1, 1, 1)),
            False,
        )
        return out[0] if single else out

    def fk_jacobian(self, q: FloatArray) -> tuple[FloatArray, FloatArray]:
        """End-effector pose(s) and frame Jacobian(s) in the LOCAL_WORLD_ALIGNED convention.

        The Jacobian maps joint velocities to ``[v; ω]``: ``v`` the velocity of the
        end-effector origin and ``ω`` the angular velocity, both in world axes (Pinocchio's
        ``getFrameJacobian(..., LOCAL_WORLD_ALIGNED)``).

        Args:
            q: Joint values, shape ``(nq,)`` or ``(pop, nq)``.

        Returns:
            ``(poses (pop, 4, 4), jac (pop, 6, nq))``, without the ``pop`` axis for a single q.
        """
        q2, single = self._prep(q)
        pop = q2.shape[0]
        out_t = np.empty((pop, 4, 4))
        out_j = np.empty((pop, 6, self.nq))
        _chain(
            q2,
            self.kinds,
            self.axes,
            self.rot_p,
            self.pos_p,
            self.rot_f,
            self.pos_f,
            out_t,
            out_j,
            True,
        )
        return (out_t[0], out_j[0]) if single else (out_t, out_j)


@numba.njit(cache=True)
def fk_jac_one(
    q: FloatArray,
    kinds: NDArray[np.int64],
    axes: FloatArray,
    rot_p: FloatArray,
    pos_p: FloatArray,
    rot_f: FloatArray,
    pos_f: FloatArray,
    rot_out: FloatArray,
    pos_out: FloatArray,
    jac_out: FloatArray,
    w_buf: FloatArray,
    o_buf: FloatArray,
    mot: FloatArray,
    tmp: FloatArray,
    want_jac: bool,
) -> None:  # pragma: no cover - compiled
    """FK (and Jacobian) of ONE configuration into caller-owned buffers, no allocation.

    The same computation as the batched kernel behind :meth:`ChainKinematics.fk_jacobian`
    (identical results), for compiled loops that evaluate one configuration at a time (the
    Levenberg–Marquardt polish of :mod:`swarm_ik.solvers.hybrid`).

    Args:
        q: Joint values, shape ``(nq,)``.
        kinds, axes, rot_p, pos_p, rot_f, pos_f: The chain (see :class:`ChainKinematics`).
        rot_out: Output end-effector rotation, shape ``(3, 3)``.
        pos_out: Output end-effector position [m], shape ``(3,)``.
        jac_out: Output LOCAL_WORLD_ALIGNED Jacobian ``[v; ω]``, shape ``(6, nq)`` (untouched
            when ``want_jac`` is False).
        w_buf, o_buf: Scratch, shape ``(nq, 3)`` each.
        mot, tmp: Scratch, shape ``(3, 3)`` each.
        want_jac: Whether to fill ``jac_out``.
    """
    n = q.shape[0]
    rot = rot_out
    pos = pos_out
    for a in range(3):
        pos[a] = 0.0
        for b in range(3):
            rot[a, b] = 1.0 if a == b else 0.0
    for j in range(n):
        for a in range(3):
            pos[a] += rot[a, 0] * pos_p[j, 0] + rot[a, 1] * pos_p[j, 1] + rot[a, 2] * pos_p[j, 2]
        for a in range(3):
            for b in range(3):
                tmp[a, b] = (
                    rot[a, 0] * rot_p[j, 0, b]
                    + rot[a, 1] * rot_p[j, 1, b]
                    + rot[a, 2] * rot_p[j, 2, b]
                )
        for a in range(3):
            for b in range(3):
                rot[a, b] = tmp[a, b]
        if want_jac:
            for a in range(3):
                w_buf[j, a] = (
                    rot[a, 0] * axes[j, 0] + rot[a, 1] * axes[j, 1] + rot[a, 2] * axes[j, 2]
                )
                o_buf[j, a] = pos[a]
        qj = q[j]
        if kinds[j] == PRISMATIC:
            for a in range(3):
                pos[a] += qj * (
                    rot[a, 0] * axes[j, 0] + rot[a, 1] * axes[j, 1] + rot[a, 2] * axes[j, 2]
                )
        elif axes[j, 2] == 1.0 and axes[j, 0] == 0.0 and axes[j, 1] == 0.0:
            # rotation about z (every joint of a canonical chain): rot <- rot @ Rz(qj)
            c = np.cos(qj)
            s = np.sin(qj)
            for a in range(3):
                r0 = rot[a, 0]
                r1 = rot[a, 1]
                rot[a, 0] = c * r0 + s * r1
                rot[a, 1] = c * r1 - s * r0
        else:
            _rodrigues(axes[j], qj, mot)
            for a in range(3):
                for b in range(3):
                    tmp[a, b] = (
                        rot[a, 0] * mot[0, b] + rot[a, 1] * mot[1, b] + rot[a, 2] * mot[2, b]
                    )
            for a in range(3):
                for b in range(3):
                    rot[a, b] = tmp[a, b]
    # end-effector frame in the last joint's frame
    for a in range(3):
        pos[a] = pos[a] + rot[a, 0] * pos_f[0] + rot[a, 1] * pos_f[1] + rot[a, 2] * pos_f[2]
    for a in range(3):
        for b in range(3):
            tmp[a, b] = rot[a, 0] * rot_f[0, b] + rot[a, 1] * rot_f[1, b] + rot[a, 2] * rot_f[2, b]
    for a in range(3):
        for b in range(3):
            rot[a, b] = tmp[a, b]
    if want_jac:
        for j in range(n):
            if kinds[j] == PRISMATIC:
                for a in range(3):
                    jac_out[a, j] = w_buf[j, a]
                    jac_out[3 + a, j] = 0.0
            else:
                dx = pos[0] - o_buf[j, 0]
                dy = pos[1] - o_buf[j, 1]
                dz = pos[2] - o_buf[j, 2]
                wx, wy, wz = w_buf[j, 0], w_buf[j, 1], w_buf[j, 2]
                jac_out[0, j] = wy * dz - wz * dy
                jac_out[1, j] = wz * dx - wx * dz
                jac_out[2, j] = wx * dy - wy * dx
                jac_out[3, j] = wx
                jac_out[4, j] = wy
                jac_out[5, j] = wz


@numba.njit(cache=True)
def _chain(
    q: FloatArray,
    kinds: NDArray[np.int64],
    axes: FloatArray,
    rot_p: FloatArray,
    pos_p: FloatArray,
    rot_f: FloatArray,
    pos_f: FloatArray,
    out_t: FloatArray,
    out_j: FloatArray,
    want_jac: bool,
) -> None:  # pragma: no cover - compiled
    """Batched FK (and Jacobian): :func:`fk_jac_one` for each row of ``q`` ``(pop, nq)``."""
    pop, n = q.shape
    rot = np.empty((3, 3))
    pos = np.empty(3)
    tmp = np.empty((3, 3))
    mot = np.empty((3, 3))
    w_buf = np.empty((n, 3))
    o_buf = np.empty((n, 3))
    jac = np.empty((6, n))
    for k in range(pop):
        fk_jac_one(
            q[k], kinds, axes, rot_p, pos_p, rot_f, pos_f,
            rot, pos, jac, w_buf, o_buf, mot, tmp, want_jac,
        )  # fmt: skip
        for a in range(3):
            out_t[k, a, 3] = pos[a]
            for b in range(3):
                out_t[k, a, b] = rot[a, b]
            out_t[k, 3, a] = 0.0
        out_t[k, 3, 3] = 1.0
        if want_jac:
            for a in range(6):
                for j in range(n):
                    out_j[k, a, j] = jac[a, j]
