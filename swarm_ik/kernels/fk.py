"""Forward kinematics and Jacobians of every goal frame of a kinematic tree, in one pass.

The tree is read off a reduced Pinocchio model (:mod:`swarm_ik.robot`): for each joint its
parent joint, its placement in the parent joint frame, its kind and axis, and which entry of
the joint vector drives it (``q_index``; a mimic follower reads its driver's value as
``multiplier·q + offset``).  The frames are any frames of the model (goal frames, collision
bodies), each a placement in a joint frame (or in the root when ``frame_joint == -1``).

Every joint axis is turned onto z (:meth:`TreeArrays.canonical`), so a revolute step is a
two-column update.  The kernels loop with no allocation: :func:`fk_one` fills caller-owned
buffers for one configuration (used inside the LM kernel), :func:`fk_batch` runs it over a
population.  Tested against Pinocchio's ``framesForwardKinematics`` and ``getFrameJacobian``
(LOCAL_WORLD_ALIGNED) to 1e-12 on chains and trees (``tests/test_fk_tree.py``).
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np
from numba.extending import register_jitable

from swarm_ik._types import FloatArray, IntArray
from swarm_ik.kernels import loaded_despite_damage
from swarm_ik.kernels.lie import exp3_nb, jr_nb

REVOLUTE = 0
PRISMATIC = 1
CONTINUOUS = 2
BALL = 3
"""A rotation of three joint-vector entries ``r = q[i:i+3]`` (a rotation vector: the joint
turns by ``exp([r]×)``), the orientation of a floating base; no gimbal lock (``exp`` is
regular for ``‖r‖ < 2π``, and the bounds keep ``|r_k| ≤ π``)."""
KIND_NAMES = ("revolute", "prismatic", "continuous", "ball")


def rotation_z_to(axis: FloatArray) -> FloatArray:
    """A rotation matrix taking the z axis onto the unit vector ``axis`` (3,)."""
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    if np.array_equal(a, [0.0, 0.0, 1.0]):
        return np.eye(3)
    if a[2] < 0.0:  # a half turn about x first keeps the formula below well conditioned
        half = np.diag([1.0, -1.0, -1.0])
        return half @ rotation_z_to(half @ a)
    v = np.cross([0.0, 0.0, 1.0], a)  # sin θ · unit rotation axis
    k = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + k + k @ k / (1.0 + float(a[2]))


_FK_CALLS = [0]
"""Batched FK calls this process made (:func:`_first_fk`)."""


def _first_fk() -> bool:
    """Whether this is the process's first batched FK call (the one that loads its kernel
    from numba's cache: marked, see :func:`swarm_ik.kernels.loading_marked`)."""
    _FK_CALLS[0] += 1
    return _FK_CALLS[0] == 1  # (with or without Jacobians: one signature, one kernel)


class TreeArrays(NamedTuple):
    """A kinematic tree as arrays (every joint axis on z), with its frames.

    Joints are in topological order (``parent[j] < j``).  ``nq`` is the length of the joint
    vector; ``nj >= nq`` the number of joints in the tree (mimic followers included).

    Attributes:
        kind: Joint kind codes (``REVOLUTE``, ``PRISMATIC``, ``CONTINUOUS``, ``BALL``), shape
            ``(nj,)``.
        parent: Parent joint index, ``-1`` for a joint on the root, shape ``(nj,)``.
        q_index: Entry of the joint vector driving each joint (a ``BALL``: the first of its
            three), shape ``(nj,)``.
        multiplier: Joint value = ``multiplier·q[q_index] + offset``, shape ``(nj,)``.
        offset: See ``multiplier`` (rad or m), shape ``(nj,)``.
        rot_p: Rotation of each joint's placement in its parent joint frame, ``(nj, 3, 3)``.
        pos_p: Translation of each joint's placement [m], ``(nj, 3)``.
        frame_joint: Joint each frame is attached to (``-1``: the root), shape ``(nf,)``.
        frame_rot: Rotation of each frame in its joint frame, ``(nf, 3, 3)``.
        frame_pos: Translation of each frame in its joint frame [m], ``(nf, 3)``.
        nq: Length of the joint vector.
    """

    kind: IntArray
    parent: IntArray
    q_index: IntArray
    multiplier: FloatArray
    offset: FloatArray
    rot_p: FloatArray
    pos_p: FloatArray
    frame_joint: IntArray
    frame_rot: FloatArray
    frame_pos: FloatArray
    nq: int

    @classmethod
    def canonical(
        cls,
        kind: IntArray,
        parent: IntArray,
        q_index: IntArray,
        multiplier: FloatArray,
        offset: FloatArray,
        axes: FloatArray,
        rot_p: FloatArray,
        pos_p: FloatArray,
        frame_joint: IntArray,
        frame_rot: FloatArray,
        frame_pos: FloatArray,
        nq: int,
    ) -> TreeArrays:
        """The tree with every joint axis turned onto z (so FK needs no Rodrigues).

        With ``B_j`` a rotation taking z onto axis ``a_j``, the motion about (along) ``a_j``
        is ``B_j · motion_z · B_jᵀ``; the ``B``'s are folded into the placements:
        ``R'_j = B_parentᵀ R_j B_j``, ``p'_j = B_parentᵀ p_j`` and each frame
        ``(B_jᵀ R_f, B_jᵀ p_f)``.  Poses and Jacobians are unchanged.

        Args:
            kind, parent, q_index, multiplier, offset: As the attributes.
            axes: Unit joint axes in each joint's own frame, shape ``(nj, 3)``.
            rot_p, pos_p, frame_joint, frame_rot, frame_pos, nq: As the attributes, with the
                joint frames of the model (any axes).
        """
        nj = int(kind.shape[0])
        basis = np.array([rotation_z_to(axes[j]) for j in range(nj)]).reshape(nj, 3, 3)
        eye = np.eye(3)
        new_rot = np.empty((nj, 3, 3))
        new_pos = np.empty((nj, 3))
        for j in range(nj):
            bp = basis[parent[j]] if parent[j] >= 0 else eye
            new_rot[j] = bp.T @ rot_p[j] @ basis[j]
            new_pos[j] = bp.T @ pos_p[j]
        nf = int(frame_joint.shape[0])
        f_rot = np.empty((nf, 3, 3))
        f_pos = np.empty((nf, 3))
        for f in range(nf):
            bj = basis[frame_joint[f]] if frame_joint[f] >= 0 else eye
            f_rot[f] = bj.T @ frame_rot[f]
            f_pos[f] = bj.T @ frame_pos[f]
        return cls(
            kind=np.ascontiguousarray(kind, dtype=np.int64),
            parent=np.ascontiguousarray(parent, dtype=np.int64),
            q_index=np.ascontiguousarray(q_index, dtype=np.int64),
            multiplier=np.ascontiguousarray(multiplier, dtype=float),
            offset=np.ascontiguousarray(offset, dtype=float),
            rot_p=np.ascontiguousarray(new_rot),
            pos_p=np.ascontiguousarray(new_pos),
            frame_joint=np.ascontiguousarray(frame_joint, dtype=np.int64),
            frame_rot=np.ascontiguousarray(f_rot),
            frame_pos=np.ascontiguousarray(f_pos),
            nq=int(nq),
        )

    @property
    def nj(self) -> int:
        """Number of joints in the tree."""
        return int(self.kind.shape[0])

    @property
    def nf(self) -> int:
        """Number of frames."""
        return int(self.frame_joint.shape[0])

    def with_frames(
        self, frame_joint: IntArray, frame_rot: FloatArray, frame_pos: FloatArray
    ) -> TreeArrays:
        """The same joints with other frames, given in the canonical joint frames (as
        ``frame_rot``/``frame_pos`` of this object)."""
        return self._replace(
            frame_joint=np.ascontiguousarray(frame_joint, dtype=np.int64),
            frame_rot=np.ascontiguousarray(frame_rot, dtype=float),
            frame_pos=np.ascontiguousarray(frame_pos, dtype=float),
        )

    def fk(self, q: FloatArray) -> FloatArray:
        """Poses of every frame: ``(nq,) -> (nf, 4, 4)`` or ``(pop, nq) -> (pop, nf, 4, 4)``."""
        q2, single = self._prep(q)
        out_t = np.empty((q2.shape[0], self.nf, 4, 4))
        loaded_despite_damage(
            lambda: fk_batch(q2, self, out_t, np.empty((1, 1, 6, 1)), False), mark=_first_fk()
        )
        return out_t[0] if single else out_t

    def fk_jacobian(self, q: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Poses ``(…, nf, 4, 4)`` and LOCAL_WORLD_ALIGNED Jacobians ``(…, nf, 6, nq)``
        (rows ``[v; ω]``: frame-origin velocity and angular velocity in world axes)."""
        q2, single = self._prep(q)
        pop = q2.shape[0]
        out_t = np.empty((pop, self.nf, 4, 4))
        out_j = np.empty((pop, self.nf, 6, self.nq))
        loaded_despite_damage(lambda: fk_batch(q2, self, out_t, out_j, True), mark=_first_fk())
        return (out_t[0], out_j[0]) if single else (out_t, out_j)

    def _prep(self, q: FloatArray) -> tuple[FloatArray, bool]:
        arr = np.asarray(q, dtype=np.float64)
        single = arr.ndim == 1
        q2 = np.ascontiguousarray(arr.reshape(1, -1) if single else arr)
        if q2.ndim != 2 or q2.shape[1] != self.nq:
            from swarm_ik.errors import InvalidArgumentError

            raise InvalidArgumentError(
                f"joint vector(s) must have shape (nq,) or (pop, nq) with nq = {self.nq}; "
                f"got {arr.shape}"
            )
        return q2, single


class FKScratch(NamedTuple):
    """Caller-owned buffers of :func:`fk_one` (allocate once with :func:`fk_scratch`).

    Attributes:
        j_rot: World rotation of each joint frame, ``(nj, 3, 3)``.
        j_pos: World position of each joint origin [m], ``(nj, 3)``.
        f_rot: World rotation of each frame, ``(nf, 3, 3)``.
        f_pos: World position of each frame [m], ``(nf, 3)``.
        f_jac: LOCAL_WORLD_ALIGNED Jacobian of each frame, ``(nf, 6, nq)``.
        ball: Scratch of a ``BALL`` joint's rotation, ``(3, 3)``.
    """

    j_rot: FloatArray
    j_pos: FloatArray
    f_rot: FloatArray
    f_pos: FloatArray
    f_jac: FloatArray
    ball: FloatArray


@register_jitable
def fk_scratch(tree: TreeArrays) -> FKScratch:
    """Buffers for :func:`fk_one` on ``tree`` (callable from Python and from compiled code:
    ``numba.extending.register_jitable``)."""
    nj = tree.kind.shape[0]
    nf = tree.frame_joint.shape[0]
    return FKScratch(
        np.empty((nj, 3, 3)),
        np.empty((nj, 3)),
        np.empty((nf, 3, 3)),
        np.empty((nf, 3)),
        np.empty((nf, 6, tree.nq)),
        np.empty((3, 3)),
    )


@numba.njit(cache=True, inline="always")
def place(
    j_rot: FloatArray,
    j_pos: FloatArray,
    j: int,
    rot: FloatArray,
    pos: FloatArray,
    i: int,
    out_rot: FloatArray,
    out_pos: FloatArray,
    k: int,
) -> None:  # pragma: no cover - compiled
    """World placement of placement ``i`` of ``rot`` ``(·, 3, 3)`` / ``pos`` ``(·, 3)``, given
    in joint ``j``'s frame (``j < 0``: the root), into entry ``k`` of ``out_rot`` /
    ``out_pos``: ``R_j rot[i]`` and ``p_j + R_j pos[i]``.  Indices rather than row views:
    a view per call is an array structure built and reference-counted in the innermost loop
    (FK with Jacobians took 5–8 % longer so, measured in one process)."""
    for a in range(3):
        if j < 0:
            out_pos[k, a] = pos[i, a]
            for b in range(3):
                out_rot[k, a, b] = rot[i, a, b]
        else:
            r0, r1, r2 = j_rot[j, a, 0], j_rot[j, a, 1], j_rot[j, a, 2]
            out_pos[k, a] = j_pos[j, a] + (r0 * pos[i, 0] + r1 * pos[i, 1] + r2 * pos[i, 2])
            for b in range(3):
                out_rot[k, a, b] = r0 * rot[i, 0, b] + r1 * rot[i, 1, b] + r2 * rot[i, 2, b]


@numba.njit(cache=True, inline="always")
def fk_one(
    q: FloatArray, t: TreeArrays, s: FKScratch, want_jac: bool
) -> None:  # pragma: no cover - compiled
    """FK (and Jacobians) of every frame of the tree for ONE configuration, no allocation.

    Args:
        q: Joint vector, shape ``(nq,)``.
        t: The tree (canonical: every axis on z).
        s: Output buffers: ``s.f_rot``, ``s.f_pos`` and, when ``want_jac``, ``s.f_jac``.
        want_jac: Whether to fill ``s.f_jac``.
    """
    fk_fields(
        q, t.kind, t.parent, t.q_index, t.multiplier, t.offset, t.rot_p, t.pos_p,
        t.frame_joint, t.frame_rot, t.frame_pos, s.j_rot, s.j_pos, s.f_rot, s.f_pos, s.f_jac,
        s.ball, want_jac,
    )  # fmt: skip


@numba.njit(cache=True, inline="always")
def fk_fields(
    q: FloatArray,
    kind: IntArray,
    parent: IntArray,
    q_index: IntArray,
    mult: FloatArray,
    offset: FloatArray,
    rot_p: FloatArray,
    pos_p: FloatArray,
    frame_joint: IntArray,
    frame_rot: FloatArray,
    frame_pos: FloatArray,
    jr: FloatArray,
    jp: FloatArray,
    f_rot: FloatArray,
    f_pos: FloatArray,
    f_jac: FloatArray,
    ball: FloatArray,
    want_jac: bool,
) -> None:  # pragma: no cover - compiled
    """:func:`fk_one` with the fields of the tree (:class:`TreeArrays`) and of the scratch
    (:class:`FKScratch`: ``jr`` = ``j_rot``, ``jp`` = ``j_pos``) given one by one, for a
    loop that reads them once before it starts (the LM loop of
    :func:`swarm_ik.kernels.lm.lm_run`): each read of a tuple's array field takes a
    reference count and gives it back, about 60 ns per evaluation here (see
    ``docs/performance.md``)."""
    nj = kind.shape[0]
    for j in range(nj):
        place(jr, jp, parent[j], rot_p, pos_p, j, jr, jp, j)
        if kind[j] == BALL:  # rot <- rot @ exp([r]x)
            i = q_index[j]
            m3 = ball
            exp3_nb(q[i], q[i + 1], q[i + 2], m3)
            for a in range(3):
                r0, r1, r2 = jr[j, a, 0], jr[j, a, 1], jr[j, a, 2]
                for b in range(3):
                    jr[j, a, b] = r0 * m3[0, b] + r1 * m3[1, b] + r2 * m3[2, b]
            continue
        v = mult[j] * q[q_index[j]] + offset[j]
        if kind[j] == PRISMATIC:
            for a in range(3):
                jp[j, a] += v * jr[j, a, 2]
        else:  # rotation about z: rot <- rot @ Rz(v)
            c = np.cos(v)
            sn = np.sin(v)
            for a in range(3):
                r0 = jr[j, a, 0]
                r1 = jr[j, a, 1]
                jr[j, a, 0] = c * r0 + sn * r1
                jr[j, a, 1] = c * r1 - sn * r0
    nf = frame_joint.shape[0]
    nq = f_jac.shape[2]
    for f in range(nf):
        j = frame_joint[f]
        place(jr, jp, j, frame_rot, frame_pos, f, f_rot, f_pos, f)
        if want_jac:
            for a in range(6):
                for i in range(nq):
                    f_jac[f, a, i] = 0.0
            px, py, pz = f_pos[f, 0], f_pos[f, 1], f_pos[f, 2]
            k = j
            while k >= 0:  # every joint supporting the frame
                wx, wy, wz = jr[k, 0, 2], jr[k, 1, 2], jr[k, 2, 2]
                m = mult[k]
                col = q_index[k]
                if kind[k] == BALL:
                    # world angular velocity R·Jr(r)·ṙ: three columns, each an axis through
                    # the joint origin
                    m3 = ball
                    jr_nb(q[col], q[col + 1], q[col + 2], m3)
                    dx = px - jp[k, 0]
                    dy = py - jp[k, 1]
                    dz = pz - jp[k, 2]
                    for c in range(3):
                        wx = (
                            jr[k, 0, 0] * m3[0, c] + jr[k, 0, 1] * m3[1, c] + jr[k, 0, 2] * m3[2, c]
                        )
                        wy = (
                            jr[k, 1, 0] * m3[0, c] + jr[k, 1, 1] * m3[1, c] + jr[k, 1, 2] * m3[2, c]
                        )
                        wz = (
                            jr[k, 2, 0] * m3[0, c] + jr[k, 2, 1] * m3[1, c] + jr[k, 2, 2] * m3[2, c]
                        )
                        f_jac[f, 0, col + c] += wy * dz - wz * dy
                        f_jac[f, 1, col + c] += wz * dx - wx * dz
                        f_jac[f, 2, col + c] += wx * dy - wy * dx
                        f_jac[f, 3, col + c] += wx
                        f_jac[f, 4, col + c] += wy
                        f_jac[f, 5, col + c] += wz
                elif kind[k] == PRISMATIC:
                    f_jac[f, 0, col] += m * wx
                    f_jac[f, 1, col] += m * wy
                    f_jac[f, 2, col] += m * wz
                else:
                    dx = px - jp[k, 0]
                    dy = py - jp[k, 1]
                    dz = pz - jp[k, 2]
                    f_jac[f, 0, col] += m * (wy * dz - wz * dy)
                    f_jac[f, 1, col] += m * (wz * dx - wx * dz)
                    f_jac[f, 2, col] += m * (wx * dy - wy * dx)
                    f_jac[f, 3, col] += m * wx
                    f_jac[f, 4, col] += m * wy
                    f_jac[f, 5, col] += m * wz
                k = parent[k]


@numba.njit(cache=True, nogil=True)
def fk_batch(
    q: FloatArray, t: TreeArrays, out_t: FloatArray, out_j: FloatArray, want_jac: bool
) -> None:  # pragma: no cover - compiled
    """:func:`fk_one` for each row of ``q`` ``(pop, nq)``: poses into ``out_t``
    ``(pop, nf, 4, 4)``, Jacobians into ``out_j`` ``(pop, nf, 6, nq)`` when ``want_jac``."""
    pop = q.shape[0]
    nf = t.frame_joint.shape[0]
    nq = q.shape[1]
    s = fk_scratch(t)
    for k in range(pop):
        fk_one(q[k], t, s, want_jac)
        for f in range(nf):
            for a in range(3):
                out_t[k, f, a, 3] = s.f_pos[f, a]
                for b in range(3):
                    out_t[k, f, a, b] = s.f_rot[f, a, b]
                out_t[k, f, 3, a] = 0.0
            out_t[k, f, 3, 3] = 1.0
            if want_jac:
                for a in range(6):
                    for i in range(nq):
                        out_j[k, f, a, i] = s.f_jac[f, a, i]
