"""Many targets at once: batched IK with one compiled kernel over all targets.

:func:`solve_batch` solves ``N`` target poses of one robot in one call.  The work is one
numba-compiled loop over the targets (:func:`_solve_targets`); for each target it runs the
bounded Levenberg–Marquardt polish of the default solver (:func:`swarm_ik.kernels.lm.lm_run`:
pose residual in world axes, exact residual Jacobian, active-set joint limits, adaptive
damping with accept/reject, stall detection), first from the seed (``q0``, else the middle of
the joint ranges), then from random restarts until one start converges or ``max_starts``
starts are spent.  No Python code runs per target.

Randomness does not depend on how the targets are split into chunks: the restart points of
target ``i`` come from a SplitMix64 stream (Steele, Lea & Flood, "Fast splittable
pseudorandom number generators", OOPSLA 2014) keyed by ``(seed, i)`` with ``i`` the target's
index in the whole batch, so the same seed gives bit-identical answers whether the targets
are solved in one call, in chunks, or on any number of Dask workers
(:mod:`swarm_ik.distributed`).

Success is judged afterwards, independently of the kernel: the batched forward kinematics of
the answers against the targets, ``‖Δp‖ ≤ tol_pos`` and geodesic angle ``≤ tol_rot``, and the
answer within the joint limits.

>>> import numpy as np, swarm_ik
>>> robot = swarm_ik.load_robot("yumi_left")
>>> q_true = robot.random_q(np.random.default_rng(0), 50)
>>> res = swarm_ik.solve_batch(robot, robot.fk(q_true), seed=0)
>>> bool(res.success.all())
True
"""

from __future__ import annotations

import contextlib
import csv
import functools
import logging
import math
import os
import pickle
import signal
import time
import warnings
import zipfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numba
import numpy as np

from swarm_ik._types import BoolArray, FloatArray, IntArray
from swarm_ik.errors import InvalidArgumentError, InvalidTargetError, SwarmIKError
from swarm_ik.goals import Pose, Position, kernel_slot, kernels
from swarm_ik.kernels import lie, lm
from swarm_ik.kernels.fk import TreeArrays
from swarm_ik.kernels.lm import CONVERGED, NOT_RUN
from swarm_ik.kernels.search import sampling_window, splitmix64
from swarm_ik.pose import make_pose, matrix_to_quat
from swarm_ik.robot import RobotModel

POSE_COLUMNS = ("x", "y", "z", "qx", "qy", "qz", "qw")
"""Columns of a target table: position [m] and quaternion ``(x, y, z, w)``."""

_RESTART_BLOCK = 8
"""Random restarts handed to one call of the polish (each call stops at the first success)."""


# --------------------------------------------------------------------------- kernels
_splitmix64 = splitmix64  # one SplitMix64 (kernels/search.py): the restart streams


@numba.njit(cache=True)
def target_uniforms(seed: int, index: int, n: int) -> FloatArray:  # pragma: no cover
    """The first ``n`` uniforms in ``[0, 1)`` of target ``index``'s stream (for tests and
    tools; the kernel draws the same numbers inline)."""
    key = _splitmix64(_splitmix64(np.uint64(seed)) ^ np.uint64(index))
    out = np.empty(n)
    for c in range(n):
        out[c] = float(_splitmix64(key + np.uint64(c + 1)) >> np.uint64(11)) * (2.0**-53)
    return out


@numba.njit(cache=True)
def _solve_targets(
    t_par: FloatArray,
    q_seed: FloatArray,
    index: IntArray,
    tree: TreeArrays,
    goals: lm.GoalTable,
    ks: lm.GoalKernels,
    bounds: lm.Bounds,
    cfg: lm.LMSettings,
    tol_pos: float,
    tol_rot: float,
    max_starts: int,
    seed: int,
    out_q: FloatArray,
    out_evals: IntArray,
    out_starts: IntArray,
) -> None:  # pragma: no cover - compiled
    """Polish every target from its seed, then from random restarts, until one converges.

    Args:
        t_par: Each target as the parameter block of the table's first goal, ``(N, P)``.
        q_seed: First start of each target, shape ``(N, nq)``, inside the bounds.
        index: Index of each target in the whole batch (keys its random stream), ``(N,)``.
        tree: The robot's kinematic tree.
        goals: The goal table; its first goal's parameter block is overwritten with each
            target's row of ``t_par``.
        bounds: Joint bounds; ``cfg``: LM settings (:data:`swarm_ik.kernels.lm.DEFAULT_LM`).
        tol_pos, tol_rot: Tolerances the polish stops at [m], [rad].
        max_starts: Most starts per target (the seed included).
        seed: Seed of the restart streams, ``0 <= seed < 2**63``.
        out_q: Best point per target, shape ``(N, nq)``.
        out_evals: FK + Jacobian evaluations per target, ``(N,)``.
        out_starts: Starts polished per target, ``(N,)``.
    """
    n_targets = t_par.shape[0]
    n = bounds.lower.shape[0]
    block = min(_RESTART_BLOCK, max(max_starts - 1, 1))
    starts = np.empty((block, n))
    pq, pdp, pdr, pst, pev = lm.polish_outputs(block, n)
    seed_key = _splitmix64(np.uint64(seed))
    s_lo = np.empty(n)
    s_hi = np.empty(n)
    scale = 2.0**-53
    par = goals.par[goals.p0[0] : goals.p0[1]]
    work = lm.make_work(tree, goals, goals.rows_primary)
    for i in range(n_targets):
        for c in range(par.shape[0]):
            par[c] = t_par[i, c]
        key = _splitmix64(seed_key ^ np.uint64(index[i]))
        for j in range(n):
            starts[0, j] = q_seed[i, j]
        sampling_window(bounds.lower, bounds.upper, q_seed[i], s_lo, s_hi)  # uniform restarts
        k = 1  # starts in this call
        done = 0  # starts polished so far
        counter = np.uint64(0)
        evals = 0
        best_cost = np.inf
        converged = False
        while True:
            used = lm.lm_run(
                starts[:k], tree, goals, ks, bounds, cfg, tol_pos, tol_rot, k * cfg.max_iters,
                True, pq[:k], pdp[:k], pdr[:k], pst[:k], pev[:k], work,
            )  # fmt: skip
            evals += used
            for s in range(k):
                if pst[s] == NOT_RUN:
                    break
                done += 1
                cost = pdp[s] + pdr[s]
                if pst[s] == CONVERGED or cost < best_cost:
                    best_cost = cost
                    for j in range(n):
                        out_q[i, j] = pq[s, j]
                if pst[s] == CONVERGED:
                    converged = True
                    break
            if converged or done >= max_starts:
                break
            k = min(block, max_starts - done)
            for s in range(k):
                for j in range(n):
                    counter += np.uint64(1)
                    u = float(_splitmix64(key + counter) >> np.uint64(11)) * scale
                    starts[s, j] = min(s_lo[j] + u * (s_hi[j] - s_lo[j]), s_hi[j])
        out_evals[i] = evals
        out_starts[i] = done


# --------------------------------------------------------------------------- data
BATCH_MAX_ITERS = 60
"""Evaluations per start of the batch solver (the default of :func:`solve_batch`, so that
``BatchSettings()`` is what ``solve_batch`` uses)."""


@dataclass(frozen=True)
class BatchSettings:
    """Settings of the batched solver (picklable: it travels to Dask workers).

    Attributes:
        tol_pos: Position tolerance of success [m].
        tol_rot: Rotation tolerance of success [rad] (ignored when ``position_only``).
        position_only: Solve for the position only (rotation residual weight 0).
        max_starts: Most starts per target, the seed included (later ones uniform random
            within the limits).
        max_iters: Most FK + Jacobian evaluations per start.
        seed: Seed of the per-target restart streams, ``0 <= seed < 2**63``.
        lam0: Initial LM damping, relative to the mean diagonal of ``JᵀJ``.
        max_step: Largest joint change per LM step (rad, or m for prismatic joints).
        stall_rel: A step reducing the squared residual by less than this fraction…
        stall_iters: …this many times in a row ends a start (local minimum).
        tol_margin: The kernel stops at this fraction of the tolerances, so the independent
            check passes with margin.
    """

    tol_pos: float = 1e-5
    tol_rot: float = 1e-5
    position_only: bool = False
    max_starts: int = 128
    max_iters: int = BATCH_MAX_ITERS
    seed: int = 0
    lam0: float = lm.DEFAULT_LM.lam0
    max_step: float = lm.DEFAULT_LM.max_step
    stall_rel: float = lm.DEFAULT_LM.stall_rel
    stall_iters: int = lm.DEFAULT_LM.stall_iters
    tol_margin: float = lm.DEFAULT_LM.tol_margin

    def __post_init__(self) -> None:
        for label in ("tol_pos", "tol_rot"):
            v = getattr(self, label)
            if not (np.isfinite(v) and v > 0):
                raise InvalidArgumentError(f"{label} must be a positive number, got {v!r}")
        for label, lo in (("max_starts", 1), ("max_iters", 2), ("stall_iters", 1)):
            v = getattr(self, label)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo:
                raise InvalidArgumentError(f"{label} must be an integer >= {lo}, got {v!r}")
        s = self.seed
        if isinstance(s, bool) or not isinstance(s, (int, np.integer)) or not 0 <= s < 2**63:
            raise InvalidArgumentError(f"seed must be an integer in [0, 2**63), got {s!r}")
        if not 0.0 < self.tol_margin <= 1.0:
            raise InvalidArgumentError(f"tol_margin must be in (0, 1], got {self.tol_margin!r}")
        self.lm_settings()  # validates lam0, max_step, stall_rel

    def lm_settings(self) -> lm.LMSettings:
        """The LM settings of the kernel, validated."""
        return lm.LMSettings(
            self.max_iters, self.lam0, self.max_step, self.stall_rel, self.stall_iters,
            self.tol_margin,
        ).checked()  # fmt: skip


@dataclass(frozen=True)
class BatchChain:
    """What a worker needs of a robot: the tree arrays and the bounds (plain arrays, so
    shipping it to a Dask worker needs neither the URDF nor Pinocchio).

    Attributes:
        tree: The kinematic tree (:class:`swarm_ik.kernels.fk.TreeArrays`); targets are for
            its first frame.
        bounds: Limits, continuous and prismatic joints (:class:`swarm_ik.kernels.lm.Bounds`).
    """

    tree: TreeArrays
    bounds: lm.Bounds

    @classmethod
    def from_robot(cls, robot: RobotModel) -> BatchChain:
        """The tree of ``robot``, reduced to its first goal frame."""
        t = robot.tree
        return cls(
            t.with_frames(t.frame_joint[:1], t.frame_rot[:1], t.frame_pos[:1]),
            lm.Bounds(
                np.ascontiguousarray(robot.lower, dtype=float),
                np.ascontiguousarray(robot.upper, dtype=float),
                np.ascontiguousarray(robot.continuous_mask),
                np.ascontiguousarray(robot.prismatic_mask),
            ),
        )

    @property
    def nq(self) -> int:
        """Number of joints."""
        return self.tree.nq


@dataclass(frozen=True)
class _Rows:
    """One row per target: the answers and their check (shared by :class:`ChunkResult` and
    :class:`BatchResult`; shapes ``(n, nq)`` and ``(n,)``)."""

    q: FloatArray
    position_error: FloatArray
    rotation_error: FloatArray
    success: BoolArray
    n_evals: IntArray
    n_starts: IntArray


@dataclass(frozen=True)
class ChunkResult(_Rows):
    """Answers for one contiguous chunk of targets (what a worker sends back).

    Attributes:
        q, position_error, rotation_error, success, n_evals, n_starts: As
            :class:`BatchResult`, for the chunk's targets.
        start: Index of the chunk's first target in the batch.
        time_s: Seconds the worker spent on the chunk.
    """

    start: int
    time_s: float


@dataclass(frozen=True)
class BatchResult(_Rows):
    """What :func:`solve_batch` returns: one row per target.

    Attributes:
        q: Best joint vector per target (rad / m), shape ``(N, nq)``.
        position_error: ‖p − p_target‖ [m], ``(N,)``.
        rotation_error: Geodesic angle between reached and target orientation [rad], ``(N,)``.
        success: Both errors within tolerance (rotation ignored when position-only) and ``q``
            within the limits, ``(N,)``.
        n_evals: FK + Jacobian evaluations spent per target, ``(N,)``.
        n_starts: Starts polished per target (1: the seed start converged), ``(N,)``.
        time_s: Wall-clock seconds of the whole call (``setup_s`` included).
        setup_s: Seconds spent starting or connecting to the Dask cluster (0 in-process).
        compute_s: Seconds spent in the chunks, summed over chunks (workers).
        settings: The settings used.
        joint_names: Joint names, ``(nq,)``.
        interrupted: Ctrl-C stopped the call (``keep_on_interrupt``): the rows are the
            chunks finished before it, the first targets in order.
    """

    time_s: float
    setup_s: float
    compute_s: float
    settings: BatchSettings
    joint_names: tuple[str, ...] = ()
    interrupted: bool = False

    @classmethod
    def from_chunks(
        cls,
        parts: list[ChunkResult],
        robot: RobotModel,
        settings: BatchSettings,
        time_s: float,
        setup_s: float,
        interrupted: bool = False,
    ) -> BatchResult:
        """The chunks' answers joined in order (none: empty arrays)."""

        def cat(attr: str, empty: Any) -> Any:
            return np.concatenate([getattr(p, attr) for p in parts]) if parts else empty

        return cls(
            q=cat("q", np.empty((0, robot.nq))),
            position_error=cat("position_error", np.empty(0)),
            rotation_error=cat("rotation_error", np.empty(0)),
            success=cat("success", np.empty(0, dtype=bool)),
            n_evals=cat("n_evals", np.empty(0, dtype=np.int64)),
            n_starts=cat("n_starts", np.empty(0, dtype=np.int64)),
            time_s=time_s,
            setup_s=setup_s,
            compute_s=float(sum(p.time_s for p in parts)),
            settings=settings,
            joint_names=tuple(robot.joint_names),
            interrupted=interrupted,
        )

    @property
    def n(self) -> int:
        """Number of targets."""
        return int(self.q.shape[0])

    @property
    def success_rate(self) -> float:
        """Fraction of targets solved (0 for an empty batch)."""
        return float(self.success.mean()) if self.n else 0.0

    @property
    def poses_per_s(self) -> float:
        """Targets per wall-clock second."""
        return self.n / self.time_s if self.time_s > 0 else float("inf")

    def save(self, path: str | Path, targets: FloatArray | None = None) -> Path:
        """Write the answers to ``.npz`` or ``.csv`` (chosen by the suffix).

        The ``.npz`` holds ``q``, ``position_error``, ``rotation_error``, ``success``,
        ``n_evals``, ``n_starts``, ``joint_names``, ``tol_pos``, ``tol_rot``, ``seed`` (and
        ``targets`` ``(N, 4, 4)`` when given).  The ``.csv`` has a header ``index, <joint
        names>, position_error, rotation_error, success, n_evals`` and one row per target.

        Raises:
            InvalidArgumentError: the suffix is neither ``.npz`` nor ``.csv``.
        """
        p = Path(path)
        suffix = p.suffix.lower()
        if suffix == ".npz":
            arrays: dict[str, Any] = {
                "q": self.q,
                "position_error": self.position_error,
                "rotation_error": self.rotation_error,
                "success": self.success,
                "n_evals": self.n_evals,
                "n_starts": self.n_starts,
                "joint_names": np.array(self.joint_names, dtype=str),
                "tol_pos": self.settings.tol_pos,
                "tol_rot": self.settings.tol_rot,
                "seed": self.settings.seed,
            }
            if targets is not None:
                arrays["targets"] = np.asarray(targets, dtype=float)
            np.savez_compressed(p, **arrays)
        elif suffix == ".csv":
            names = self.joint_names or tuple(f"q{j}" for j in range(self.q.shape[1]))
            with p.open("w", newline="") as fh:
                w = csv.writer(fh)
                w.writerow(
                    ["index", *names, "position_error", "rotation_error", "success", "n_evals"]
                )
                for i in range(self.n):
                    w.writerow(
                        [
                            i,
                            *(repr(float(v)) for v in self.q[i]),
                            repr(float(self.position_error[i])),
                            repr(float(self.rotation_error[i])),
                            int(self.success[i]),
                            int(self.n_evals[i]),
                        ]
                    )
        else:
            raise InvalidArgumentError(
                f"cannot write results to {str(p)!r}: unknown suffix {p.suffix!r}; "
                "valid suffixes: .csv, .npz"
            )
        return p

    def __repr__(self) -> str:
        return (
            f"BatchResult(n={self.n}, success_rate={self.success_rate:.4f}, "
            f"time_s={self.time_s:.3f}, poses_per_s={self.poses_per_s:.0f})"
        )


# --------------------------------------------------------------------------- checks
def check_targets(targets: Any, orth_tol: float = 1e-6) -> FloatArray:
    """Validate a batch of target poses.

    Args:
        targets: Poses, shape ``(N, 4, 4)`` [m], or rows ``x y z qx qy qz qw``, shape
            ``(N, 7)`` (quaternions normalised).
        orth_tol: Tolerance on the orthonormality of the rotation blocks.

    Returns:
        Poses, shape ``(N, 4, 4)``, contiguous.

    Raises:
        InvalidTargetError: wrong shape, NaN/inf, bad bottom row or a non-rotation block; the
            message names the first bad target.
    """
    arr = np.asarray(targets, dtype=float)
    if arr.ndim == 2 and arr.shape[1] == 7:
        if not np.all(np.isfinite(arr)):
            bad = int(np.flatnonzero(~np.isfinite(arr).all(axis=1))[0])
            raise InvalidTargetError(f"target {bad} contains NaN or infinite values")
        out = np.empty((arr.shape[0], 4, 4))
        for i, row in enumerate(arr):
            try:
                out[i] = make_pose(row[:3], row[3:])
            except InvalidTargetError as exc:
                raise InvalidTargetError(f"target {i}: {exc}") from None
        return out
    if arr.ndim != 3 or arr.shape[1:] != (4, 4):
        raise InvalidTargetError(
            f"targets must have shape (N, 4, 4) or (N, 7) (x y z qx qy qz qw); got {arr.shape}"
        )
    finite = np.isfinite(arr).all(axis=(1, 2))
    if not finite.all():
        raise InvalidTargetError(
            f"target {int(np.flatnonzero(~finite)[0])} contains NaN or infinite values"
        )
    bottom = np.abs(arr[:, 3] - np.array([0.0, 0.0, 0.0, 1.0])).max(axis=-1, initial=0.0) > 1e-9
    if bottom.any():
        i = int(np.flatnonzero(bottom)[0])
        raise InvalidTargetError(
            f"target {i}: bottom row must be [0, 0, 0, 1], got {arr[i, 3].tolist()}"
        )
    rot = arr[:, :3, :3]
    orth = np.abs(np.einsum("nji,njk->nik", rot, rot) - np.eye(3)).max(axis=(1, 2), initial=0.0)
    det = np.linalg.det(rot) if arr.shape[0] else np.ones(0)
    bad = (orth > orth_tol) | (np.abs(det - 1.0) > orth_tol)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise InvalidTargetError(
            f"target {i}: rotation is not orthonormal (max|RᵀR − I| = {orth[i]:.3g}, "
            f"det = {det[i]:.9g}, tolerance {orth_tol:g}); fix it with "
            "swarm_ik.pose.project_to_se3"
        )
    return np.ascontiguousarray(arr)


def _seed_starts(bc: BatchChain, q0: Any, n: int) -> FloatArray:
    """First start per target ``(n, nq)``: ``q0`` (``(nq,)`` or ``(n, nq)``) wrapped and
    clipped into the limits (with one warning), else the middle of the joint ranges."""
    if q0 is None:
        return np.tile(0.5 * (bc.bounds.lower + bc.bounds.upper), (n, 1))
    arr = np.asarray(q0, dtype=float)
    if arr.shape == (bc.nq,):
        arr = np.tile(arr, (n, 1))
    if arr.shape != (n, bc.nq):
        raise InvalidArgumentError(
            f"q0 must have shape ({bc.nq},) or ({n}, {bc.nq}) (one row per target); got {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise InvalidArgumentError("q0 contains NaN or infinite values")
    arr = arr.copy()
    b = bc.bounds
    if b.wrap.any():
        arr[:, b.wrap] = (arr[:, b.wrap] + np.pi) % (2 * np.pi) - np.pi
    fixed = np.clip(arr, b.lower, b.upper)
    outside = int(np.any(fixed != arr, axis=1).sum())
    if outside:
        warnings.warn(
            f"q0 lies outside the joint limits for {outside} target(s); clipped into them",
            stacklevel=3,
        )
    return np.ascontiguousarray(fixed)


def pose_errors(
    tree: TreeArrays, q: FloatArray, targets: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Position [m] and rotation [rad] errors of ``q`` ``(N, nq)`` against ``targets``
    ``(N, 4, 4)`` for the tree's first frame, with the batched FK (not the LM kernel)."""
    poses = tree.fk(q)[:, 0] if q.shape[0] else np.empty((0, 4, 4))
    dp = np.linalg.norm(poses[:, :3, 3] - targets[:, :3, 3], axis=-1)
    rel = np.einsum("nji,njk->nik", targets[:, :3, :3], poses[:, :3, :3])
    return dp, lie.angle(rel)


# --------------------------------------------------------------------------- chunks
def solve_chunk(
    bc: BatchChain,
    settings: BatchSettings,
    start: int,
    targets: FloatArray,
    q_seed: FloatArray,
) -> ChunkResult:
    """Solve one contiguous chunk of targets (the unit of work shipped to a Dask worker).

    Args:
        bc: The robot's chain and limits.
        settings: Solver settings (seed, tolerances, restarts).
        start: Index of the chunk's first target in the whole batch (keys the random streams).
        targets: Valid poses, shape ``(n, 4, 4)``.
        q_seed: First start per target, shape ``(n, nq)``, inside the limits.

    Returns:
        The chunk's answers, errors (checked with the batched FK) and counters.
    """
    t0 = time.perf_counter()
    n = targets.shape[0]
    nq = bc.nq
    q = np.empty((n, nq))
    evals = np.zeros(n, dtype=np.int64)
    starts = np.zeros(n, dtype=np.int64)
    if n:
        goal = Position if settings.position_only else Pose
        t_par = np.ascontiguousarray(goal.params(targets), dtype=float)
        goals = lm.goal_table(
            [kernel_slot(goal.kernel)], [1.0], [True], [t_par[0].copy()],
            [np.zeros(1, dtype=np.int64)], [3 if settings.position_only else 6],
        )  # fmt: skip
        _solve_targets(
            t_par,
            np.ascontiguousarray(q_seed, dtype=float),
            np.arange(start, start + n, dtype=np.int64),
            bc.tree,
            goals,
            kernels(),
            bc.bounds,
            settings.lm_settings(),
            settings.tol_pos * settings.tol_margin,
            settings.tol_rot * settings.tol_margin,
            int(settings.max_starts),
            int(settings.seed),
            q,
            evals,
            starts,
        )
    dp, dr = pose_errors(bc.tree, q, targets)
    within = np.all((q >= bc.bounds.lower - 1e-12) & (q <= bc.bounds.upper + 1e-12), axis=1)
    ok = within & (dp <= settings.tol_pos)
    if not settings.position_only:
        ok &= dr <= settings.tol_rot
    return ChunkResult(
        q=q, position_error=dp, rotation_error=dr, success=ok, n_evals=evals, n_starts=starts,
        start=start, time_s=time.perf_counter() - t0,
    )  # fmt: skip


def _run_chunk(
    bc: BatchChain, settings: BatchSettings, item: tuple[int, FloatArray, FloatArray]
) -> ChunkResult:
    start, targets, q_seed = item
    return solve_chunk(bc, settings, start, targets, q_seed)


def default_chunk_size(n: int, n_workers: int = 1) -> int:
    """Targets per chunk: about four chunks per worker, between 64 and 4096 targets."""
    return int(min(4096, max(64, math.ceil(n / max(4 * n_workers, 1)))))


def solve_batch(
    robot: RobotModel,
    targets: Any,
    *,
    seed: int = 0,
    q0: Any = None,
    tol_pos: float = 1e-5,
    tol_rot: float = 1e-5,
    position_only: bool = False,
    max_starts: int = 128,
    max_iters: int = BATCH_MAX_ITERS,
    scheduler: Any = None,
    chunk_size: int | None = None,
    progress: bool = False,
    keep_on_interrupt: bool = False,
) -> BatchResult:
    """Solve many target poses of one robot at once.

    One compiled kernel loops over the targets (see the module docstring); chunks of targets
    go to Dask workers when a ``scheduler`` is given.  The answer for each target depends only
    on ``(seed, its index, its target, its q0)``: neither the chunk size nor the number of
    workers changes any bit of the result.

    Args:
        robot: The robot.
        targets: Target poses, shape ``(N, 4, 4)`` [m], or rows ``x y z qx qy qz qw``,
            shape ``(N, 7)``.
        seed: Seed of the per-target restart streams, ``0 <= seed < 2**63``.
        q0: First start, shape ``(nq,)`` (all targets) or ``(N, nq)`` (one per target);
            clipped into the limits with a warning when outside.  Default: the middle of the
            joint ranges.
        tol_pos: Position tolerance of success [m].
        tol_rot: Rotation tolerance of success [rad].
        position_only: Ignore the target orientation.
        max_starts: Most starts per target (the seed start included); unreachable targets
            cost this many polishes.
        max_iters: Most FK + Jacobian evaluations per start.
        scheduler: ``None`` (in this process, no Dask), ``"local"`` (an embedded
            ``dask.distributed.LocalCluster``, one single-threaded worker process per core),
            a scheduler address such as ``"tcp://127.0.0.1:8786"``, or a
            ``distributed.Client``.
        chunk_size: Targets per chunk (default: :func:`default_chunk_size`).
        progress: Show a progress bar (tqdm) over the chunks.
        keep_on_interrupt: On Ctrl-C return the chunks finished so far (``interrupted``
            set) instead of raising ``KeyboardInterrupt``; chunks then go out in waves of two
            per worker, and worker processes are started ignoring SIGINT (``swarm-ik batch``).

    Returns:
        A :class:`BatchResult`, one row per target, in the order of ``targets``.

    Raises:
        InvalidTargetError: a target is not a valid pose (the first bad one named).
        InvalidArgumentError: bad ``q0``, settings, ``chunk_size`` or ``scheduler``.
    """
    from swarm_ik import distributed

    if not isinstance(robot, RobotModel):
        raise InvalidArgumentError(
            f"robot must be a RobotModel (see swarm_ik.load_robot), got {type(robot).__name__}"
        )
    from swarm_ik._validate import float_array, positive_float

    t0 = time.perf_counter()
    targets = float_array(targets, "targets")
    settings = BatchSettings(
        tol_pos=positive_float(tol_pos, "tol_pos"),
        tol_rot=positive_float(tol_rot, "tol_rot"),
        position_only=bool(position_only),
        max_starts=max_starts,
        max_iters=max_iters,
        seed=seed,
    )
    poses = check_targets(targets)
    n = poses.shape[0]
    bc = BatchChain.from_robot(robot)
    seeds = _seed_starts(bc, q0, n)
    if chunk_size is not None and (
        isinstance(chunk_size, bool)
        or not isinstance(chunk_size, (int, np.integer))
        or chunk_size < 1
    ):
        raise InvalidArgumentError(f"chunk_size must be a positive integer, got {chunk_size!r}")
    interrupted = False
    with contextlib.ExitStack() as stack:
        t_setup = time.perf_counter()
        with _workers_ignore_sigint() if keep_on_interrupt else contextlib.nullcontext():
            client = stack.enter_context(distributed.connect(scheduler))
        setup_s = time.perf_counter() - t_setup
        workers = distributed.n_workers(client)
        size = int(chunk_size) if chunk_size is not None else default_chunk_size(n, workers)
        items = [(s, poses[s : s + size], seeds[s : s + size]) for s in range(0, n, size)]
        func = functools.partial(_run_chunk, bc, settings)
        parts: list[ChunkResult] = []
        if not keep_on_interrupt:
            parts = distributed.map_chunks(
                func, items, client=client, name="swarm-ik-batch", progress=progress,
                desc=f"IK {robot.name}", sizes=[len(it[1]) for it in items], unit="pose",
            )  # fmt: skip
        else:  # in waves, keeping what finished
            wave = 1 if client is None else 2 * workers
            bar = distributed.progress_bar(progress, n, f"IK {robot.name}", "pose")
            try:
                for w in range(0, len(items), wave):
                    chunk = items[w : w + wave]
                    parts.extend(
                        distributed.map_chunks(func, chunk, client=client, name="swarm-ik-batch")
                    )
                    bar.update(sum(len(it[1]) for it in chunk))
            except KeyboardInterrupt:
                interrupted = True
                logging.getLogger("distributed").setLevel(logging.CRITICAL)
            finally:
                bar.close()
    return BatchResult.from_chunks(
        parts, robot, settings, time.perf_counter() - t0, setup_s, interrupted
    )


@contextlib.contextmanager
def _workers_ignore_sigint() -> Iterator[None]:
    """Ignore SIGINT while worker processes are started, so that they inherit the ignore
    (Python keeps an inherited ignore) and Ctrl-C reaches this process only: no tracebacks
    from every worker.  The handler is restored at once."""
    try:
        old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


# --------------------------------------------------------------------------- files
def read_targets(path: str | Path) -> FloatArray:
    """Read target poses from a file.

    * ``.npz``: the array ``targets`` (or ``poses``, or the file's only array), shape
      ``(N, 4, 4)`` or ``(N, 7)``; ``.npy``: one such array.
    * ``.csv``: one target per row, either 7 columns ``x y z qx qy qz qw`` (a header naming
      them, in any order, is recognised) or 16 columns (the 4x4 matrix row by row).

    Returns:
        Valid poses, shape ``(N, 4, 4)``.

    Raises:
        InvalidArgumentError: no such file, unknown suffix, missing array, bad columns.
        InvalidTargetError: a row is not a valid pose.
    """
    p = Path(path)
    if not p.is_file():
        raise InvalidArgumentError(f"targets file not found: {str(p)!r}")
    suffix = p.suffix.lower()
    if suffix in (".npz", ".npy"):
        data = np.load(p, allow_pickle=False)
        if suffix == ".npy":
            return check_targets(data)
        keys = list(data.keys())
        for k in ("targets", "poses"):
            if k in keys:
                return check_targets(data[k])
        if len(keys) == 1:
            return check_targets(data[keys[0]])
        raise InvalidArgumentError(
            f"{p}: no array named 'targets' or 'poses'; arrays in the file: {', '.join(keys)}"
        )
    if suffix == ".csv":
        with p.open(newline="") as fh:
            rows = [r for r in csv.reader(fh) if r and not r[0].lstrip().startswith("#")]
        if not rows:
            return np.empty((0, 4, 4))
        header = [h.strip().lower() for h in rows[0]]
        cols: list[int] | None = None
        try:
            [float(v) for v in rows[0]]
            body = rows
        except ValueError:
            body = rows[1:]
            if all(c in header for c in POSE_COLUMNS):
                cols = [header.index(c) for c in POSE_COLUMNS]
            elif len(header) != 16:
                missing = [c for c in POSE_COLUMNS if c not in header]
                raise InvalidArgumentError(
                    f"{p}: header lacks column(s) {', '.join(missing)}; expected "
                    f"{', '.join(POSE_COLUMNS)} (or 16 matrix entries)"
                ) from None
        try:
            table = np.array([[float(v) for v in r] for r in body], dtype=float)
        except ValueError as exc:
            raise InvalidArgumentError(f"{p}: non-numeric value ({exc})") from None
        if table.size == 0:
            return np.empty((0, 4, 4))
        if cols is not None:
            return check_targets(table[:, cols])
        if table.shape[1] == 7:
            return check_targets(table)
        if table.shape[1] == 16:
            return check_targets(table.reshape(-1, 4, 4))
        raise InvalidArgumentError(
            f"{p}: rows must have 7 columns (x y z qx qy qz qw) or 16 (a 4x4 matrix), "
            f"got {table.shape[1]}"
        )
    raise InvalidArgumentError(
        f"cannot read targets from {str(p)!r}: unknown suffix {p.suffix!r}; valid suffixes: "
        ".csv, .npy, .npz"
    )


def write_targets(path: str | Path, targets: Any) -> Path:
    """Write poses ``(N, 4, 4)`` to ``.npz`` (array ``targets``) or ``.csv`` (columns
    ``x y z qx qy qz qw``); the inverse of :func:`read_targets`."""
    poses = check_targets(targets)
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".npz":
        np.savez_compressed(p, targets=poses)
    elif suffix == ".csv":
        with p.open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(POSE_COLUMNS)
            for t in poses:
                w.writerow([repr(float(v)) for v in (*t[:3, 3], *matrix_to_quat(t[:3, :3]))])
    else:
        raise InvalidArgumentError(
            f"cannot write targets to {str(p)!r}: unknown suffix {p.suffix!r}; valid suffixes: "
            ".csv, .npz"
        )
    return p


def read_targets_file(path: str | os.PathLike[str]) -> FloatArray:
    """:func:`swarm_ik.batch.read_targets`, with unreadable files turned into one message.

    Raises:
        InvalidArgumentError: a corrupt ``.npz``/``.npy`` (not a zip, truncated, an object
            array that would need pickle), an unreadable file.
        InvalidTargetError: a row is not a valid pose.
    """
    try:
        return read_targets(Path(path))
    except SwarmIKError:
        raise
    except (
        ValueError,
        TypeError,
        OSError,
        EOFError,
        zipfile.BadZipFile,
        pickle.UnpicklingError,
        UnicodeDecodeError,
        KeyError,
    ) as exc:
        reason = " ".join(str(exc).split()) or type(exc).__name__
        if "allow_pickle" in reason:
            reason = "an object array of Python objects, not numbers"
        raise InvalidArgumentError(f"{path}: cannot read targets ({reason})") from None
