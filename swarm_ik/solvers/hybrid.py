"""``swarm``: the default solver, a memetic swarm + Levenberg–Marquardt hybrid.

[CS-IK] (cuckoo search + Newton) draws the lesson: a global population
finds the basin, a Jacobian method finishes.  This module turns that into a solver that is
exact (it stops at the tolerance, down to 1e-10), stays inside the joint limits, and is fast
enough to compare with TRAC-IK:

* **The polish** (:func:`swarm_ik.kernels.lm.lm_run`) is one numba-compiled function: for
  a batch of starts ``(k, nq)`` it runs a bounded Levenberg–Marquardt iteration on the stacked
  residual of the problem's primary goals (for a pose ``r(q) = [p* − p(q); log(R* R(q)ᵀ)]`` in
  world axes) with the exact residual Jacobian (for a pose ``[J_v; J_r⁻¹(φ) J_ω]``) built from
  the LOCAL_WORLD_ALIGNED frame Jacobians of :func:`swarm_ik.kernels.fk.fk_one` (checked
  against finite differences in the tests).
  Joint limits are handled as an active set (a joint at a limit whose Gauss–Newton direction
  points outwards is frozen for that step) and by projection (clipping; continuous joints
  wrapped).  Each start stops at the tolerance, at a local minimum (no progress), or at its
  iteration cap.  Every FK + Jacobian evaluation counts as one evaluation.
* **The swarm** keeps the best polished points that did not converge (an archive of
  ``pop_size`` local minima) as its population and proposes half of each next generation's
  starts from them with the grey wolf move of :mod:`swarm_ik.solvers.gwo`
  (:func:`swarm_ik.solvers.gwo.gwo_move`, [GWO] eqs. 3.3–3.7, the update
  [MGWO] builds on); the other half are uniform random starts.

**What the swarm proposals are worth: nothing measurable.**  Two ablations find no place for
them.  On plain pose targets (:func:`run`, ``swarm_fraction``): 0, 0.25 and 0.5 gave the same
success within noise, a swarm-only generation (1.0) was worse.  On collision problems
(``swarm-ik bench collision --scenes hard --n 100 --ablation``, ``docs/results/collision/hard``:
a cubby, a narrow shelf and 10–60 random boxes, Panda and UR5, 100 targets per scene, 50 ms,
same seed per target, on a shared 2-core machine): ``swarm_fraction=0`` (uniform restarts
only) solved the same targets as the default (pooled 85.5 % and 85.5 % on the Panda, 83.2 %
and 83.2 % on the UR5; at most one target apart in any scene) at the same median time.  Most
targets are solved in generation 0 (the seed, then uniform starts), before any proposal
exists; where a later generation was needed, the default spent fewer evaluations than
uniform restarts on 14 of 23 Panda targets and 26 of 55 UR5 targets: a coin toss.  What limits
success on those scenes is the sphere model of ``AvoidCollisions`` (the targets solved are
those with an IK branch the spheres find free), not the search.  In effect this solver is a
multi-start bounded Levenberg–Marquardt with uniform random restarts, and its grey-wolf
proposals are kept only because they do not hurt; the name ``swarm`` is a maintainer's
decision.

The first start is ``q0`` when given, else the middle of the joint ranges (TRAC-IK's
benchmark seed).  One polish iteration costs about a microsecond, so a typical pose is solved
in well under a millisecond; the whole search loop is compiled too
(:mod:`swarm_ik.kernels.search`), so Python runs only around it; see ``docs/performance.md``.
"""

from __future__ import annotations

import time
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from swarm_ik.errors import InvalidArgumentError, unknown
from swarm_ik.goals import base as goals_base
from swarm_ik.goals import kernels
from swarm_ik.kernels import lm, raise_ctrl_c, raise_lost_ctrl_c, search
from swarm_ik.kernels.lm import BUDGET, CONVERGED, ITER_CAP, LOCAL_MIN, NOT_RUN, LMSettings
from swarm_ik.periodic import nearest_winding, periodic_mask
from swarm_ik.problem import REPLACEABLE, IKProblem
from swarm_ik.solvers.base import Evaluator, FloatArray, register
from swarm_ik.solvers.gwo import gwo_move
from swarm_ik.solvers.python_lm import PolishOutcome, PythonPolisher

__all__ = [
    "BUDGET",
    "CONVERGED",
    "ITER_CAP",
    "LOCAL_MIN",
    "NOT_RUN",
    "Polisher",
    "SearchOutcome",
    "BoundSearch",
    "run",
]

FULL_BUDGET_TOL = 1e-14
"""Polish tolerance [m, rad] when the run is not to stop at success (``stop_on_success=False``,
as in the papers' experiments): each start is polished to round-off."""

PREFER = ("best", "nearest")
"""Answer selection modes of the ``swarm`` solver (``prefer`` parameter)."""


# --------------------------------------------------------------------------- python side
class Polisher(NamedTuple):
    """The compiled LM kernel (:func:`swarm_ik.kernels.lm.lm_run`) bound to one problem, with
    its scratch (made once).

    Build with :meth:`from_problem`.  ``kernel_tol_*`` are the tolerances the kernel stops at
    (``tol_margin`` × the success tolerances, so that Pinocchio's check passes with margin).
    """

    tree: lm.TreeArrays
    table: lm.GoalTable
    kernels: lm.GoalKernels
    bounds: lm.Bounds
    cfg: LMSettings
    kernel_tol_pos: float
    kernel_tol_rot: float
    work: Any
    """The scratch of :func:`swarm_ik.kernels.lm.lm_run` (``lm.Work``, for ``table``)."""

    @classmethod
    def from_problem(
        cls,
        problem: IKProblem,
        lower: FloatArray | None = None,
        upper: FloatArray | None = None,
        tol_pos: float = 1e-5,
        tol_rot: float = 1e-5,
        *,
        wrap: NDArray[np.bool_] | None = None,
        q0: FloatArray | None = None,
        settings: LMSettings = lm.DEFAULT_LM,
        **overrides: float,
    ) -> Polisher:
        """Bind the kernel to ``problem`` within the bounds.

        Args:
            problem: The IK problem.
            lower: Lower bounds, shape ``(nq,)`` (default the problem's).
            upper: Upper bounds, shape ``(nq,)``.
            tol_pos: Position tolerance of success [m].
            tol_rot: Angular tolerance of success [rad].
            wrap: Continuous-joint mask, shape ``(nq,)`` (default: the robot's).
            q0: The solve's start (fills ``MinimalDisplacement`` goals).
            settings: LM settings (default :data:`swarm_ik.kernels.lm.DEFAULT_LM`).
            **overrides: Fields of :class:`~swarm_ik.kernels.lm.LMSettings` to change.
        """
        cfg = settings._replace(**overrides).checked()  # type: ignore[arg-type]
        b = problem.bounds
        bounds = lm.Bounds(
            b.lower if lower is None else np.ascontiguousarray(lower, dtype=float),
            b.upper if upper is None else np.ascontiguousarray(upper, dtype=float),
            b.wrap if wrap is None else np.ascontiguousarray(wrap, dtype=np.bool_),
            b.linear,
        )
        if problem.python_goals:  # goals written in Python: the numpy polish
            return PythonPolisher(  # type: ignore[return-value]
                problem, bounds, cfg, float(tol_pos) * cfg.tol_margin,
                float(tol_rot) * cfg.tol_margin, q0,
            )  # fmt: skip
        table = problem.table(q0)
        return cls(
            problem.tree,
            table,
            kernels(),
            bounds,
            cfg,
            float(tol_pos) * cfg.tol_margin,
            float(tol_rot) * cfg.tol_margin,
            lm.make_work(problem.tree, table, table.rows_primary),
        )

    @property
    def wrap(self) -> NDArray[np.bool_]:
        """Continuous-joint mask, ``(nq,)``."""
        return self.bounds.wrap

    def polish(
        self,
        starts: FloatArray,
        max_evals: int,
        stop_first: bool = True,
        deadline: float | None = None,
    ) -> PolishOutcome:
        """Polish ``starts`` ``(k, nq)`` (inside the bounds) with at most ``max_evals``
        evaluations; with ``stop_first`` the call ends at the first converged start.
        ``deadline`` is the numpy polish's (:class:`PythonPolisher`); this one is held to a
        time by its ``max_evals`` (about a microsecond each)."""
        starts = np.ascontiguousarray(starts, dtype=float)
        k, n = starts.shape
        out_q = np.empty((k, n))
        dp = np.empty(k)
        dr = np.empty(k)
        status = np.empty(k, dtype=np.int64)
        evals = np.empty(k, dtype=np.int64)
        raise_lost_ctrl_c()  # (a loop of polishes: where a lost Ctrl-C is raised again)
        used = lm.lm_polish(
            starts, self.tree, self.table, self.kernels, self.bounds, self.cfg, self.kernel_tol_pos,
            self.kernel_tol_rot, int(max_evals), bool(stop_first), out_q, dp, dr, status, evals,
            self.work,
        )  # fmt: skip
        return PolishOutcome(out_q, dp, dr, status, evals, int(used))

    def secondary(
        self, q: FloatArray, max_evals: int, deadline: float | None = None
    ) -> tuple[FloatArray, int]:
        """Lower the secondary goals' cost in the primary null space
        (:func:`swarm_ik.kernels.lm.secondary_descent`); returns ``(q', evaluations)``
        (``deadline``: as :meth:`polish`)."""
        out = np.empty(q.shape[0])
        used = lm.secondary_descent(
            np.ascontiguousarray(q, dtype=float), self.tree, self.table, self.kernels, self.bounds,
            self.kernel_tol_pos, self.kernel_tol_rot, int(max_evals), out,
        )  # fmt: skip
        return out, int(used)

    def with_posture(self, q_ref: FloatArray) -> Polisher:
        """The same kernel with a secondary posture goal at ``q_ref`` added (``prefer=
        "nearest"``: slide along the self-motion towards ``q0``)."""
        from swarm_ik.goals.base import kernel_slot
        from swarm_ik.goals.joint import encode_joint, joint_kernel

        t = self.table
        nq = q_ref.shape[0]
        enc = encode_joint(
            np.asarray(q_ref, dtype=float), np.ones(nq), self.bounds.wrap, self.bounds.linear
        )
        ng = t.kind.shape[0]
        tab = lm.goal_table(
            [*t.kind.tolist(), kernel_slot(joint_kernel)],
            [*t.weight.tolist(), 1.0],
            [*t.primary.tolist(), False],
            [t.par[t.p0[i] : t.p0[i + 1]] for i in range(ng)] + [enc.par],
            [t.ipar[t.i0[i] : t.i0[i + 1]] for i in range(ng)] + [enc.ipar],
            [*t.nrows.tolist(), nq],
        )
        work = lm.make_work(self.tree, tab, tab.rows_primary)
        return self._replace(table=tab, kernels=kernels(), work=work)

    def toward(self, q: FloatArray, q_ref: FloatArray, max_evals: int) -> tuple[FloatArray, int]:
        """Move the solution ``q`` along its self-motion towards ``q_ref``."""
        return self.with_posture(q_ref).secondary(q, max_evals)

    def residual(self, q: FloatArray) -> tuple[FloatArray, FloatArray, float, float]:
        """Stacked primary residual ``r (rows,)``, its step Jacobian ``(rows, nq)``
        (``r(q + δ) ≈ r − jac @ δ``), largest position error [m] and angular error [rad]."""
        q2 = np.ascontiguousarray(np.asarray(q, dtype=float)[None])
        m = self.table.rows_primary
        res = np.empty((1, m))
        jac = np.empty((1, m, q2.shape[1]))
        err = np.empty((1, self.table.kind.shape[0], 2))
        lm.residuals_batch(
            q2, self.tree, self.table, self.kernels, self.bounds, True, res, jac, err
        )
        e = np.where(np.isnan(err[0][self.table.primary]), 0.0, err[0][self.table.primary])
        return res[0], jac[0], float(e[:, 0].max()), float(e[:, 1].max())

    def secondary_cost(self, q_batch: FloatArray) -> FloatArray:
        """Squared norm of the secondary stack for each row of ``q_batch`` ``(k, nq)``."""
        q2 = np.ascontiguousarray(np.atleast_2d(q_batch), dtype=float)
        err = np.empty((q2.shape[0], self.table.kind.shape[0], 2))
        c2 = np.empty(q2.shape[0])
        lm.errors_batch(q2, self.tree, self.table, self.kernels, self.bounds, err, c2)
        return c2


def wrapped_distance(a: FloatArray, b: FloatArray, wrap: NDArray[np.bool_]) -> FloatArray:
    """Euclidean joint-space distance with continuous joints' differences wrapped to
    ``[-π, π)``: ``a (..., nq)`` against ``b (nq,)`` → ``(...)``."""
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    if wrap.any():
        d[..., wrap] = (d[..., wrap] + np.pi) % (2 * np.pi) - np.pi
    return np.linalg.norm(d, axis=-1)


class SearchOutcome(NamedTuple):
    """What a :class:`BoundSearch` returns.

    Attributes:
        q: The answer (lowest fitness seen), ``(nq,)``.
        fitness: Its fitness ``dp + w_rot·dr`` (``inf`` when nothing was polished).
        position_error: Its position error [m] (kernel FK).
        rotation_error: Its angular error [rad] (kernel FK).
        used: Evaluations spent.
        stopped: The stop test (errors within the success tolerances) ended the run.
        history: Best fitness after each generation.
    """

    q: FloatArray
    fitness: float
    position_error: float
    rotation_error: float
    used: int
    stopped: bool
    history: FloatArray


def search_state(pol: Polisher, pop_size: int) -> Any:
    """The :class:`swarm_ik.kernels.search.SearchState` of ``pol`` for ``pop_size`` starts
    per generation (its goal table shared)."""
    return search.new_search_state(
        pol.tree, pol.table, pol.kernels, pol.bounds, pol.cfg, int(pop_size)
    )


class BoundSearch:
    """The compiled search (:func:`swarm_ik.kernels.search.swarm_search`) bound to a
    polisher and to the settings that stay fixed between its calls (a route's, made once):
    a call passes only the start, the stream key and the budgets.

    Args:
        pol: The polisher (kernel tolerances).
        pop_size, n_swarm, iterations: As :func:`run`.
        stop: Stop at the first point within ``tol_pos``/``tol_rot``.
        tol_pos, tol_rot: Success tolerances [m], [rad].
        w_rot: Angle weight of the fitness [m/rad].
        state: The polisher's :class:`swarm_ik.kernels.search.SearchState` for ``pop_size``
            (:func:`search_state`; made here when None).
    """

    def __init__(
        self,
        pol: Polisher,
        *,
        pop_size: int,
        n_swarm: int,
        iterations: int,
        stop: bool,
        tol_pos: float,
        tol_rot: float,
        w_rot: float,
        state: Any = None,
    ) -> None:
        self.state = search_state(pol, pop_size) if state is None else state
        self.nq = int(pol.bounds.lower.shape[0])
        self.fixed = (
            pol.kernel_tol_pos, pol.kernel_tol_rot,
            float(tol_pos) if stop else -1.0, float(tol_rot) if stop else -1.0, float(w_rot),
            int(pop_size), int(n_swarm), int(iterations),
        )  # fmt: skip

    def __call__(
        self,
        seed_q: FloatArray,
        key: np.uint64,
        max_evals: int | None,
        remaining: int,
        evals_before: int,
        time_limit: float | None,
        t0: float,
    ) -> SearchOutcome:
        """Search from ``seed_q`` (``(nq,)``, inside the bounds, float64 and contiguous).

        Args:
            seed_q: First start.
            key: Random stream key (:func:`swarm_ik.kernels.search.stream_key`).
            max_evals: The evaluation budget of the solve (``None``: none).
            remaining: Evaluations this call may spend.
            evals_before: Evaluations counted before (for the ``a`` schedule).
            time_limit: Seconds since ``t0`` (``None``: none).
            t0: Start of the solve, ``time.perf_counter()`` [s].
        """
        out_q = np.empty(self.nq)
        try:
            used, f, dp, dr, stopped, hist = search.swarm_search(
                self.state, seed_q, *self.fixed, max_evals is None and time_limit is None,
                int(min(remaining, 2**62)), -1 if max_evals is None else int(max_evals),
                int(evals_before),
                search.NO_LIMIT if time_limit is None else max(float(time_limit), 0.0),
                float(t0), key, out_q,
            )  # fmt: skip
        except SystemError as exc:  # (a Ctrl-C in the kernel's clock read: KeyboardInterrupt)
            raise_ctrl_c(exc)
            raise
        raise_lost_ctrl_c()
        return SearchOutcome(out_q, f, dp, dr, used, stopped, hist)


def compiled_ok(problem: IKProblem, prefer: str) -> bool:
    """Whether :func:`run` can hand its whole loop to the compiled search: ``prefer="best"``,
    every goal compiled and primary (a secondary goal needs the null-space descent after the
    search), the ``"se3"`` fitness, and no method of the problem replaced on the instance
    (e.g. wrapped to record a trace)."""
    return (
        prefer == "best"
        and not problem.python_goals
        and bool(np.all(problem.primary))
        and problem.fitness_name == "se3"
        and type(problem).fitness is IKProblem.fitness
        and type(problem).is_success is IKProblem.is_success
        and REPLACEABLE.isdisjoint(vars(problem))
    )


def check_params(
    pop_size: int,
    iterations: int,
    swarm_fraction: float,
    max_iters: int,
    prefer: str,
    nearest_starts: int,
    tol_margin: float,
) -> None:
    if pop_size < 1 or iterations < 0 or max_iters < 2 or nearest_starts < 0:
        raise InvalidArgumentError(
            "need pop_size >= 1, iterations >= 0, max_iters >= 2 and nearest_starts >= 0; got "
            f"pop_size={pop_size}, iterations={iterations}, max_iters={max_iters}, "
            f"nearest_starts={nearest_starts}"
        )
    if not 0.0 <= swarm_fraction <= 1.0:
        raise InvalidArgumentError(f"swarm_fraction must be in [0, 1], got {swarm_fraction}")
    if not 0.0 < tol_margin <= 1.0:
        raise InvalidArgumentError(f"tol_margin must be in (0, 1], got {tol_margin}")
    if prefer not in PREFER:
        raise unknown("prefer mode", prefer, PREFER)


def default_seed(
    problem: IKProblem, lower: FloatArray | None = None, upper: FloatArray | None = None
) -> FloatArray:
    """The first start without ``q0``: the first goal's preferred start
    (:meth:`~swarm_ik.goals.Goal.preferred_start`, a Posture's reference; clipped into the
    bounds) when one names it, else the middle of the ranges (TRAC-IK's seed)."""
    lo = problem.lower if lower is None else lower
    hi = problem.upper if upper is None else upper
    robot = problem.robot
    named = goals_base.preferred_start_of(problem.goals, robot)
    if named is not None:
        goal, q = named
        ref = robot.wrap(robot.check_q(q, f"{goal.describe()}.preferred_start()"))
        return np.clip(ref, lo, hi)
    return 0.5 * (lo + hi)


def propose(
    ev: Evaluator,
    rng: np.random.Generator,
    arch_x: FloatArray,
    arch_f: FloatArray,
    n_swarm: int,
    n_total: int,
    a: float,
    box: tuple[FloatArray, FloatArray] | None = None,
) -> FloatArray:
    """The next generation of starts: ``n_swarm`` grey-wolf moves of the archive of polished
    points (leaders = its three best; :func:`swarm_ik.solvers.gwo.gwo_move`) and uniform
    random starts for the rest, all inside the bounds.

    Args:
        ev: The evaluator (bounds, clipping, continuous joints).
        rng: Random generator.
        arch_x: Archive of polished points, best first, shape ``(p, nq)``.
        arch_f: Their costs, shape ``(p,)``.
        n_swarm: Number of swarm-proposed starts (0 when the archive is empty).
        n_total: Generation size.
        a: The GWO coefficient ``a`` (2: exploration … 0: exploitation).
        box: ``(lo, hi)`` of the uniform starts (default the bounds; see
            :func:`swarm_ik.urdf.sampling_bounds`).

    Returns:
        Starts, shape ``(n_total, nq)``.
    """
    k = arch_x.shape[0]
    n_swarm = min(n_swarm, n_total) if k > 0 else 0
    parts = []
    if n_swarm > 0:
        rows = np.arange(n_swarm) % k
        leaders = arch_x[np.arange(3) % k]  # alpha, beta, delta (repeated when k < 3)
        moved = gwo_move(arch_x[rows], leaders, a, rng)
        parts.append(ev.clip(moved))
    if n_total - n_swarm > 0:
        lo, hi = (ev.lower, ev.upper) if box is None else box
        parts.append(lo + (hi - lo) * rng.random((n_total - n_swarm, ev.dim)))
    return np.concatenate(parts) if parts else np.empty((0, ev.dim))


def run(
    ev: Evaluator,
    rng: np.random.Generator,
    *,
    pop_size: int = 12,
    iterations: int = 100,
    swarm_fraction: float = 0.5,
    max_iters: int = lm.DEFAULT_LM.max_iters,
    lam0: float = lm.DEFAULT_LM.lam0,
    max_step: float = lm.DEFAULT_LM.max_step,
    stall_rel: float = lm.DEFAULT_LM.stall_rel,
    stall_iters: int = lm.DEFAULT_LM.stall_iters,
    tol_margin: float = lm.DEFAULT_LM.tol_margin,
    prefer: str = "best",
    nearest_starts: int = 8,
    nearest_sigma: float = 0.1,
) -> None:
    """Memetic swarm + Levenberg–Marquardt IK (the default solver, ``swarm``).

    Generation 0 polishes the seed (``q0``, else the middle of the ranges) and then
    ``pop_size − 1`` uniform random starts, one after the other, stopping at the first that
    converges.  The polished points that did not converge (local minima, often against a joint
    limit) form an archive, best first; each later generation polishes
    ``round(swarm_fraction · pop_size)`` starts proposed from it by the grey wolf move
    (:func:`propose`; [GWO] eqs. 3.3–3.7, ``a`` falling from 2 to 0 with the spent
    share of the budget) and uniform random starts for the rest.  [CS-IK] is the
    model: the population finds the basin, the Jacobian method finishes; here the Jacobian
    method does most of the work and the population supplies starts.

    **Which code runs.**  With ``prefer="best"``, one primary goal under the ``"se3"``
    fitness, no secondary goal and no problem method replaced on the instance
    (:func:`compiled_ok`), and an evaluator whose stop test is the success test at
    ``ev.tolerance`` (or none: ``stop_on_success=False``), the whole loop below runs in one
    compiled call, :func:`swarm_ik.kernels.search.swarm_search` (its random stream keyed by one
    draw from ``rng``); its evaluations are counted with ``ev.add_evals``, its answer offered
    to ``ev`` and its history (one entry per generation) appended.  ``prefer="nearest"``,
    secondary goals, several primary goals, other fitness forms and custom stop predicates
    run the Python loop (with numpy's ``rng`` directly).  :func:`swarm_ik.solve` with an
    integer seed and :class:`swarm_ik.IKSolver` call the compiled search without an
    ``Evaluator`` (``swarm_ik.api._fast_path``), with the same key, so the same answer.

    Every FK + Jacobian evaluation of the compiled polish counts as one evaluation
    (``ev.add_evals``); a time limit is honoured by giving each compiled call only as many
    evaluations as the remaining time allows at the measured cost per evaluation.  The polish
    stops each start at ``tol_margin`` × the tolerance of ``ev.tolerance`` (1e-5 m / 1e-5 rad
    when the evaluator has none).

    With ``prefer="nearest"`` the answer is the solution nearest to ``q0`` rather than the
    lowest fitness: once a first solution is found, ``nearest_starts`` more starts drawn
    around ``q0`` are polished, each converged one taken as its 2π copy within the bounds
    nearest to ``q0`` (on joints whose range is 2π or more: the same pose), the nearest kept
    and, on a redundant arm, slid along its self-motion towards ``q0``
    (:func:`nullspace_toward`).

    Args:
        ev: The evaluator; must wrap an IK problem.
        rng: Source of all randomness.
        pop_size: Starts per generation (our choice: 12 keeps a generation well under a
            millisecond while giving the swarm enough personal bests).
        iterations: Generations when no ``max_evals``/``time_limit`` is given; also the
            length of the grey-wolf ``a`` schedule (``a = 2·(1 − max(t/iterations,
            n_evals/max_evals))``; elapsed time is not used, so results do not depend on the
            machine's speed unless the time limit cuts the run).
        swarm_fraction: Share of a generation proposed by the swarm (rest uniform random).
            Our choice, 0.5, from an ablation on 3000 FK-sampled targets per robot (Panda,
            Baxter) at 300 and 1500 evaluations: 0, 0.25 and 0.5 gave the same success within
            noise (e.g. 2, 2 and 0 failures of 3000 at 1500 evaluations); 1.0 (swarm only)
            was worse (11–12 failures).  Local minima of the pose residual are rarely next
            to a solution, so most of the global search comes from the uniform starts.
        max_iters: Evaluations per start before it is abandoned (a converging LM start needs
            about 10–20 on 6–7 joint arms).  The defaults of ``max_iters``, ``lam0``,
            ``max_step``, ``stall_rel``, ``stall_iters`` and ``tol_margin`` are those of
            :data:`swarm_ik.kernels.lm.DEFAULT_LM` (how they were chosen: its docstring).
        lam0: Initial LM damping, relative to the mean diagonal of ``JᵀJ``.
        max_step: Largest joint change per LM step (rad, or m for prismatic joints).
        stall_rel: A step that reduces the squared residual by less than this fraction…
        stall_iters: …this many times in a row marks a local minimum.
        tol_margin: The polish stops at this fraction of the tolerance, so that the
            independent Pinocchio check passes with margin.
        prefer: ``"best"`` (lowest fitness) or ``"nearest"`` (nearest to ``q0``).
        nearest_starts: Extra starts around ``q0`` polished in ``"nearest"`` mode.
        nearest_sigma: Their standard deviation, as a fraction of each joint's range; the
            extra starts spread geometrically from ``nearest_sigma`` to four times it.

    Raises:
        InvalidArgumentError: no IK problem behind ``ev``, or a parameter out of range.
        UnknownNameError: unknown ``prefer`` mode (the valid ones listed).
    """
    problem = ev.problem
    if problem is None:
        raise InvalidArgumentError("solver 'swarm' needs an IK problem (it uses the Jacobian)")
    check_params(
        pop_size, iterations, swarm_fraction, max_iters, prefer, nearest_starts, tol_margin
    )
    tol_pos, tol_rot = ev.tolerance if ev.tolerance is not None else (1e-5, 1e-5)
    if not ev.stops_on_success:  # the whole budget runs: polish down to round-off
        tol_pos, tol_rot = min(tol_pos, FULL_BUDGET_TOL), min(tol_rot, FULL_BUDGET_TOL)
    settings = lm.LMSettings(max_iters, lam0, max_step, stall_rel, stall_iters, tol_margin)

    def polisher(of: IKProblem) -> Polisher:
        return Polisher.from_problem(
            of, ev.lower, ev.upper, tol_pos, tol_rot, wrap=ev.wrap_mask, q0=ev.q0,
            settings=settings,
        )  # fmt: skip

    pol = polisher(problem)
    # a single-goal se3 cost is dp + w_rot·θ, which the kernel computes; any other cost (or
    # an overridden one) is evaluated by the problem itself
    se3 = (
        problem.fitness_name == "se3"
        and len(problem.goals) == 1
        and type(problem).fitness is IKProblem.fitness
    )
    w_rot = 0.0 if problem.position_only else problem.w_rot

    def fitness_of(q: FloatArray, dp: FloatArray, dr: FloatArray) -> FloatArray:
        if se3:
            return dp + w_rot * dr
        return np.asarray(problem.fitness(q), dtype=float)

    seed = ev.q0.copy() if ev.q0 is not None else default_seed(problem, ev.lower, ev.upper)
    if (
        compiled_ok(problem, prefer)
        and ev.f_target is None
        and (not ev.stops_on_success or ev.tolerance is not None)
    ):  # the whole loop in one compiled call (kernels/search.py)
        bound = BoundSearch(
            pol, pop_size=pop_size, n_swarm=int(round(swarm_fraction * pop_size)),
            iterations=iterations, stop=ev.stops_on_success, tol_pos=tol_pos, tol_rot=tol_rot,
            w_rot=w_rot,
        )  # fmt: skip
        res = bound(
            np.ascontiguousarray(seed, dtype=float),
            search.stream_key(rng) if ev.key is None else ev.key,
            ev.max_evals, ev.remaining, ev.n_evals, ev.time_limit, ev.t0,
        )  # fmt: skip
        prior = ev.best_f
        ev.add_evals(res.used)
        if np.isfinite(res.fitness):
            ev.add_evals(0, res.q, res.fitness)
        ev.history.extend(np.minimum(res.history, prior).tolist())
        return
    if prefer == "nearest":
        pol_sec = pol.with_posture(seed)  # nearest to q0: a secondary posture at q0
    else:
        pol_sec = pol
    # "nearest" mode and problems with secondary goals: once a first solution is found,
    # polish more starts around the seed, keep the converged one with the lowest secondary
    # cost, then lower it further in the primary null space
    nearest = prefer == "nearest" or problem.has_secondary
    m = int(pop_size)
    n_swarm = int(round(swarm_fraction * m))
    unlimited = ev.max_evals is None and ev.time_limit is None
    arch_x = np.empty((0, ev.dim))
    arch_f = np.empty(0)
    sol_x: list[FloatArray] = []  # converged points ("nearest" mode)
    # lowest fitness seen and not yet offered to ev: offered at the end of each generation
    # (one stop-criterion check per generation instead of one per compiled call); a
    # converged point is offered at once.  In "nearest" mode it is the fallback answer.
    best_x, best_f = seed, np.inf
    # generation 0: the seed first; the other pop_size - 1 (uniform) only if it fails
    queue = seed[None]
    gen0_rest = m > 1
    from swarm_ik.urdf import sampling_bounds

    s_lo, s_hi = sampling_bounds(ev.lower, ev.upper, seed)  # huge ranges: a window
    lo, width = s_lo, s_hi - s_lo
    near_done = False
    open_gen = False
    sec_per_eval = 5e-6
    exact_check = problem.collision_goal is not None and ev.stops_on_success
    # the numpy polish of Python goals (milliseconds an evaluation) reads the clock itself
    deadline = None if ev.time_limit is None else ev.t0 + ev.time_limit
    pol_free = None
    if exact_check:
        free = problem.without_collisions()
        if free is not None:
            pol_free = polisher(free)
    t = 0
    while not ev.done and (not unlimited or t < iterations):
        cap = ev.remaining
        if ev.time_limit is not None:
            left = ev.time_limit - ev.elapsed
            cap = min(cap, max(8, int(0.8 * left / sec_per_eval)))
        if pol_free is not None and queue.shape[0]:
            # collision goal: polish the starts for the other goals alone and let coal judge
            # the converged ones; those in contact continue below with the sphere rows, from
            # where they reached the goals
            pre = pol_free.polish(queue, cap, stop_first=False, deadline=deadline)
            ev.add_evals(pre.used)
            conv = pre.status == CONVERGED
            for row in np.flatnonzero(conv).tolist():
                fk = problem.candidate_cost(pre.q[row], pol.kernel_tol_pos, pol.kernel_tol_rot)
                if fk is not None:
                    best_x, best_f = pre.q[row].copy(), fk
                    ev.add_evals(0, best_x, best_f)
                    break
            if ev.done:
                break
            queue = np.where(conv[:, None], pre.q, queue)
            cap = ev.remaining
            if ev.time_limit is not None:
                left = ev.time_limit - ev.elapsed
                cap = min(cap, max(8, int(0.8 * left / sec_per_eval)))
        t1 = time.perf_counter()
        out = pol.polish(queue, cap, stop_first=not (nearest and sol_x), deadline=deadline)
        if out.used > 0:
            sec_per_eval = 0.5 * sec_per_eval + 0.5 * (time.perf_counter() - t1) / out.used
        open_gen = True
        # the kernel runs the starts in order: the rows it reached are a prefix, and only the
        # last of them can have been cut by the budget
        st = out.status
        r = int(np.count_nonzero(st))
        qs = out.q[:r]
        fi = np.inf
        i = 0
        if r:
            f = fitness_of(qs, out.position_error[:r], out.rotation_error[:r])
            i = int(np.argmin(f))
            fi = float(f[i])
        ev.add_evals(out.used)
        if fi < best_f:
            best_x, best_f = qs[i].copy(), fi
        if exact_check and r:  # starts the spheres reject may still be free: ask coal
            for row in np.flatnonzero(st[:r] != CONVERGED).tolist():
                fk = problem.candidate_cost(qs[row], pol.kernel_tol_pos, pol.kernel_tol_rot)
                if fk is not None:
                    best_x, best_f = qs[row].copy(), fk
                    ev.add_evals(0, best_x, best_f)
                    break
            if ev.done:
                break
        if nearest:
            sol_x.extend(qs[st[:r] == CONVERGED])
        elif r and st[r - 1] == CONVERGED:  # stop_first: a converged start ends the call
            ev.add_evals(0, qs[r - 1], float(f[r - 1]))
            if ev.done:
                break
        cut = r > 0 and st[r - 1] == BUDGET
        n_done = r - 1 if cut else r
        failed = st[:n_done] != CONVERGED
        if failed.any():  # archive of polished local minima, best first, pop_size kept
            arch_x = np.concatenate([arch_x, qs[:n_done][failed]])
            arch_f = np.concatenate(
                [arch_f, out.position_error[:n_done][failed] + out.rotation_error[:n_done][failed]]
            )
            order = np.argsort(arch_f, kind="stable")[:m]
            arch_x, arch_f = arch_x[order], arch_f[order]
        # unfinished rows (cut by the budget, or not reached) stay queued, partially polished
        queue = out.q[n_done:]
        if nearest and sol_x and not near_done:
            near_done = True
            # spreads from nearest_sigma to 4 × nearest_sigma of the ranges, nearest first
            spread = nearest_sigma * np.geomspace(1.0, 4.0, nearest_starts)[:, None]
            noise = rng.standard_normal((nearest_starts, ev.dim)) * spread
            around = ev.clip(seed + noise * (ev.upper - ev.lower))
            queue = np.concatenate([queue, around])
        if nearest and near_done and queue.shape[0] == 0:
            break
        if queue.shape[0] == 0 and gen0_rest:
            gen0_rest = False
            queue = lo + width * rng.random((m - 1, ev.dim))  # uniform within the bounds
        elif queue.shape[0] == 0:
            if not nearest:
                if np.isfinite(best_f):
                    ev.add_evals(0, best_x, best_f)
                ev.end_iteration()
                open_gen = False
            t += 1
            frac = t / max(iterations, 1)
            if ev.max_evals is not None:
                frac = max(frac, ev.n_evals / ev.max_evals)
            # (elapsed time is deliberately not used: proposals must not depend on the
            # machine's speed, so a run that the time limit does not cut is reproducible)
            a = 2.0 * max(0.0, 1.0 - frac)
            queue = propose(ev, rng, arch_x, arch_f, n_swarm, m, a, (s_lo, s_hi))
    if nearest:
        if sol_x:
            sols = np.asarray(sol_x)
            if prefer == "nearest":
                sols = _nearest_copies(problem, sols, ev.lower, ev.upper, seed)
            k = int(np.argmin(pol_sec.secondary_cost(sols)))
            q_best = sols[k]
            if ev.remaining > 0:
                q_best, used = pol_sec.secondary(q_best, min(ev.remaining, 200), deadline)
                ev.add_evals(used)
            _r, _j, dp, dr = pol.residual(q_best)
            best_x = q_best
            best_f = float(fitness_of(q_best[None], np.array([dp]), np.array([dr]))[0])
        ev.add_evals(0, best_x, best_f)
        ev.end_iteration()
    else:
        if np.isfinite(best_f):
            ev.add_evals(0, best_x, best_f)
        if open_gen or not ev.history:
            ev.end_iteration()


def _nearest_copies(
    problem: IKProblem, sols: FloatArray, lower: FloatArray, upper: FloatArray, q0: FloatArray
) -> FloatArray:
    """Each solution ``(k, nq)`` as its 2π copy within the bounds nearest to ``q0`` (a joint
    whose range is 2π or more may turn either way to the same pose), where the copy meets the
    problem as well as the solution does: a goal on joint values (``JointValue``, a primary
    ``Posture``) tells the copies apart, and then the solution stays as it is."""
    periodic = periodic_mask(problem.robot, lower, upper)
    copies = nearest_winding(sols, lower, upper, periodic, q0)[0]
    same = problem.fitness(copies) <= problem.fitness(sols) + SAME_POSE_FITNESS
    return np.where(same[:, None], copies, sols)


SAME_POSE_FITNESS = 1e-9
"""Fitness by which a 2π copy of a solution may exceed it and still count as meeting the
problem as well (round-off of the FK of angles 2π apart is about 1e-15)."""


register(
    "swarm",
    run,
    description="default: memetic swarm (grey wolf proposals) + compiled bounded "
    "Levenberg-Marquardt polish; exact, within limits, fast",
    needs_jacobian=True,
    budget_only=True,
    constraints={
        "swarm_fraction": "[0, 1]",
        "max_iters": "int>=2",
        "lam0": "(0, 1e12]",
        "max_step": "positive",
        "stall_rel": "[0, 1]",
        "stall_iters": "int>=1",
        "tol_margin": "(0, 1]",
        "prefer": "choice:best|nearest",
        "nearest_starts": "int>=0",
        "nearest_sigma": "nonnegative",
    },
)
