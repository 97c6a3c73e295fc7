"""Many targets at once: batched IK with one compiled kernel over all targets.

:func:`solve_batch` solves ``N`` target poses of one robot in one call.  The work is one
numba-compiled loop over the targets (:func:`_solve_targets`); for each target it runs the
bounded Levenberg–Marquardt polish of the default solver (:func:`swarm_ik.kernels.lm.lm_run`:
pose residual in world axes, exact residual Jacobian, active-set joint limits, adaptive
damping with accept/reject, stall detection), first from the seed (``q0``, else the middle of
the joint ranges); a target that did not converge then starts again from the configurations
of a fixed table nearest to its pose (:func:`_seed_table_restarts`), then from random
restarts, until one start converges or ``max_starts`` starts are spent.  Each pass is one
compiled call over the targets still open; no Python code runs per target (with ``goals``,
the goals' own check of each converged answer runs in Python: coal for collisions).

``goals=[...]`` applies any compiled goals of :mod:`swarm_ik.goals` to every target (the
table of ``IKProblem(robot, goals=[Pose(ee, target), *goals])``, the target's block rewritten
per target): collisions (``AvoidCollisions``), axes, centre of mass, secondary postures…

Randomness does not depend on how the targets are split into chunks: the restart points of
target ``i`` come from a SplitMix64 stream (Steele, Lea & Flood, "Fast splittable
pseudorandom number generators", OOPSLA 2014) keyed by ``(seed, i)`` with ``i`` the target's
index in the whole batch, so the same seed gives bit-identical answers whether the targets
are solved in one call, in chunks, or on any number of Dask workers
(:mod:`swarm_ik.distributed`).

Success is judged afterwards, independently of the kernel: the batched forward kinematics of
the answers against the targets, ``‖Δp‖ ≤ tol_pos`` and geodesic angle ``≤ tol_rot``, and the
answer within the joint limits; with goals, also every primary goal met by the check of
:meth:`swarm_ik.IKProblem.verify`, on the targets the kernel converged on.  An error within
:data:`JUDGE_MARGIN` of a tolerance is measured again with Pinocchio's FK, which then
judges it, so that every verdict is Pinocchio's.

>>> import numpy as np, swarm_ik
>>> robot = swarm_ik.load_robot("yumi_left")
>>> q_true = robot.random_q(np.random.default_rng(0), 50)
>>> res = swarm_ik.solve_batch(robot, robot.fk(q_true), seed=0)
>>> bool(res.success.all())
True
"""

from __future__ import annotations

import array
import contextlib
import csv
import dataclasses
import functools
import hashlib
import itertools
import logging
import math
import os
import pickle
import threading
import time
import warnings
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from swarm_ik._types import BoolArray, FloatArray, IntArray
from swarm_ik._validate import (
    check_output_path,
    check_seed,
    count,
    float_array,
    floats_or,
    keywords_checked,
    user_stacklevel,
)
from swarm_ik.api import unreachable_targets
from swarm_ik.errors import InvalidArgumentError, InvalidTargetError, SwarmIKError
from swarm_ik.goals import AvoidCollisions, Goal, Pose, Position, State, kernel_slot, kernels
from swarm_ik.goals import base as goals_base
from swarm_ik.kernels import (
    announced,
    ctrl_c_counted,
    lie,
    lm,
    loaded_despite_damage,
    raise_lost_ctrl_c,
)
from swarm_ik.kernels.fk import TreeArrays
from swarm_ik.kernels.lm import CONVERGED, NOT_RUN
from swarm_ik.kernels.search import sampling_window, splitmix64, uniform_in, uniforms, wall_clock
from swarm_ik.optimize import check_budget
from swarm_ik.paths import written_in_place_of
from swarm_ik.pose import matrix_to_quat, poses_from_rows
from swarm_ik.problem import IKProblem
from swarm_ik.result import FrozenArrays
from swarm_ik.robot import RobotModel
from swarm_ik.scene import Scene

POSE_COLUMNS = ("x", "y", "z", "qx", "qy", "qz", "qw")
"""Columns of a target table: position [m] and quaternion ``(x, y, z, w)``."""

_RESTART_BLOCK = 8
"""Random restarts handed to one call of the polish (each call stops at the first success)."""


# --------------------------------------------------------------------------- kernels
_splitmix64 = splitmix64  # one SplitMix64 (kernels/search.py): the restart streams


@numba.njit(cache=True)
def target_uniforms(seed: int, index: int, n: int) -> FloatArray:  # pragma: no cover
    """The first ``n`` uniforms in ``[0, 1)`` of target ``index``'s stream (for tests and
    tools; the kernel draws the same numbers with :func:`~swarm_ik.kernels.search.uniform_at`)."""
    return uniforms(_splitmix64(_splitmix64(np.uint64(seed)) ^ np.uint64(index)), 0, n)


INTERRUPT_EVERY = 64
"""Targets between two entries of :func:`_solve_targets` into Python (a clock read) without
a time limit, in the main thread: where a pending Ctrl-C raises ``KeyboardInterrupt`` (a chunk
of 10⁶ targets ran 15 s past a Ctrl-C; 64 targets take a few ms at most).  Another thread
(``scheduler="threads"``, a Dask worker's) takes no Ctrl-C and never enters Python without a
time limit: each entry waits for the GIL, which the other threads' Python holds for up to
its switch interval (5 ms), and cost two threads 15-20 % of their speed."""

NO_DEADLINE = -1.0
"""``deadline`` of :func:`_solve_targets` when there is no time limit."""


@numba.njit(cache=True, nogil=True)
def _solve_targets(
    t_par: FloatArray,
    cols: IntArray,
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
    max_evals: int,
    spent: IntArray,
    seed: int,
    secondary_evals: int,
    deadline: float,
    reserve: float,
    interrupt_every: int,
    out_q: FloatArray,
    out_evals: IntArray,
    out_starts: IntArray,
    out_conv: BoolArray,
) -> None:  # pragma: no cover - compiled
    """Polish every target from its seed, then from random restarts, until one converges.

    Args:
        t_par: Each target's parameters, ``(N, P)``: written into the table's floats at
            ``cols`` before the target is solved (its own goal's block, and the blocks of goals
            encoded from its start).
        cols: Where each column of ``t_par`` goes in ``goals.par``, ``(P,)``.
        q_seed: First start of each target, shape ``(N, nq)``, inside the bounds.
        index: Index of each target in the whole batch (keys its random stream), ``(N,)``.
        tree: The kinematic tree (the goal frames, then the frames goals add).
        goals: The goal table (its floats are overwritten at ``cols``).
        ks: The goal kernels.
        bounds: Joint bounds; ``cfg``: LM settings (:data:`swarm_ik.kernels.lm.DEFAULT_LM`).
        tol_pos, tol_rot: Tolerances the polish stops at [m], [rad].
        max_starts: Most starts per target (the seed included).
        max_evals: Most evaluations per target over the whole batch (``-1``: none).
        spent: Evaluations each target spent in earlier passes, ``(N,)``: a target starts
            only while ``spent + its evaluations here < max_evals``, each polish within the
            rest.
        seed: Seed of the restart streams, ``0 <= seed < 2**63``.
        secondary_evals: Evaluations of the null-space descent of the secondary goals after a
            target converged (:func:`swarm_ik.kernels.lm.secondary_descent`; none without
            secondary goals).
        deadline: :func:`~swarm_ik.kernels.search.wall_clock` time after which no target
            and no restart block starts (:data:`NO_DEADLINE`: none).
        reserve: Seconds kept before ``deadline`` per target started in this call (for the
            check of its answer after the call): a target or a restart block starts only
            while ``deadline − reserve · (targets started)`` has not passed.
        interrupt_every: Without a deadline, enter Python (a clock read, where a Ctrl-C
            raises) after every this many targets; 0: never (:data:`INTERRUPT_EVERY`).
        out_q: Best point per target, shape ``(N, nq)`` (the seed for a target not started).
        out_evals: FK + Jacobian evaluations per target, ``(N,)``.
        out_starts: Starts polished per target, ``(N,)`` (0: not started before the deadline).
        out_conv: Whether a start converged (every primary goal within the tolerances of the
            polish), ``(N,)``.
    """
    n_targets = t_par.shape[0]
    n = bounds.lower.shape[0]
    block = min(_RESTART_BLOCK, max(max_starts - 1, 1))
    starts = np.empty((block, n))
    pq, pdp, pdr, pst, pev = lm.polish_outputs_nb(block, n)
    seed_key = _splitmix64(np.uint64(seed))
    s_lo = np.empty(n)
    s_hi = np.empty(n)
    q_in = np.empty(n)
    q_sec = np.empty(n)
    par = goals.par
    timed = deadline != NO_DEADLINE
    late = False
    work = lm.make_work_nb(tree, goals, goals.rows_primary)
    for i in range(n_targets):
        if timed and not late:
            late = wall_clock() > deadline - reserve * i
        elif not timed and interrupt_every > 0 and i % interrupt_every == interrupt_every - 1:
            wall_clock()  # (entering Python: where a pending Ctrl-C raises KeyboardInterrupt)
        cap = max_evals - spent[i] if max_evals >= 0 else np.iinfo(np.int64).max
        if late or cap <= 0:  # out of time or of evaluations: not started
            for j in range(n):
                out_q[i, j] = q_seed[i, j]
            out_evals[i] = 0
            out_starts[i] = 0
            out_conv[i] = False
            continue
        for c in range(cols.shape[0]):
            par[cols[c]] = t_par[i, c]
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
                starts[:k], tree, goals, ks, bounds, cfg, tol_pos, tol_rot,
                min(k * cfg.max_iters, cap - evals), True, pq[:k], pdp[:k], pdr[:k], pst[:k],
                pev[:k], work,
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
            if converged or done >= max_starts or evals >= cap:
                break
            if timed:
                late = wall_clock() > deadline - reserve * (i + 1)
                if late:
                    break
            k = min(block, max_starts - done)
            for s in range(k):
                for j in range(n):
                    counter += np.uint64(1)
                    starts[s, j] = uniform_in(s_lo[j], s_hi[j], key, counter)
        descent = min(secondary_evals, cap - evals)
        if converged and goals.rows_secondary > 0 and descent > 0:
            for j in range(n):
                q_in[j] = out_q[i, j]
            evals += lm.secondary_descent(
                q_in, tree, goals, ks, bounds, tol_pos, tol_rot, descent, q_sec
            )
            for j in range(n):
                out_q[i, j] = q_sec[j]
        out_evals[i] = evals
        out_starts[i] = done
        out_conv[i] = converged


# --------------------------------------------------------------------------- data
BATCH_MAX_ITERS = 60
"""Evaluations per start of the batch solver (the default of :func:`solve_batch`, so that
``BatchSettings()`` is what ``solve_batch`` uses)."""

RESTART_LAM0 = 0.1
"""Initial LM damping of a batch target's restarts and of a first start at the middle of the
ranges (:func:`_restarts`; a ``q0`` the caller gave and the patient last start keep ``lam0``
of :data:`swarm_ik.kernels.lm.DEFAULT_LM`, 0.3).  With
:data:`RESTART_STALL_REL`, chosen on 6,000 FK targets each of Panda, UR5, UR10, Kinova, xArm7
and YuMi's left arm (``lam0`` 0.03 / 0.1 / 0.3 × ``stall_rel`` 0.05 – 0.3 × ``stall_iters``
2 / 3, on every start): 16.6 against 18.3 evaluations per Panda target, 21.4 against 23.9 on
YuMi, the same targets solved; ``stall_iters`` 2 lost targets on YuMi.  A restart is a guess
that gains from being given up sooner, and so is the middle of the ranges, the first start
when the caller gives no ``q0`` (16.6 against 16.8 evaluations per Panda target, 21.6 against
23.1 on YuMi, with it quick rather than patient); a ``q0`` the caller gave keeps the patient
defaults (``BatchSettings.own_start``): on it the quick settings lost 2 of 300 Panda paths of
:func:`swarm_ik.path.solve_path`, whose tracking is that one start.  The single solve's swarm
search gained nothing from them (25.9 against 24.9 evaluations per Panda target)."""

RESTART_STALL_REL = 0.15
"""A restart's LM step lowering the squared residual by less than this fraction counts as a
stall (``stall_rel`` of :data:`~swarm_ik.kernels.lm.DEFAULT_LM` is 0.05): see
:data:`RESTART_LAM0`."""


@dataclass(frozen=True)
class BatchSettings:
    """Settings of the batched solver (picklable: it travels to Dask workers).

    Attributes:
        tol_pos: Position tolerance of success [m].
        tol_rot: Rotation tolerance of success [rad] (ignored when ``position_only``).
        position_only: Solve for the position only (rotation residual weight 0).
        max_starts: Most starts per target, the seed included (then up to
            :data:`TABLE_RESTARTS` from the restart table, then uniform random within the
            limits, the last a patient polish of the best point found: :func:`_patient`).
        max_iters: Most FK + Jacobian evaluations per start (the patient last start:
            :data:`PATIENT_ITERS` times as many).
        seed: Seed of the per-target restart streams, ``0 <= seed < 2**63``.
        lam0: Initial LM damping, relative to the mean diagonal of ``JᵀJ`` (the restarts:
            :data:`RESTART_LAM0`).
        max_step: Largest joint change per LM step (rad, or m for prismatic joints).
        stall_rel: A step reducing the squared residual by less than this fraction… (the
            restarts: :data:`RESTART_STALL_REL`)
        stall_iters: …this many times in a row ends a start (local minimum).
        tol_margin: The kernel stops at this fraction of the tolerances, so the independent
            check passes with margin.
        deadline: Wall-clock time (``time.time()``, seconds since the epoch) after which no
            target starts (``solve_batch``'s ``time_limit``); None: no limit.
        reserve: Seconds kept before ``deadline`` per target started in a kernel call, for the
            check of its answer (:func:`_with_deadline`: :data:`FINISH_PER_STARTED`, and
            coal's verdicts with a collision goal); ``>= 0``.
        own_start: The first start of each target is the caller's ``q0`` (polished with
            ``lam0`` and ``stall_rel``), not the middle of the ranges (a guess, polished as
            a restart: :func:`_restarts`).
        restart_share: With a ``deadline``: seconds per target of a chunk after which, counted
            from the chunk's start, its targets start no more restarts (their first starts
            run until the deadline), so that one chunk's hopeless targets do not spend the
            limit of the chunks after it; 0: the deadline alone.  ``>= 0``.
        max_evals: Most FK + Jacobian evaluations per target over all its passes (None: the
            starts alone bound them), as ``swarm_ik.solve``'s ``max_evals`` bounds one solve.
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
    deadline: float | None = None
    reserve: float = 0.0
    own_start: bool = False
    restart_share: float = 0.0
    max_evals: int | None = None

    def __post_init__(self) -> None:
        for label in ("tol_pos", "tol_rot"):
            v = getattr(self, label)
            if not (np.isfinite(v) and v > 0):
                raise InvalidArgumentError(f"{label} must be a positive number, got {v!r}")
        for label, lo in (("max_starts", 1), ("max_iters", 2), ("stall_iters", 1)):
            object.__setattr__(self, label, count(getattr(self, label), label, lo))
        if self.max_starts > MAX_STARTS:
            raise InvalidArgumentError(
                f"max_starts must be at most {MAX_STARTS} (swarm_ik.batch.MAX_STARTS; "
                f"time_limit bounds the whole call), got {self.max_starts!r}"
            )
        check_budget(self.max_evals, None)  # (a positive integer up to 2**62, or None)
        if not isinstance(self.own_start, bool):
            raise InvalidArgumentError(f"own_start must be a bool, got {self.own_start!r}")
        if self.seed is None or isinstance(self.seed, np.random.Generator):
            raise InvalidArgumentError(
                f"seed must be an integer in [0, 2**63) (a batch keys each target's stream by "
                f"it), got {self.seed!r}"
            )
        check_seed(self.seed)
        if not 0.0 < self.tol_margin <= 1.0:
            raise InvalidArgumentError(f"tol_margin must be in (0, 1], got {self.tol_margin!r}")
        d = self.deadline
        if d is not None:
            ok = isinstance(d, (int, float)) and not isinstance(d, bool)
            if not (ok and math.isfinite(d) and d > 0):
                raise InvalidArgumentError(
                    f"deadline must be a positive time.time() value, got {d!r}"
                )
        for label in ("reserve", "restart_share"):
            r = getattr(self, label)
            bad = isinstance(r, bool) or not isinstance(r, (int, float))
            if bad or not (0.0 <= r < math.inf):
                raise InvalidArgumentError(f"{label} must be a finite number >= 0 [s], got {r!r}")
        self.lm_settings()  # validates lam0, max_step, stall_rel

    def lm_settings(self) -> lm.LMSettings:
        """The LM settings of the kernel, validated."""
        return lm.LMSettings(
            self.max_iters, self.lam0, self.max_step, self.stall_rel, self.stall_iters,
            self.tol_margin,
        ).checked()  # fmt: skip


SECONDARY_EVALS = 200
"""Evaluations of the null-space descent of the secondary goals per solved target (as the
default solver spends after its search)."""

_ROBOTS: dict[str, RobotModel] = {}
"""Robots received by this process (a Dask worker), by the fingerprint of their pickle: a
worker keeps one robot per fingerprint, and with it the sphere models and the collision model
cached on it, from chunk to chunk and call to call."""
_MAX_ROBOTS = 4


class BatchGoals:
    """The goals of a batch besides each target's own: one :class:`~swarm_ik.problem.IKProblem`
    ``(robot, goals=[Pose(ee, target), *goals])`` (``Position`` when position-only) whose
    tree, goal table and bounds the kernel runs, its first goal's parameters rewritten for each
    target (with a primary collision goal, the same problem without it for the first pass:
    :attr:`free_problem`).

    Picklable (it travels to Dask workers): it is sent as the robot and the goals, and the
    receiving process builds the problem again (the goal table's kernel slots are per process),
    reusing a robot it already received (with the sphere and collision models cached on it).

    Args:
        robot: The robot (loaded with every goal frame).
        goals: Compiled goals (:mod:`swarm_ik.goals`), applied to every target.
        position_only: The targets' goal is a ``Position`` (else a ``Pose``).
        first: A valid pose for the template's target, ``(4, 4)`` (rewritten per target).

    Raises:
        InvalidArgumentError: not a list of goals, a goal written in Python, or what
            :class:`~swarm_ik.problem.IKProblem` refuses (a frame the robot was not loaded
            with is named with the frames it has).
    """

    def __init__(
        self, robot: RobotModel, goals: Any, position_only: bool, first: FloatArray
    ) -> None:
        if isinstance(goals, Goal) or not isinstance(goals, (list, tuple)):
            raise InvalidArgumentError(
                f"goals must be a list of goal terms (swarm_ik.goals), got {goals!r:.80}"
            )
        self.robot = robot
        self.goals: tuple[Goal, ...] = tuple(goals)
        self.position_only = bool(position_only)
        self._first = np.asarray(first, dtype=float)
        self._fingerprint: str | None = None
        self._free: IKProblem | None = None
        self._problem: IKProblem | None = self._build(robot)
        py = self._problem.python_goals
        if py:
            raise InvalidArgumentError(
                f"solve_batch runs compiled goals only (one compiled loop over the targets); "
                f"{py[0].describe()} is a goal written in Python: solve such problems with "
                "swarm_ik.solve or swarm_ik.solve_many"
            )

    def _build(self, robot: RobotModel) -> IKProblem:
        ee = robot.ee_frame
        own: Goal = (
            Position(ee, self._first[:3, 3])
            if self.position_only
            else Pose.checked(ee, self._first)
        )
        return IKProblem(robot, goals=[own, *self.goals])

    @property
    def problem(self) -> IKProblem:
        """The problem of the first target (built again where this object was unpickled)."""
        if self._problem is None:
            robot = _ROBOTS.get(self._fingerprint or "")
            if robot is None:
                robot = self.robot
                if len(_ROBOTS) >= _MAX_ROBOTS:
                    _ROBOTS.clear()
                _ROBOTS[self._fingerprint or ""] = robot
            self._problem = self._build(robot)
        return self._problem

    @property
    def primary(self) -> tuple[Goal, ...]:
        """The primary goals among :attr:`goals` (those the judge checks)."""
        return tuple(g for g in self.goals if g.is_primary)

    @property
    def labels(self) -> tuple[str, ...]:
        """Labels of :attr:`primary` (``Goal.describe()``)."""
        return tuple(g.describe() for g in self.primary)

    def fingerprint(self) -> str:
        """SHA-1 of the robot's pickle (which robot a worker may reuse)."""
        if self._fingerprint is None:
            self._fingerprint = hashlib.sha1(pickle.dumps(self.robot)).hexdigest()
        return self._fingerprint

    def __getstate__(self) -> dict[str, Any]:
        """The robot and the goals (scenes without their coal objects, which do not pickle);
        the problem is built again where it is unpickled."""
        goals = tuple(
            dataclasses.replace(g, scene=Scene(g.scene.obstacles))
            if isinstance(g, AvoidCollisions)
            else g
            for g in self.goals
        )
        return {
            "robot": self.robot, "goals": goals, "position_only": self.position_only,
            "_first": self._first, "_fingerprint": self.fingerprint(), "_problem": None,
            "_free": None,
        }  # fmt: skip

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)

    @property
    def collision(self) -> AvoidCollisions | None:
        """The primary ``AvoidCollisions`` goal, if any."""
        return next((g for g in self.primary if isinstance(g, AvoidCollisions)), None)

    @property
    def free_problem(self) -> IKProblem:
        """:attr:`problem` without its collision goal (the first pass of a batch with one)."""
        if self._free is None:  # (never None: the target's own goal is primary)
            self._free = self.problem.without_collisions() or self.problem
        return self._free

    def target_params(
        self, problem: IKProblem, targets: FloatArray, q_seed: FloatArray
    ) -> tuple[FloatArray, IntArray]:
        """What the kernel writes into ``problem``'s goal table (:attr:`problem` or
        :attr:`free_problem`) for each target: ``(t_par (n, P), cols (P,))``, the target's own
        goal block, then the blocks of goals encoded from the start (``MinimalDisplacement``),
        each target's from its own ``q_seed`` row."""
        tab = problem.table(None)
        own = Position if self.position_only else Pose
        blocks = [np.asarray(own.params(targets), dtype=float).reshape(len(targets), -1)]
        cols = [np.arange(tab.p0[0], tab.p0[1], dtype=np.int64)]
        for k, gl in enumerate(problem.compiled_goals):
            if k and getattr(gl, "uses_start", False):
                blocks.append(np.array([problem.encode(k, q).par for q in q_seed], dtype=float))
                cols.append(np.arange(tab.p0[k], tab.p0[k + 1], dtype=np.int64))
        return (
            np.ascontiguousarray(np.concatenate(blocks, axis=1).reshape(len(targets), -1)),
            np.concatenate(cols),
        )

    def in_contact(self, qs: FloatArray) -> BoolArray:
        """Coal's exact test of the collision goal at each row of ``qs`` ``(n, nq)``
        (:meth:`swarm_ik.collision.RobotCollision.collides_many`: the verdict of the ``check``
        that ``AvoidCollisions.met`` runs, without computing the clearance)."""
        gl = self.collision
        if gl is None:
            return np.zeros(len(qs), dtype=bool)
        rc = self.problem.robot.collision_model()
        return rc.collides_many(qs, gl.scene, gl.margin, bool(gl.self_collision))

    def free_table(self, bc: BatchChain) -> tuple[FloatArray, FloatArray]:
        """The scene's table of collision-free configurations: of :data:`FREE_TABLE_DRAWS`
        draws of :func:`_window_table` (from a fixed seed), those coal finds free, with their
        poses of the first goal frame: ``(q (K, nq), poses (K, 4, 4))``.  Made once per scene,
        collision settings and bounds in each process (kept on the robot for the next batch,
        whatever its seed: a table drawn from each batch's seed was made again, 2,048 checks,
        in each timed call with a new seed, and a 5 ms limit took 55 ms); the same in every
        process, so a target's answer does not depend on the chunking."""
        gl = self.collision
        tables = self.problem.robot._cache.setdefault("free_tables", {})
        key = (
            gl.scene if gl is not None else None, None if gl is None else gl.margin,
            None if gl is None else bool(gl.self_collision),
            bc.bounds.lower.tobytes(), bc.bounds.upper.tobytes(),
        )  # fmt: skip
        hit = tables.get(key)
        if hit is None:
            if len(tables) >= 8:
                tables.clear()
            hit = tables[key] = _window_table(
                bc, 0, 0xF2EE, FREE_TABLE_DRAWS, lambda qs: ~self.in_contact(qs)
            )
        return hit  # type: ignore[no-any-return]

    def judge(
        self,
        q: FloatArray,
        q0: FloatArray,
        tol_pos: float,
        tol_rot: float,
        known_free: bool = False,
    ) -> list[bool]:
        """Whether each of :attr:`primary` is met at ``q`` by the independent check of
        :meth:`IKProblem.verify` (``Goal.met`` on Pinocchio's state; the collision goal by
        :meth:`in_contact`, skipped when ``known_free``: already found free at this ``q``)."""
        state: State | None = None
        out = []
        for gl in self.primary:
            if isinstance(gl, AvoidCollisions):
                out.append(known_free or not self.in_contact(q[None])[0])
                continue
            if state is None:
                state = State(self.problem.robot, q, q0)
            out.append(bool(gl.met(state, tol_pos, tol_rot)[2]))
        return out


@dataclass(frozen=True)
class BatchChain:
    """What a worker needs of a robot: the tree arrays and the bounds (plain arrays, so
    shipping it to a Dask worker needs neither the URDF nor Pinocchio), and the batch's goals
    when it has any (then the robot travels with them).

    Attributes:
        tree: The kinematic tree (:class:`swarm_ik.kernels.fk.TreeArrays`); targets are for
            its first frame.
        bounds: Limits, continuous and prismatic joints (:class:`swarm_ik.kernels.lm.Bounds`).
        goals: The goals applied to every target besides its own (None: the target alone).
    """

    tree: TreeArrays
    bounds: lm.Bounds
    goals: BatchGoals | None = None

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


@dataclass(frozen=True, eq=False)
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
        goals_met: As :class:`BatchResult` (None without goals).
    """

    start: int
    time_s: float
    goals_met: BoolArray | None = None


@dataclass(frozen=True, eq=False)
class BatchResult(_Rows, FrozenArrays):
    """What :func:`solve_batch` returns: one row per target (its arrays read-only, as
    checked; ``.copy()`` gives a writable one).

    Attributes:
        q: Best joint vector per target (rad / m), shape ``(N, nq)``.
        position_error: ‖p − p_target‖ [m], ``(N,)`` (the batched FK's; Pinocchio's within
            :data:`JUDGE_MARGIN` of a tolerance); NaN for a target the time limit left
            unstarted (not measured).
        rotation_error: Geodesic angle between reached and target orientation [rad], ``(N,)``
            (NaN likewise, and NaN in a position-only batch: no target orientation).
        success: Both errors within tolerance (rotation ignored when position-only) and ``q``
            within the limits, ``(N,)``.
        n_evals: FK + Jacobian evaluations spent per target, ``(N,)``.
        n_starts: Starts polished per target (1: the seed start converged; 0: not started
            before the time limit, ``q`` its first start), ``(N,)``.
        time_s: Wall-clock seconds of the whole call (``setup_s`` included).
        setup_s: Seconds spent starting or connecting to the Dask cluster (0 in-process).
        compute_s: Seconds spent in the chunks, summed over chunks (workers).
        settings: The settings used.
        joint_names: Joint names, ``(nq,)``.
        interrupted: Ctrl-C stopped the call (``keep_on_interrupt``): the rows are the
            chunks finished before it, the first targets in order.
        goal_labels: Labels of the primary goals given in ``goals`` (``Goal.describe()``),
            ``(k,)``; empty without goals.
        goals_met: Whether each of those goals is met at ``q`` by the independent check
            (``AvoidCollisions``: coal finds no contact), ``(N, k)``; checked only for targets
            whose own pose is within tolerance and on which the kernel converged (the other
            rows are False).  None when ``solve_batch`` had no ``goals``.
        unreachable: Whether each target is proven out of reach, ``(N,)``, as
            :func:`swarm_ik.solve` proves it (:func:`swarm_ik.api.unreachable_targets`): its
            point beyond the frame's reach or inside an obstacle, or a goal of ``goals`` that
            says it cannot be met; asked only of targets started and not solved (one the time
            limit left unstarted stays ``"time_limit"``; under a time limit, coal's test of a
            point in an obstacle's bounding box only until the limit).  None: not asked.
    """

    time_s: float
    setup_s: float
    compute_s: float
    settings: BatchSettings
    joint_names: tuple[str, ...] = ()
    interrupted: bool = False
    goal_labels: tuple[str, ...] = ()
    goals_met: BoolArray | None = None
    unreachable: BoolArray | None = None

    @classmethod
    def from_chunks(
        cls,
        parts: list[ChunkResult],
        robot: RobotModel,
        settings: BatchSettings,
        time_s: float,
        setup_s: float,
        interrupted: bool = False,
        goal_labels: tuple[str, ...] | None = None,
    ) -> BatchResult:
        """The chunks' answers joined in order (none: empty arrays); ``goal_labels``: those
        of the batch's primary goals (None: a batch without goals)."""

        def cat(attr: str, empty: Any) -> Any:
            return np.concatenate([getattr(p, attr) for p in parts]) if parts else empty

        met = None
        if goal_labels is not None:
            k = len(goal_labels)
            met = (
                np.concatenate([p.goals_met for p in parts])  # type: ignore[misc]
                if parts
                else np.zeros((0, k), dtype=bool)
            )

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
            goal_labels=tuple(goal_labels or ()),
            goals_met=met,
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
    def reason(self) -> NDArray[np.str_]:
        """Why each target ended, ``(N,)``, in :attr:`swarm_ik.Result.reason`'s words:
        ``"converged"`` (success), ``"unreachable"`` (proven out of reach:
        :attr:`unreachable`), ``"time_limit"`` (not started before the limit, or its starts
        cut short by it), ``"budget"`` (``max_evals`` spent), else ``"local_minima"`` (every
        start of ``max_starts`` ended without meeting the goals)."""
        s = self.settings
        out = np.full(self.n, "local_minima", dtype="<U12")
        if s.deadline is not None:
            out[self.n_starts < s.max_starts] = "time_limit"
        if s.max_evals is not None:
            out[self.n_evals >= s.max_evals] = "budget"
        out[self.n_starts == 0] = "time_limit"
        if self.unreachable is not None:
            out[self.unreachable] = "unreachable"
        out[self.success] = "converged"
        return out

    @property
    def poses_per_s(self) -> float:
        """Targets per wall-clock second."""
        return self.n / self.time_s if self.time_s > 0 else float("inf")

    def save(
        self, path: str | Path, targets: FloatArray | None = None, compress: bool = True
    ) -> Path:
        """Write the answers to ``.npz`` or ``.csv`` (chosen by the suffix).

        The ``.npz`` holds ``q``, ``position_error``, ``rotation_error``, ``success``,
        ``n_evals``, ``n_starts``, ``joint_names``, ``tol_pos``, ``tol_rot``, ``seed`` (and
        ``targets`` ``(N, 4, 4)`` when given; ``goal_labels`` and ``goals_met`` after a batch
        with goals), compressed unless ``compress`` is False (``swarm-ik batch`` after a
        Ctrl-C: 590,000 Panda rows in 0.4 s instead of 3.9–5.3 s).  The ``.csv`` has a header
        ``index, <joint names>, position_error, rotation_error, success, n_evals`` (then one
        ``met:<goal label>`` column per primary goal of a batch with goals) and one row per
        target.

        Raises:
            InvalidArgumentError: the suffix is neither ``.npz`` nor ``.csv``, or the file
                cannot be written (:func:`swarm_ik._validate.check_output_path`).
            InvalidTargetError: ``targets`` are not one pose per row (``(N, 4, 4)`` or
                ``(N, 7)`` rows ``x y z qx qy qz qw``, as :func:`check_targets` takes them).
        """
        p = check_output_path(path, "cannot write results to", (".csv", ".npz"))
        suffix = p.suffix.lower()
        if targets is not None:  # (written beside the rows: one checked pose per row)
            targets = check_targets(targets, positions=self.settings.position_only)
            if targets.shape[0] != self.q.shape[0]:
                raise InvalidTargetError(
                    f"targets hold {targets.shape[0]} poses for {self.q.shape[0]} results: "
                    "give the targets that were solved"
                )
        with written_in_place_of(p) as part:  # (never a partial file)
            self._write(part, suffix, targets, compress)
        return p

    def _write(self, p: Path, suffix: str, targets: FloatArray | None, compress: bool) -> None:
        """Write the answers to ``p`` in the format of ``suffix`` (see :meth:`save`)."""
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
                arrays["targets"] = targets
            if self.goals_met is not None:
                arrays["goal_labels"] = np.array(self.goal_labels, dtype=str)
                arrays["goals_met"] = self.goals_met
            with p.open("wb") as fb:  # (a file object: numpy adds no suffix to it)
                (np.savez_compressed if compress else np.savez)(fb, **arrays)
        else:
            names = self.joint_names or tuple(f"q{j}" for j in range(self.q.shape[1]))
            with p.open("w", newline="") as fh:
                w = csv.writer(fh)
                met = self.goals_met
                w.writerow(
                    ["index", *names, "position_error", "rotation_error", "success", "n_evals"]
                    + [f"met:{label}" for label in self.goal_labels if met is not None]
                )
                # (whole columns as Python numbers at once; csv writes a float as repr does,
                # the shortest text that reads back to it: 5x faster than a row at a time)
                q, dp, dr = (
                    self.q.tolist(),
                    self.position_error.tolist(),
                    self.rotation_error.tolist(),
                )
                ok, ev = self.success.astype(int).tolist(), self.n_evals.astype(int).tolist()
                flags = [()] * self.n if met is None else met.astype(int).tolist()
                w.writerows(
                    [i, *q[i], dp[i], dr[i], ok[i], ev[i], *flags[i]] for i in range(self.n)
                )

    def __repr__(self) -> str:
        return (
            f"BatchResult(n={self.n}, success_rate={self.success_rate:.4f}, "
            f"time_s={self.time_s:.3f}, poses_per_s={self.poses_per_s:.0f})"
        )


# --------------------------------------------------------------------------- checks
MAX_TARGETS = 10_000_000
"""Most targets of one :func:`solve_batch` call or targets file (a 4x4 pose is 128 bytes:
1.3 GB of poses, about as much again for the answers); split larger sets into calls."""
MAX_STARTS = 10_000
"""Largest ``max_starts`` (about 0.5 s of starts per target on a 7-joint arm)."""


def check_targets(targets: Any, orth_tol: float = 1e-6, positions: bool = False) -> FloatArray:
    """Validate a batch of target poses.

    Args:
        targets: Poses, shape ``(N, 4, 4)`` [m], or rows ``x y z qx qy qz qw``, shape
            ``(N, 7)`` (quaternions normalised); with ``positions`` also points, shape
            ``(N, 3)`` [m] (their poses unrotated).
        orth_tol: Tolerance on the orthonormality of the rotation blocks.
        positions: Whether ``(N, 3)`` points are targets (a position-only batch).

    Returns:
        Poses, shape ``(N, 4, 4)``, contiguous.

    Raises:
        InvalidTargetError: wrong shape, NaN/inf, bad bottom row or a non-rotation block; the
            message names the first bad target.
    """
    if np.iscomplexobj(targets):
        raise InvalidTargetError("targets must be real numbers, got complex values")
    arr = float_array(targets)  # (text, None, ragged nesting: refused by name)
    if arr.ndim >= 1 and arr.shape[0] > MAX_TARGETS:
        raise InvalidTargetError(
            f"{arr.shape[0]} targets; at most {MAX_TARGETS} per call "
            "(swarm_ik.batch.MAX_TARGETS): split them"
        )
    rows = arr.ndim == 2 and (arr.shape[1] == 7 or (positions and arr.shape[1] == 3))
    if rows and not np.all(np.isfinite(arr)):
        bad = int(np.flatnonzero(~np.isfinite(arr).all(axis=1))[0])
        raise InvalidTargetError(f"target {bad} contains NaN or infinite values")
    if rows and arr.shape[1] == 3:  # points: their poses unrotated
        out = np.zeros((arr.shape[0], 4, 4))
        out[:, [0, 1, 2, 3], [0, 1, 2, 3]] = 1.0
        out[:, :3, 3] = arr
        return out
    if rows:  # x y z qx qy qz qw (a block at a time: see below)
        out = np.empty((arr.shape[0], 4, 4))
        for a in range(0, arr.shape[0], BLOCK):
            out[a : a + BLOCK] = poses_from_rows(arr[a : a + BLOCK], a)
        return out
    if arr.ndim != 3 or arr.shape[1:] != (4, 4):
        also = ", (N, 3) points" if positions else ""
        raise InvalidTargetError(
            f"targets must have shape (N, 4, 4) or (N, 7) (x y z qx qy qz qw){also}; "
            f"got {arr.shape}"
        )
    # a block at a time: a Ctrl-C is answered between blocks (millions of targets)
    for a in range(0, arr.shape[0], BLOCK):
        _check_pose_block(arr[a : a + BLOCK], a, orth_tol)
    return np.ascontiguousarray(arr)


BLOCK = 1 << 16
"""Targets per numpy pass where a pass over millions of them is split so that a Ctrl-C is
answered between passes (the validation of :func:`check_targets`, the CLI's random targets)."""


def _check_pose_block(blk: FloatArray, first: int, orth_tol: float) -> None:
    """:func:`check_targets`' tests of the poses ``blk`` ``(n, 4, 4)``, the first of them
    target ``first`` (messages name targets by their index in the batch)."""
    finite = np.isfinite(blk).all(axis=(1, 2))
    if not finite.all():
        raise InvalidTargetError(
            f"target {first + int(np.flatnonzero(~finite)[0])} contains NaN or infinite values"
        )
    bottom = np.abs(blk[:, 3] - np.array([0.0, 0.0, 0.0, 1.0])).max(axis=-1, initial=0.0) > 1e-9
    if bottom.any():
        i = int(np.flatnonzero(bottom)[0])
        raise InvalidTargetError(
            f"target {first + i}: bottom row must be [0, 0, 0, 1], got {blk[i, 3].tolist()}"
        )
    # RᵀR − I and det R from the columns (whole-array products: einsum and LAPACK's det per
    # 3×3 matrix took 0.4 µs a target, 4 % of a batch on two threads, before any target)
    c0, c1, c2 = blk[:, :3, 0], blk[:, :3, 1], blk[:, :3, 2]
    orth = np.abs(
        np.stack(
            [
                np.einsum("ni,ni->n", c0, c0) - 1.0,
                np.einsum("ni,ni->n", c1, c1) - 1.0,
                np.einsum("ni,ni->n", c2, c2) - 1.0,
                np.einsum("ni,ni->n", c0, c1),
                np.einsum("ni,ni->n", c0, c2),
                np.einsum("ni,ni->n", c1, c2),
            ]
        )  # fmt: skip
    ).max(axis=0)
    det = np.einsum("ni,ni->n", c0, np.cross(c1, c2))
    bad = ~((orth <= orth_tol) & (np.abs(det - 1.0) <= orth_tol))  # (NaN: entries that
    # overflow, 1e200 say, are bad too)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise InvalidTargetError(
            f"target {first + i}: rotation is not orthonormal (max|RᵀR − I| = {orth[i]:.3g}, "
            f"det = {det[i]:.9g}, tolerance {orth_tol:g}); fix it with "
            "swarm_ik.pose.project_to_se3"
        )


def _seed_starts(bc: BatchChain, q0: Any, n: int) -> FloatArray:
    """First start per target ``(n, nq)``: ``q0`` (``(nq,)`` or ``(n, nq)``) wrapped and
    clipped into the limits (with one warning), else the middle of the joint ranges."""
    if q0 is None:
        return np.tile(0.5 * (bc.bounds.lower + bc.bounds.upper), (n, 1))
    arr = floats_or(
        q0, lambda: f"q0 must be {bc.nq} numbers or one row of them per target, got {q0!r:.80}"
    )
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
            stacklevel=user_stacklevel(),
        )
    return np.ascontiguousarray(fixed)


def pose_errors(
    tree: TreeArrays, q: FloatArray, targets: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Position [m] and rotation [rad] errors of ``q`` ``(N, nq)`` against ``targets``
    ``(N, 4, 4)`` for the tree's first frame, with the batched FK (not the LM kernel)."""
    return errors_of_poses(tree.fk(q)[:, 0] if q.shape[0] else np.empty((0, 4, 4)), targets)


def errors_of_poses(poses: FloatArray, targets: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Position [m] and rotation [rad] errors of poses ``(N, 4, 4)`` against ``targets``
    ``(N, 4, 4)``: the norm of the offset as the in-order sum of squares and
    :func:`swarm_ik.kernels.lie.relative_angles` (the bits of ``Pose.errors``)."""
    d = poses[:, :3, 3] - targets[:, :3, 3]
    with np.errstate(over="ignore"):  # (a target at 1e300 m: its error inf, as Pose.errors's)
        dp = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2])
    return dp, lie.relative_angles(targets[:, :3, :3], poses[:, :3, :3])


# --------------------------------------------------------------------------- chunks
def _polish_targets(
    tree: TreeArrays,
    goals: lm.GoalTable,
    bounds: lm.Bounds,
    t_par: FloatArray,
    cols: IntArray,
    q_seed: FloatArray,
    index: IntArray,
    settings: BatchSettings,
    spent: IntArray | None = None,
) -> tuple[FloatArray, IntArray, IntArray, BoolArray]:
    """:func:`_solve_targets` on ``n`` targets: ``(q (n, nq), evaluations, starts,
    converged)``; ``spent``: the evaluations each spent in earlier passes (default none),
    against ``settings.max_evals``."""
    n, nq = q_seed.shape
    spent = np.zeros(n, dtype=np.int64) if spent is None else np.ascontiguousarray(spent)
    q = np.empty((n, nq))
    evals = np.zeros(n, dtype=np.int64)
    starts = np.zeros(n, dtype=np.int64)
    conv = np.zeros(n, dtype=np.bool_)
    if n:
        seeds = np.ascontiguousarray(q_seed, dtype=float)
        loaded_despite_damage(  # (a cache damaged inside its files: removed, compiled again)
            lambda: _solve_targets(
                t_par, cols, seeds, index, tree, goals, kernels(), bounds,
                settings.lm_settings(), settings.tol_pos * settings.tol_margin,
                settings.tol_rot * settings.tol_margin, int(settings.max_starts),
                -1 if settings.max_evals is None else int(settings.max_evals), spent,
                int(settings.seed), SECONDARY_EVALS,
                NO_DEADLINE if settings.deadline is None else float(settings.deadline),
                float(settings.reserve),
                INTERRUPT_EVERY if threading.current_thread() is threading.main_thread() else 0,
                q, evals, starts, conv,
            )
        )  # fmt: skip
        raise_lost_ctrl_c()  # (a Ctrl-C the kernel's clock read lost)
    return q, evals, starts, conv


_Polished = tuple[FloatArray, IntArray, IntArray, BoolArray]
"""``(q (n, nq), evaluations (n,), starts (n,), converged (n,))`` of a polish pass."""

RESTART_TABLE = 512
"""Joint vectors of the restart table (:func:`_seed_table_restarts`; :func:`_window_table`
from the batch's seed)."""

TABLE_RESTARTS = 8
"""Restarts of a target whose first start did not converge that start from the table's
configurations nearest to its pose, before the kernel's uniform random restarts.  Measured
(Panda, 4,000 targets, 27.5 % not converged from the middle of the ranges): those targets
needed 28–31 evaluations each against 62 with uniform restarts, 18–19 per target in all
against 24.1."""


def _window_table(
    bc: BatchChain, seed: int, salt: int, n: int, keep: Any = None
) -> tuple[FloatArray, FloatArray]:
    """A table of starts: ``n`` joint vectors drawn uniformly in the restart window of the
    middle of the ranges (:func:`~swarm_ik.kernels.search.sampling_window`) from
    ``(seed, salt)``, those ``keep`` (rows → mask) keeps, with their poses of the first goal
    frame: ``(q (K, nq), poses (K, 4, 4))``; the same in every process."""
    b = bc.bounds
    lo, hi = np.empty_like(b.lower), np.empty_like(b.upper)
    sampling_window(b.lower, b.upper, 0.5 * (b.lower + b.upper), lo, hi)
    qs = np.random.default_rng([int(seed), salt]).uniform(lo, hi, size=(n, lo.shape[0]))
    if keep is not None:
        qs = qs[keep(qs)]
    qs = np.ascontiguousarray(qs)
    return qs, np.asarray(bc.tree.fk(qs), dtype=float)[:, 0]


def _seed_table_restarts(
    polish: Any,
    bc: BatchChain,
    targets: FloatArray,
    q_seed: FloatArray,
    settings: BatchSettings,
    later: BatchSettings | None = None,
) -> _Polished:
    """Every target polished from its seed; one that did not converge from up to
    :data:`TABLE_RESTARTS` of the restart table's configurations nearest to its pose
    (:func:`_window_table`, :func:`_nearest_poses`), one start a pass; one still not
    converged gets the kernel's random restarts, and its last start is a patient polish of
    the best point it found (:func:`_patient`), within ``max_starts`` in all.  The restarts,
    and a first start that is the middle of the ranges, give up sooner than a first start
    the caller gave (:func:`_restarts`).  A target's
    answer depends only on its seed, index, target and start (not on the chunking).

    Args:
        polish: ``(rows (m,), first starts (m, nq), settings, evaluations spent (m,) or None)
            -> (q, evals, starts, conv)`` of those targets (:func:`_polish_targets` or
            :func:`_polish_problem`).
        bc: The chain and bounds (the table's FK).
        targets: The chunk's poses ``(n, 4, 4)``.
        q_seed: Their first starts ``(n, nq)``.
        settings: The batch's settings.
        later: The settings of the passes after the first (default ``settings``): the
            chunk's own deadline for its restarts (:attr:`BatchSettings.restart_share`).
    """
    n = targets.shape[0]
    one = dataclasses.replace(settings, max_starts=1)
    first = one if settings.own_start else _restarts(one)  # (the middle of the ranges: a guess)
    q, evals, starts, conv = polish(np.arange(n), q_seed, first, None)
    settings = settings if later is None else later
    quick_one = _restarts(dataclasses.replace(settings, max_starts=1))
    redo = np.flatnonzero(~conv & (starts > 0))  # (one not started: the time limit is spent)
    if _past(settings):  # (no restart would start: the table and each pass cost 0.05-0.5 ms)
        return q, evals, starts, conv
    after_seed = settings.max_starts - 1
    patient = min(after_seed, 1)  # the last start: the best point, polished patiently
    k_table = min(TABLE_RESTARTS, after_seed - patient)
    if redo.size and k_table > 0:
        table_q, table_poses = _window_table(bc, settings.seed, 0x7AB1E, RESTART_TABLE)
        near = _nearest_poses(table_poses, targets[redo], k_table, settings)
        for k in range(near.shape[1]):
            if not redo.size or _past(settings):
                break
            qk, evk, stk, convk = polish(redo, table_q[near[:, k]], quick_one, evals[redo])
            evals[redo] += evk
            starts[redo] += stk
            q[redo[convk]], conv[redo[convk]] = qk[convk], True
            near, redo = near[~convk], redo[~convk]
    left = after_seed - patient - k_table
    if redo.size and left > 0 and not _past(settings):  # the kernel's random restarts,
        # after a start from the best point found (a local minimum: it stalls in a few
        # evaluations)
        rest = dataclasses.replace(_restarts(settings), max_starts=left)
        q2, ev2, st2, conv2 = polish(redo, np.ascontiguousarray(q[redo]), rest, evals[redo])
        evals[redo] += ev2
        starts[redo] += st2
        q[redo], conv[redo] = q2, conv2
        redo = redo[~conv2 & (st2 > 0)]
    if redo.size and patient and not _past(settings):
        q2, ev2, st2, conv2 = polish(
            redo, np.ascontiguousarray(q[redo]), _patient(settings), evals[redo]
        )
        evals[redo] += ev2
        starts[redo] += st2
        q[redo[conv2]], conv[redo[conv2]] = q2[conv2], True
    return q, evals, starts, conv


def _past(settings: BatchSettings) -> bool:
    """Whether ``settings``' deadline has passed (no target would start)."""
    return settings.deadline is not None and time.time() > settings.deadline


def _restarts(settings: BatchSettings) -> BatchSettings:
    """Settings of a batch target's restarts: ``settings`` with :data:`RESTART_LAM0` and
    :data:`RESTART_STALL_REL` (less damping at first, an earlier verdict on a stalling
    start)."""
    return dataclasses.replace(settings, lam0=RESTART_LAM0, stall_rel=RESTART_STALL_REL)


PATIENT_ITERS = 4
"""The patient last start of a batch target (:func:`_patient`) may run this many times
``max_iters`` evaluations."""


def _patient(settings: BatchSettings) -> BatchSettings:
    """Settings of a target's last start, a polish of the best point its other starts found:
    one start of :data:`PATIENT_ITERS` × ``max_iters`` evaluations that no slow step ends
    (``stall_rel`` 0: only ``stall_iters`` rejected steps in a row, or the damping exploding,
    end it).  The restarts' quick verdict on a stalling start (:data:`RESTART_STALL_REL`)
    gives up on targets near a singular or limit configuration whose steps shrink slowly:
    measured on 100,000 Panda FK targets with the quick settings on every start, 21 ended
    unsolved (errors 2e-5–2e-4), 14 of them solved by this start (9 unsolved with the patient
    ``stall_rel`` 0.05 on every start, at 10 % lower throughput)."""
    return dataclasses.replace(
        settings, max_starts=1, stall_rel=0.0, max_iters=PATIENT_ITERS * settings.max_iters
    )


def _polish_problem(
    bg: BatchGoals,
    problem: IKProblem,
    targets: FloatArray,
    q_first: FloatArray,
    q_seed: FloatArray,
    index: IntArray,
    settings: BatchSettings,
    spent: IntArray | None = None,
) -> _Polished:
    """:func:`_polish_targets` from ``q_first`` on ``problem``'s tree, goal table (a copy of
    its floats: the kernel rewrites them per target) and bounds; ``q_seed``: the targets' own
    starts (what goals such as ``MinimalDisplacement`` are encoded from)."""
    tab = problem.table(None)
    if not len(targets):
        return _polish_targets(
            problem.tree, tab, problem.bounds, np.zeros((0, 0)), np.zeros(0, dtype=np.int64),
            q_first, index, settings, spent,
        )  # fmt: skip
    t_par, cols = bg.target_params(problem, targets, q_seed)
    return _polish_targets(
        problem.tree, tab._replace(par=tab.par.copy()), problem.bounds, t_par, cols, q_first,
        index, settings, spent,
    )  # fmt: skip


def solve_chunk(
    bc: BatchChain,
    settings: BatchSettings,
    start: int,
    targets: FloatArray,
    q_seed: FloatArray,
) -> ChunkResult:
    """Solve one contiguous chunk of targets (the unit of work shipped to a Dask worker).

    With a collision goal the targets first go through the problem without it (the polish of
    the pose and the other goals, as the plain batch), the converged answers then tested by
    coal; those in contact are polished again without the goal, up to
    :data:`FREE_RETRIES_PER_START` × ``max_starts`` times, from the scene's free
    configurations nearest to their target
    (:meth:`BatchGoals.free_table`), then from random starts of their own
    (:func:`_retry_starts`), each answer tested by coal;
    only those still in contact go through the kernel with the collision goal's sphere rows,
    from where the first pass left them (restarts as usual).  Each target's answer still
    depends only on its seed, index, target and start.

    Args:
        bc: The robot's chain and limits (and the batch's goals).
        settings: Solver settings (seed, tolerances, restarts).
        start: Index of the chunk's first target in the whole batch (keys the random streams).
        targets: Valid poses, shape ``(n, 4, 4)``.
        q_seed: First start per target, shape ``(n, nq)``, inside the limits.

    Returns:
        The chunk's answers, errors (checked with the batched FK; the goals' own check for
        the targets the kernel converged on) and counters.
    """
    t0 = time.perf_counter()
    n = targets.shape[0]
    bg = bc.goals
    if _past(settings):
        # (a chunk begun after the deadline starts no target: its tables, first FK and
        # errors cost 0.2-0.3 ms each, and a 2 ms limit on 2,000 Panda targets took 3.2 ms)
        return ChunkResult(
            q=np.array(q_seed, dtype=float), position_error=np.full(n, np.nan),
            rotation_error=np.full(n, np.nan), success=np.zeros(n, dtype=bool),
            n_evals=np.zeros(n, dtype=np.int64), n_starts=np.zeros(n, dtype=np.int64),
            start=start, time_s=time.perf_counter() - t0,
            goals_met=None if bg is None else np.zeros((n, len(bg.primary)), dtype=bool),
        )  # fmt: skip
    later = settings  # (the passes after the first: up to the chunk's share of the limit)
    if settings.deadline is not None and settings.restart_share > 0.0:
        own = time.time() + settings.restart_share * n
        later = dataclasses.replace(settings, deadline=min(settings.deadline, own))
    q_seed = np.ascontiguousarray(q_seed, dtype=float)
    index = np.arange(start, start + n, dtype=np.int64)
    free = np.zeros(n, dtype=bool)  # found free of contact by coal already
    if bg is None:  # the target's goal alone, on the tree of the first frame
        goal = Position if settings.position_only else Pose
        t_par = np.ascontiguousarray(goal.params(targets), dtype=float)
        table = lm.goal_table(
            [kernel_slot(goal.kernel)], [1.0], [True],
            [t_par[0].copy() if n else np.zeros(t_par.shape[1])],
            [np.zeros(1, dtype=np.int64)], [3 if settings.position_only else 6],
        )  # fmt: skip
        cols = np.arange(t_par.shape[1], dtype=np.int64)

        def polish(
            rows: IntArray, q_first: FloatArray, s: BatchSettings, spent: IntArray | None
        ) -> _Polished:
            return _polish_targets(
                bc.tree, table, bc.bounds, t_par[rows], cols, q_first, index[rows], s, spent
            )

        q, evals, starts, conv = _seed_table_restarts(polish, bc, targets, q_seed, settings, later)
    else:  # the problem of the goals; with a collision goal, passes without it, each answer
        # tested by coal, and the sphere rows only where every pass ended in contact
        goals = bg
        problem = bg.problem if bg.collision is None else bg.free_problem

        def polish(
            rows: IntArray, q_first: FloatArray, s: BatchSettings, spent: IntArray | None
        ) -> _Polished:
            return _polish_problem(
                goals, problem, targets[rows], q_first, q_seed[rows], index[rows], s, spent
            )

        q, evals, starts, conv = _seed_table_restarts(polish, bc, targets, q_seed, settings, later)
    if bg is not None and bg.collision is not None:
        done = np.flatnonzero(conv)
        free[done] = ~bg.in_contact(q[done])
        redo = np.flatnonzero(conv & ~free)
        one_start = dataclasses.replace(_restarts(later), max_starts=1)  # (one start each)
        near = np.empty((redo.size, 0), dtype=np.int64)
        if redo.size and FREE_TABLE_RETRIES:
            table_q, table_poses = bg.free_table(bc)
            near = _nearest_poses(table_poses, targets[redo], FREE_TABLE_RETRIES, settings)
        for k in range(FREE_RETRIES_PER_START * settings.max_starts):  # another branch: from
            # the table's free configurations
            if not redo.size:  # nearest to the target, then from random starts
                break
            if later.deadline is not None and time.time() > later.deadline:
                break  # (past the chunk's time: no retry would start)
            if k < near.shape[1]:
                q_k = table_q[near[:, k]]
            else:
                q_k = _retry_starts(
                    bc.bounds.lower, bc.bounds.upper, q_seed[redo], settings.seed, index[redo], k
                )
            qk, evk, stk, convk = polish(redo, q_k, one_start, evals[redo])
            evals[redo] += evk
            starts[redo] += stk
            ok = np.flatnonzero(convk)
            ok = ok[~bg.in_contact(qk[ok])]
            q[redo[ok]], free[redo[ok]] = qk[ok], True
            keep = ~free[redo] & (stk > 0)  # (one not started: its evaluations are spent)
            near = near[keep]
            redo = redo[keep]
        if redo.size:
            rows = dataclasses.replace(later, max_starts=min(settings.max_starts, ROWS_STARTS))
            q2, ev2, st2, conv2 = _polish_problem(
                bg,
                bg.problem,
                targets[redo],
                q[redo],
                q_seed[redo],
                index[redo],
                rows,
                evals[redo],
            )
            q[redo], conv[redo] = q2, conv2
            evals[redo] += ev2
            starts[redo] += st2
    # errors of the targets started (one the time limit left unstarted: NaN, not measured;
    # measuring them cost as much as solving a few thousand)
    dp, dr = np.full(n, np.nan), np.full(n, np.nan)
    ran = np.flatnonzero(starts > 0)
    if ran.size == n:
        dp, dr = pose_errors(bc.tree, q, targets)
    elif ran.size:
        dp[ran], dr[ran] = pose_errors(bc.tree, q[ran], targets[ran])
    within = np.all((q >= bc.bounds.lower - 1e-12) & (q <= bc.bounds.upper + 1e-12), axis=1)
    ok = within & (dp <= settings.tol_pos)
    if settings.position_only:  # (no target orientation: no rotation error, not the angle
        dr[:] = np.nan  # from the world frame that an unrotated target would give)
    else:
        ok &= dr <= settings.tol_rot
    met = None
    if bg is not None:
        k = len(bg.primary)
        met = np.zeros((n, k), dtype=bool)
        if k:  # the goals' own check, where the kernel converged (unconverged targets fail)
            ok &= conv
            for i in np.flatnonzero(ok).tolist():
                met[i] = bg.judge(
                    q[i], q_seed[i], settings.tol_pos, settings.tol_rot, bool(free[i])
                )
                ok[i] = bool(met[i].all())
    return ChunkResult(
        q=q, position_error=dp, rotation_error=dr, success=ok, n_evals=evals, n_starts=starts,
        start=start, time_s=time.perf_counter() - t0, goals_met=met,
    )  # fmt: skip


JUDGE_MARGIN = 1e-9
"""[m, rad] How near a tolerance a batch answer's error (the batched FK's) must lie for its
verdict to be taken again from Pinocchio's FK (:func:`_judged_near_tolerance`).  The two
agree to about 1e-15 on a pose within metres of the origin (``tests/test_fk.py``: 1e-12), so
an error further from the tolerance than this has the same verdict from either."""


def _judged_near_tolerance(
    res: BatchResult, robot: RobotModel, targets: FloatArray, settings: BatchSettings, plain: bool
) -> BatchResult:
    """``res`` with the answers whose pose error lies within :data:`JUDGE_MARGIN` of a
    tolerance measured again with Pinocchio's FK (as :func:`swarm_ik.verify` measures it) and
    judged on those errors: a success Pinocchio puts beyond a tolerance is none (review 134:
    95 of 200 answers placed 1e-16 m beyond ``tol_pos`` by Pinocchio were successes of the
    batched FK), and, without goals (``plain``), an answer within the limits that Pinocchio
    puts within both tolerances is one.  With goals, only a success is taken back (whether
    the others' goals are met was not checked)."""
    dp, dr = res.position_error, res.rotation_error
    with np.errstate(invalid="ignore"):  # (NaN: a target not started, or no rotation)
        near = np.abs(dp - settings.tol_pos) <= JUDGE_MARGIN
        if not settings.position_only:
            near |= np.abs(dr - settings.tol_rot) <= JUDGE_MARGIN
    idx = np.flatnonzero(near)
    if not idx.size:
        return res
    q = res.q[idx]
    dp_p, dr_p = errors_of_poses(robot.fk_pinocchio_many(q), targets[idx])
    ok = dp_p <= settings.tol_pos
    if settings.position_only:
        dr_p = dr[idx]
    else:
        ok &= dr_p <= settings.tol_rot
    if plain:
        ok &= np.all((q >= robot.lower - 1e-12) & (q <= robot.upper + 1e-12), axis=1)
    else:
        ok &= res.success[idx]
    dp, dr, success = dp.copy(), dr.copy(), res.success.copy()
    dp[idx], dr[idx], success[idx] = dp_p, dr_p, ok
    return dataclasses.replace(res, position_error=dp, rotation_error=dr, success=success)


FREE_RETRIES_PER_START = 4
"""Passes without the collision goal per ``max_starts`` (512 by default) that a batch target
whose answer coal finds in contact gets before the pass with the goal's sphere rows (one
solve without a time limit makes :data:`swarm_ik.api.COLLISION_FIRST_TRIES`): the first
:data:`FREE_TABLE_RETRIES` start from the scene's free configurations nearest to the target
(:meth:`BatchGoals.free_table`), the rest from random starts of the target's own; each pass
polishes one start (no restarts inside it: 3,670 -> 5,200 poses/s per core among 40 boxes,
the same targets solved).  Each costs a polish (tens of µs) and coal's verdict (about 35 µs
among 40 boxes), the sphere rows about 60 µs per evaluation.  Each pass runs only the targets
still in contact.  Measured on 300 FK targets of free configurations among 50 boxes (a
held-out scene, boxes from 0.15 m of the base axis): 48 passes solved 274 (0.42 s), 128
passes 287, 256 passes 295, 512 passes 297 (0.30 s: fewer targets left to the sphere rows),
1,024 297; a solve of each (no time limit) 294."""

ROWS_STARTS = 16
"""Most starts of the last pass, with the collision goal's sphere rows (an evaluation there
costs about 60 µs among 40 boxes, 40 times a plain one): the few targets still in contact
after the retries (:data:`FREE_RETRIES_PER_START`).  With ``max_starts`` (128) there, two
targets of 2,000
took a fifth of the batch's time among 40 boxes; with 16, 4,000 targets among 60 boxes went
from 4,420 to 5,830 poses/s per core for one more target unsolved (99.90 % solved)."""

FREE_TABLE_DRAWS = 2048
"""Joint vectors drawn (uniformly within the limits, from a fixed seed) for a collision
goal's table of configurations coal finds free (:meth:`BatchGoals.free_table`; about half of
them among 40 boxes, built in 0.07 s once per scene and process)."""

FREE_TABLE_RETRIES = 24
"""Retries of a target in contact that start from the table's configurations nearest to its
pose (:func:`_nearest_poses`).  Measured (Panda, 40 random boxes, the 486 of 2,000 targets
whose first answer was in contact): 3.4 retries per target on average and 0.2 % still in
contact after 48, against 6.8 and 1.4 % from uniform random starts."""

POSE_LENGTH = 0.3
"""Length [m] weighing the rotation in the pose distance of :func:`_nearest_poses`:
``‖p − p*‖² + L²·(3 − tr(Rᵀ R*))`` (``3 − tr`` is ``2(1 − cos θ)``)."""


def _nearest_poses(
    poses: FloatArray, targets: FloatArray, k: int, settings: BatchSettings
) -> IntArray:
    """Indices ``(n, min(k, K))`` of the ``poses`` ``(K, 4, 4)`` nearest to each target
    ``(n, 4, 4)``, nearest first (the lower index first between equals), by the distance
    ``‖p − p*‖² + L²(3 − tr(RᵀR*))`` of :data:`POSE_LENGTH` (the position alone when
    ``settings.position_only``): :func:`_nearest_rows`."""
    k = min(k, poses.shape[0])
    out = np.empty((targets.shape[0], k), dtype=np.int64)
    _nearest_rows(
        np.ascontiguousarray(poses, dtype=float), np.ascontiguousarray(targets, dtype=float),
        0.0 if settings.position_only else POSE_LENGTH**2, out,
    )  # fmt: skip
    return out


@numba.njit(cache=True, nogil=True)
def _nearest_rows(
    poses: FloatArray, targets: FloatArray, w_rot2: float, out: IntArray
) -> None:  # pragma: no cover - compiled
    """For each target ``(n, 4, 4)``, the indices of the ``out.shape[1]`` poses ``(K, 4, 4)``
    nearest to it into ``out``, nearest first, by ``‖p − p*‖² + w_rot2·(3 − tr(RᵀR*))``: one
    pass over the poses keeping the nearest in order (insertion), where numpy's matrix
    products and partial sorts cost 30 µs a target."""
    k = out.shape[1]
    if k == 0:
        return
    best = np.empty(k)
    for i in range(targets.shape[0]):
        m = 0
        for c in range(poses.shape[0]):
            dx = poses[c, 0, 3] - targets[i, 0, 3]
            dy = poses[c, 1, 3] - targets[i, 1, 3]
            dz = poses[c, 2, 3] - targets[i, 2, 3]
            d = dx * dx + dy * dy + dz * dz
            if w_rot2 > 0.0:
                tr = 0.0
                for a in range(3):
                    for b in range(3):
                        tr += poses[c, a, b] * targets[i, a, b]
                d += w_rot2 * (3.0 - tr)
            if m == k and not d < best[k - 1]:
                continue
            s = m if m < k else k - 1  # (the slot it enters from: the end)
            while s > 0 and d < best[s - 1]:
                best[s] = best[s - 1]
                out[i, s] = out[i, s - 1]
                s -= 1
            best[s] = d
            out[i, s] = c
            if m < k:
                m += 1


@numba.njit(cache=True, nogil=True)
def _retry_starts(
    lower: FloatArray, upper: FloatArray, q_seed: FloatArray, seed: int, index: IntArray, k: int
) -> FloatArray:  # pragma: no cover - compiled
    """Retry ``k``'s start of each target ``index[r]`` ``(m, nq)``: uniform in the restart
    window around its seed ``q_seed[r]`` (:func:`~swarm_ik.kernels.search.sampling_window`),
    from a SplitMix64 stream of ``(seed, index, k)`` alone, so an answer does not depend on
    the chunking."""
    m, n = q_seed.shape
    out = np.empty((m, n))
    lo = np.empty(n)
    hi = np.empty(n)
    base = _splitmix64(np.uint64(seed) ^ np.uint64(0x5EED))
    for r in range(m):
        sampling_window(lower, upper, q_seed[r], lo, hi)
        key = _splitmix64(_splitmix64(base ^ np.uint64(index[r])) + np.uint64(k))
        for j in range(n):
            out[r, j] = uniform_in(lo[j], hi[j], key, np.uint64(j + 1))
    return out


def _run_chunk(
    bc: BatchChain, settings: BatchSettings, item: tuple[int, FloatArray, FloatArray]
) -> ChunkResult:
    start, targets, q_seed = item
    return solve_chunk(bc, settings, start, targets, q_seed)


MAX_CHUNK = 16384
"""Most targets per chunk of :func:`default_chunk_size`.  Each Dask task carries its chunk's
targets and the batch's chain and settings and returns its answers: fewer, larger chunks
spend less of a call on that (Panda, 10⁵ targets, Dask's two workers on two cores,
interleaved: 84,500 poses/s with chunks of 12,500 against 80,600 with 4,096, one process
46,000); four chunks a worker still share the work out evenly."""


def default_chunk_size(n: int, n_workers: int = 1) -> int:
    """Targets per chunk: about four chunks per worker, between 64 and :data:`MAX_CHUNK`."""
    return int(min(MAX_CHUNK, max(64, math.ceil(n / max(4 * n_workers, 1)))))


FINISH_PER_TARGET = 0.2e-6
"""Seconds per target that :func:`solve_batch` keeps out of a ``time_limit`` for what follows
the last polish of every target, started or not (the result's arrays, the bounds test), up to
half of what is left: targets stop starting that much earlier.  The check of a started
target's answer is kept per target as it starts (:data:`FINISH_PER_STARTED`; a target not
started is not checked)."""

FINISH_FIXED = 1e-4
"""Seconds a timed :func:`solve_batch` keeps out of its ``time_limit`` (up to half of what is
left) for the end of the call whatever its size (the result's arrays, the check of the
unsolved targets' reach) — the first call's estimate: each timed call then adds what it
overran its limit by (or lets a tenth go when it ended in time), per robot
(:func:`_finish_fixed`).  With the per-target share alone, one Panda target under a 1 ms
limit took 1.2–1.35 ms."""


def _finish_fixed(robot: RobotModel, overrun: float | None = None) -> float:
    """The robot's estimate of :data:`FINISH_FIXED` [s], corrected by ``overrun`` (seconds
    the call ended after its limit, negative when it ended earlier), within [0, 50 ms]."""
    est = float(robot._cache.get("batch_finish_s", FINISH_FIXED))
    if overrun is not None:
        est = min(max(est + overrun, 0.9 * est, 0.0), 0.05)
        robot._cache["batch_finish_s"] = est
    return est


FINISH_PER_STARTED = 2e-6
"""Seconds kept before the deadline per started target for the check of its answer (the
batched FK and errors, :func:`pose_errors`: 1.1–1.9 µs measured, yumi_left); with goals, one
call of their own check (:meth:`BatchGoals.judge`, Pinocchio) is added, and with a collision
goal twice coal's verdict at one configuration (each measured in :func:`_with_deadline`: the
contact test of the answer and the goals' check).  Without the goals' check, 3,000 Talos
targets with a centre-of-mass goal at 0.05 s took 0.08–0.12 s."""


_LOADED: set[tuple[bool, bool]] = set()
"""Kinds of batch (plain, with goals, with a collision goal) whose kernels this process has
loaded (:func:`_load_kernels`)."""


def _load_kernels(
    bc: BatchChain, settings: BatchSettings, poses: FloatArray, seeds: FloatArray
) -> float:
    """This process's kernels for the batch's kind of goals loaded from numba's cache (or
    compiled, on a cold one) on its first target, once per kind, with the line on stderr
    that a slow loading gives (:func:`swarm_ik.kernels.announced`: a cold ``swarm-ik batch``
    compiled for 50 s in silence); the seconds it took (charged as loading)."""
    bg = bc.goals
    key = (bg is None, bg is not None and bg.collision is not None)
    if key in _LOADED or not poses.shape[0]:
        return 0.0
    t = time.perf_counter()
    with announced():
        solve_chunk(bc, dataclasses.replace(settings, max_starts=1), 0, poses[:1], seeds[:1])
    _LOADED.add(key)
    return time.perf_counter() - t


def _with_deadline(
    bc: BatchChain,
    settings: BatchSettings,
    poses: FloatArray,
    seeds: FloatArray,
    limit: float,
    t0: float,
    loaded: float = 0.0,
    finish_fixed: float = FINISH_FIXED,
) -> BatchSettings:
    """``settings`` with the deadline of a ``time_limit`` of ``limit`` seconds begun at ``t0``
    (``time.perf_counter()``) and the ``reserve`` per started target (:data:`FINISH_PER_STARTED`
    and, with a collision goal, coal's verdicts timed here).  The ``loaded`` seconds the call
    spent loading this process's kernels (:func:`_load_kernels`: a process's first batch loads
    or compiles them), its goals (a robot's first
    scene: its sphere model, 0.2–0.6 s, more with an empty cache or a large mesh) and starting
    a Dask cluster and loading its workers are charged
    to the limit up to half of it (as a first solve's loading: the targets keep at least half,
    less what follows; a scene made on an empty cache took the whole limit, and no target
    started); what the call spent reading and checking the targets is charged whole (it grows
    with their number: 60 ms for 10⁵ poses), and ``finish_fixed`` (:data:`FINISH_FIXED`) and
    :data:`FINISH_PER_TARGET` per target are kept for the end of the call (at most half of
    what is left)."""
    t_load = time.perf_counter()
    reserve = FINISH_PER_STARTED
    if poses.shape[0]:  # (the kernels are loaded already: _load_kernels)
        bg = bc.goals
        if bg is not None and bg.collision is not None:
            # (8 distinct configurations: coal answers a configuration it has just checked
            # in 2.5 µs, a new one in 40-60 µs among 120 boxes; timed on one repeated, the
            # reserve was a twentieth of the verdicts' time, and a 0.3 s limit took 0.55 s)
            probe = _window_table(bc, settings.seed, 0x9E0BE, 9)[0]
            bg.in_contact(probe[:1])  # (the checker made for the scene: not timed)
            t_probe = time.perf_counter()
            bg.in_contact(probe[1:])
            reserve += 2.0 * (time.perf_counter() - t_probe) / (probe.shape[0] - 1)
        if bg is not None and len(bg.primary):  # the goals' own check of a solved target
            # (Pinocchio: tens of µs with a centre of mass; timed after a first call)
            args = (seeds[0], seeds[0], settings.tol_pos, settings.tol_rot, False)
            bg.judge(*args)
            t_judge = time.perf_counter()
            for _ in range(4):
                bg.judge(*args)
            reserve += (time.perf_counter() - t_judge) / 4
    now = time.perf_counter()
    load, other = now - t_load + loaded, t_load - t0 - loaded
    left = max(limit - other - load, 0.5 * limit - other)
    finish = finish_fixed + FINISH_PER_TARGET * poses.shape[0]
    left -= min(finish, 0.5 * max(left, 0.0))
    return dataclasses.replace(settings, deadline=time.time() + left, reserve=reserve)


@goals_base.names_kernel_errors(lambda *a, **kw: kw.get("goals"))
@keywords_checked
def solve_batch(
    robot: RobotModel,
    targets: Any,
    *,
    seed: int | None = 0,
    q0: Any = None,
    tol_pos: float = 1e-5,
    tol_rot: float = 1e-5,
    position_only: bool = False,
    goals: Any = None,
    max_starts: int = 128,
    max_iters: int = BATCH_MAX_ITERS,
    max_evals: int | None = None,
    time_limit: float | None = None,
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

    ``goals`` adds goals of :mod:`swarm_ik.goals` to every target, in the compiled kernel: the
    problem of each target is ``IKProblem(robot, goals=[Pose(ee, target), *goals])``
    (``Position`` when ``position_only``), e.g. ``AvoidCollisions(scene)``, ``Axis``,
    ``CenterOfMass`` or a secondary ``Posture`` (lowered in the null space of the primary
    goals once a target is solved).  A target then succeeds when its pose is within
    tolerance, the kernel converged on every primary goal, and each primary goal of ``goals``
    passes the independent check of :meth:`IKProblem.verify` (:attr:`BatchResult.goals_met`;
    ``AvoidCollisions``: coal finds no contact).  With a collision goal each target is first
    solved without it, from its start and then from up to
    :data:`FREE_RETRIES_PER_START` × ``max_starts`` other starts (the scene's free
    configurations nearest to the target, then random ones) while coal finds the answer in
    contact; only answers still in contact are polished again with the goal's sphere rows,
    from where they are, up to ``min(max_starts, ROWS_STARTS)`` starts (see
    :func:`solve_chunk`).

    Args:
        robot: The robot.
        targets: Target poses, shape ``(N, 4, 4)`` [m], or rows ``x y z qx qy qz qw``,
            shape ``(N, 7)``; with ``position_only`` also points, shape ``(N, 3)`` [m].
        seed: Seed of the per-target restart streams, ``0 <= seed < 2**63`` (None: 0, as
            :func:`swarm_ik.solve`; a Generator is refused: each target's stream is keyed by
            an integer).
        q0: First start, shape ``(nq,)`` (all targets) or ``(N, nq)`` (one per target);
            clipped into the limits with a warning when outside.  Default: the middle of the
            joint ranges.
        tol_pos: Position tolerance of success [m].
        tol_rot: Rotation tolerance of success [rad].
        position_only: Ignore the target orientation.
        goals: Goals applied to every target besides its pose (compiled goals only; goal
            frames other than the first need the robot loaded with them).  None or empty: the
            pose alone (the plain batch).
        max_starts: Most starts per target's search (the seed start included); unreachable
            targets cost this many polishes.  The last is a patient polish of the best point
            found (up to ``PATIENT_ITERS × max_iters`` evaluations, no verdict on slow
            steps).  With a collision goal, an answer coal finds in contact gets up to
            :data:`FREE_RETRIES_PER_START` × ``max_starts`` one-start searches without the
            goal, then one search with its sphere rows of up to ``min(max_starts,``
            :data:`ROWS_STARTS` ``)`` starts: more ``max_starts`` buys more of both.
        max_iters: Most FK + Jacobian evaluations per start.
        max_evals: Most FK + Jacobian evaluations per target over all its starts and passes
            (as :func:`swarm_ik.solve`'s ``max_evals`` bounds one solve; None: ``max_starts``
            and ``max_iters`` alone bound them); ``BatchResult.n_evals`` never exceeds it.
        time_limit: Seconds for the whole call: no target (nor restart block) starts after
            them, less what reading and checking the targets took, :data:`FINISH_PER_TARGET`
            per target kept for the end of the call and :data:`FINISH_PER_STARTED` per target
            started (with a collision goal, coal's verdicts too), and the targets not reached
            are reported unsolved (``n_starts`` 0, ``q`` their seed, errors NaN).  Checking
            the targets costs about 0.6 µs per target, so a limit shorter than that is
            overrun (a first call in a process also by loading the kernels, and any call
            by loading its goals, a robot's first scene's sphere model included, and by
            starting a Dask cluster and loading its workers, one target each: together up
            to half the limit).  Within a chunk every target first gets its seed's start,
            then the targets still open their restarts (one pass after another); a chunk's restarts
            stop at its share of the limit (its targets' share of what was left, counted
            from its start: :attr:`BatchSettings.restart_share`), so hopeless targets of one
            chunk leave time to the chunks after it.  A target reached
            may be left unsolved where a call without the limit would have restarted it,
            and a target whose best answer when the limit came lies between the search's
            stop test (``tol_margin`` × the tolerances) and the tolerances is a success with
            that answer, where a call without the limit would have restarted it and may
            answer with another branch (as with a smaller ``max_starts``); every success
            meets the tolerances, judged with Pinocchio.  Which targets are
            reached depends on the machine's speed.  The first batch of a process loads
            its kernels (or compiles them) before the targets start: charged to the limit up
            to half of it, as a first :func:`swarm_ik.solve`'s loading.
        scheduler: ``None`` (in this process, no Dask), ``"threads"`` (in this process, a
            thread per core: the kernels release the GIL; no Dask), ``"local"`` (an embedded
            ``dask.distributed.LocalCluster``, one single-threaded worker process per core),
            a scheduler address such as ``"tcp://127.0.0.1:8786"``, or a
            ``distributed.Client``.  Every choice gives the same answers.
        chunk_size: Targets per chunk (default: :func:`default_chunk_size`).
        progress: Show a progress bar (tqdm) over the chunks.
        keep_on_interrupt: On Ctrl-C return the chunks finished so far (``interrupted``
            set) instead of raising ``KeyboardInterrupt``; chunks then go out in waves of two
            per worker (``swarm-ik batch``).  An embedded cluster's worker processes are
            started with SIGINT blocked either way: a Ctrl-C reaches this process alone.

    Returns:
        A :class:`BatchResult`, one row per target, in the order of ``targets``.

    Raises:
        InvalidTargetError: a target is not a valid pose (the first bad one named).
        InvalidArgumentError: bad ``q0``, settings, ``chunk_size``, ``scheduler`` or
            ``time_limit``; bad ``goals``, or a goal written in Python.
        UnknownNameError: a goal frame the robot was not loaded with.
    """
    from swarm_ik import distributed

    if not isinstance(robot, RobotModel):
        raise InvalidArgumentError(
            f"robot must be a RobotModel (see swarm_ik.load_robot), got {type(robot).__name__}"
        )
    from swarm_ik._validate import flag, float_array, positive_float

    position_only = flag(position_only, "position_only")
    progress = False if progress is None else flag(progress, "progress (or None)")
    keep_on_interrupt = flag(keep_on_interrupt, "keep_on_interrupt")
    if seed is None:  # (as solve's: seed 0)
        seed = 0

    t0 = time.perf_counter()
    limit = None
    loading_s = 0.0  # (the clock's bridge, the goals, the kernels: charged up to half the limit)
    if time_limit is not None:
        limit = positive_float(time_limit, "time_limit")
        wall_clock()  # (its first call in a process loads numba's bridge to Python, 40-70 ms:
        # charged as loading, up to half the limit; it was charged whole, and a first call
        # with a 50 ms limit started no target)
        loading_s = time.perf_counter() - t0
    targets = float_array(targets, "targets")
    settings = BatchSettings(
        tol_pos=positive_float(tol_pos, "tol_pos"),
        tol_rot=positive_float(tol_rot, "tol_rot"),
        position_only=position_only,
        max_starts=max_starts,
        max_iters=max_iters,
        seed=seed,
        own_start=q0 is not None,
        max_evals=max_evals,
    )
    poses = check_targets(targets, positions=settings.position_only)
    n = poses.shape[0]
    bc = BatchChain.from_robot(robot)
    labels = None
    if goals is not None and (not isinstance(goals, (list, tuple)) or len(goals)):
        t_goals = time.perf_counter()
        first = poses[0] if n else robot.fk(robot.mid_q())
        bgoals = BatchGoals(robot, goals, settings.position_only, first)
        bc = dataclasses.replace(bc, goals=bgoals)
        labels = bgoals.labels
        if time_limit is not None and bgoals.collision is not None and n:
            bgoals.free_table(bc)  # (its retries' table too: made once per scene, 0.05-0.1 s)
        loading_s += time.perf_counter() - t_goals  # (a scene's sphere model and checker)
    if chunk_size is not None and (
        isinstance(chunk_size, bool)
        or not isinstance(chunk_size, (int, np.integer))
        or chunk_size < 1
    ):
        raise InvalidArgumentError(f"chunk_size must be a positive integer, got {chunk_size!r}")
    distributed.check_scheduler(scheduler)  # (refused before the kernels load: 0.3-17 s)
    seeds = _seed_starts(bc, q0, n)
    loading_s += _load_kernels(bc, settings, poses, seeds)  # (before any clock; said when slow)
    interrupted = False
    with contextlib.ExitStack() as stack:
        t_setup = time.perf_counter()
        # (worker processes are started here for an embedded cluster only, deaf to SIGINT:
        # distributed.sigint_blocked_for_workers; kept on interrupt, a Ctrl-C during the whole
        # start-up, the client's included, is held until the cluster is up, in the stack)
        embedded = isinstance(scheduler, str) and scheduler == distributed.LOCAL
        guard = distributed.sigint_blocked_for_workers() if keep_on_interrupt and embedded else None
        try:
            with guard or contextlib.nullcontext():
                client = stack.enter_context(distributed.connect(scheduler))
        except KeyboardInterrupt:  # a Ctrl-C during the cluster's start-up, raised once it
            if not keep_on_interrupt:  # is up (closed by the stack on the way out)
                raise
            logging.getLogger("distributed").setLevel(logging.CRITICAL)
            return BatchResult.from_chunks(
                [], robot, settings, time.perf_counter() - t0, time.perf_counter() - t_setup,
                True, labels,
            )  # fmt: skip
        setup_s = time.perf_counter() - t_setup
        if limit is not None:  # (a cluster's start-up, and its workers' loading of the
            # kernels and goals, one target each, charged as this process's loading)
            if n and client is not None:
                warm = dataclasses.replace(settings, max_starts=1)
                try:
                    distributed.on_every_worker(
                        client, functools.partial(_run_chunk, bc, warm),
                        (0, poses[:1], seeds[:1]), name="swarm-ik-batch",
                    )  # fmt: skip
                except KeyboardInterrupt:
                    if not keep_on_interrupt:
                        raise
                    logging.getLogger("distributed").setLevel(logging.CRITICAL)
                    distributed.abandon(client)
                    return BatchResult.from_chunks(
                        [], robot, settings, time.perf_counter() - t0, setup_s, True, labels
                    )
            loaded = loading_s + time.perf_counter() - t_setup
            settings = _with_deadline(
                bc, settings, poses, seeds, limit, t0, loaded, _finish_fixed(robot)
            )
        workers = distributed.n_workers(client)
        size = int(chunk_size) if chunk_size is not None else default_chunk_size(n, workers)
        if limit is not None and n and settings.deadline is not None:
            # each chunk's restarts get its share of what is left (its targets' share, the
            # workers running chunks side by side), counted from the chunk's start: the first
            # chunk's hopeless targets took a whole limit, later chunks never started
            left = max(settings.deadline - time.time(), 0.0)
            share = left * max(workers, 1) / n
            settings = dataclasses.replace(settings, restart_share=share)
        items = [(s, poses[s : s + size], seeds[s : s + size]) for s in range(0, n, size)]
        func = functools.partial(_run_chunk, bc, settings)
        parts: list[ChunkResult] = []
        stack.enter_context(ctrl_c_counted())  # (a Ctrl-C a kernel loses: raised after it)
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
                distributed.abandon(client)  # (its workers killed: the exit closes at once)
            finally:
                bar.close()
    done = BatchResult.from_chunks(parts, robot, settings, 0.0, setup_s, interrupted, labels)
    done = _judged_near_tolerance(done, robot, poses, settings, plain=bc.goals is None)
    # (the targets started and not solved: proven out of reach, as solve proves it, or not;
    # one the time limit left unstarted was not examined)
    unsolved = np.flatnonzero(~done.success & (done.n_starts > 0))
    beyond = np.zeros(done.n, dtype=bool)
    if unsolved.size:
        problem = bc.goals.problem if bc.goals is not None else IKProblem(robot, poses[0])
        beyond[unsolved] = unreachable_targets(  # (coal's probes within the time limit)
            problem, poses[unsolved, :3, 3], settings.tol_pos, settings.tol_rot,
            None if limit is None else t0 + limit,
        )  # fmt: skip
    elapsed = time.perf_counter() - t0
    if limit is not None and n and not interrupted:  # (what the end took: the next call's)
        _finish_fixed(robot, elapsed - limit)
    return dataclasses.replace(done, time_s=elapsed, unreachable=beyond)


# --------------------------------------------------------------------------- files
def read_targets(path: str | Path, positions: bool = False) -> FloatArray:
    """Read target poses from a file.

    * ``.npz``: the array ``targets`` (or ``poses``, or the file's only array), shape
      ``(N, 4, 4)`` or ``(N, 7)``; ``.npy``: one such array.
    * ``.csv``: one target per row, either 7 columns ``x y z qx qy qz qw`` (a header naming
      them, in any order, is recognised) or 16 columns (the 4x4 matrix row by row).

    With ``positions`` (a position-only batch) points are targets too: arrays ``(N, 3)``,
    CSV rows of 3 columns ``x y z``.

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
        _check_magic(p, suffix)
        if suffix == ".npy":  # (mapped: its shape is checked before it is read)
            return check_targets(np.load(p, allow_pickle=False, mmap_mode="r"), positions=positions)
        data = np.load(p, allow_pickle=False)
        keys = list(data.keys())
        for k in ("targets", "poses"):
            if k in keys:
                return check_targets(data[k], positions=positions)
        if len(keys) == 1:
            return check_targets(data[keys[0]], positions=positions)
        raise InvalidArgumentError(
            f"{p}: no array named 'targets' or 'poses'; arrays in the file: "
            f"{', '.join(keys) or '(none)'}"
        )
    if suffix == ".csv":
        with p.open(newline="", encoding="utf-8-sig") as fh:  # (a byte-order mark, as
            # "CSV UTF-8" files of spreadsheets start with, dropped)
            # comma-separated, or separated by white space (np.savetxt's default) when the
            # first row that is not a comment has no comma
            data_line = next(
                (ln for ln in fh if ln.strip() and not ln.lstrip().startswith("#")), ""
            )
            fh.seek(0)
            split = csv.reader(fh) if "," in data_line else (ln.split() for ln in fh)
            rows = (r for r in split if r and not r[0].lstrip().startswith("#"))
            first = next(rows, None)
            if first is None:
                return np.empty((0, 4, 4))
            header = [h.strip().lower() for h in first]
            cols: list[int] | None = None
            try:
                [float(v) for v in first]
                body: Any = itertools.chain([first], rows)
            except ValueError:  # a header
                body = rows
                if all(c in header for c in POSE_COLUMNS):
                    cols = [header.index(c) for c in POSE_COLUMNS]
                elif positions and all(c in header for c in POSE_COLUMNS[:3]):
                    cols = [header.index(c) for c in POSE_COLUMNS[:3]]
                elif len(header) != 16:
                    missing = [c for c in POSE_COLUMNS if c not in header]
                    raise InvalidArgumentError(
                        f"{p}: header lacks column(s) {', '.join(missing)}; expected "
                        f"{', '.join(POSE_COLUMNS)} (or 16 matrix entries)"
                    ) from None
            table = _read_rows(p, body, len(first))
        if table.size == 0:
            return np.empty((0, 4, 4))
        if cols is not None:
            return check_targets(table[:, cols], positions=positions)
        if table.shape[1] == 7 or (positions and table.shape[1] == 3):
            return check_targets(table, positions=positions)
        if table.shape[1] == 16:
            return check_targets(table.reshape(-1, 4, 4))
        points = ", or 3 (x y z) for position-only targets" if positions else ""
        raise InvalidArgumentError(
            f"{p}: rows must have 7 columns (x y z qx qy qz qw) or 16 (a 4x4 matrix){points}, "
            f"got {table.shape[1]}"
        )
    raise InvalidArgumentError(
        f"cannot read targets from {str(p)!r}: unknown suffix {p.suffix!r}; valid suffixes: "
        ".csv, .npy, .npz"
    )


_MAGIC = {".npy": (b"\x93NUMPY",), ".npz": (b"PK\x03\x04", b"PK\x05\x06")}
"""The first bytes of numpy's ``.npy`` format and of a zip (``.npz``: a zip of ``.npy``
files; an empty zip starts with its end record)."""


def _check_magic(p: Path, suffix: str) -> None:
    """Refuse a ``.npy`` / ``.npz`` file that does not start as numpy's format does (numpy
    would try it as a pickle and say so), naming the file and what it looks like instead.

    Raises:
        InvalidArgumentError: not a ``.npy`` (``.npz``) file.
    """
    try:
        with p.open("rb") as fh:
            head = fh.read(64)
    except OSError as exc:
        raise InvalidArgumentError(
            f"{p}: cannot read targets ({exc.strerror or type(exc).__name__})"
        ) from None
    if head.startswith(_MAGIC[suffix]):
        return
    fmt = "numpy's binary array format" if suffix == ".npy" else "numpy's zip of arrays"
    text = head.decode("utf-8", "ignore")  # (a character cut at byte 64 dropped)
    if not head:
        seen = "it is empty"
    elif len(text) >= len(head) - 3 and all(c.isprintable() or c in "\t\r\n" for c in text):
        seen = "it holds text (a CSV file of targets is read when named .csv)"
    else:
        seen = f"it starts with {head[:8]!r}"
    raise InvalidArgumentError(f"{p}: not a valid {suffix} file ({fmt}); {seen}")


def _read_rows(p: Path, rows: Any, width: int) -> FloatArray:
    """The numeric CSV ``rows`` as a ``(n, width)`` array, converted as they are read (8 bytes
    a number, not a list of strings), at most :data:`MAX_TARGETS` of them.

    Raises:
        InvalidArgumentError: a non-numeric value, a row of another width, too many rows.
    """
    values = array.array("d")
    n = 0
    for r in rows:
        if len(r) != width:
            raise InvalidArgumentError(
                f"{p}: row {n + 1} has {len(r)} columns, the first row {width}"
            )
        n += 1
        if n > MAX_TARGETS:
            raise InvalidArgumentError(
                f"{p}: more than {MAX_TARGETS} rows (swarm_ik.batch.MAX_TARGETS): split the file"
            )
        try:
            values.extend(float(v) for v in r)
        except ValueError as exc:
            raise InvalidArgumentError(f"{p}: non-numeric value ({exc})") from None
    return np.frombuffer(values, dtype=float).reshape(n, width) if n else np.empty((0, width))


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


def read_targets_file(path: str | os.PathLike[str], positions: bool = False) -> FloatArray:
    """:func:`swarm_ik.batch.read_targets`, with unreadable files turned into one message.

    Raises:
        InvalidArgumentError: a corrupt ``.npz``/``.npy`` (not a zip, truncated, an object
            array that would need pickle), an unreadable file.
        InvalidTargetError: a row is not a valid pose.
    """
    try:
        return read_targets(Path(path), positions)
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
        if "allow_pickle" in reason or "Python objects in dtype" in reason:
            reason = "an object array of Python objects, not numbers"
        raise InvalidArgumentError(f"{path}: cannot read targets ({reason})") from None
