"""``solve_many``: every distinct IK branch of one target, each once.

A 6-joint arm reaches a generic pose in up to 8 (wrist, elbow, shoulder) configurations; a
joint with a range beyond 2π repeats each of them every 2π, and a 7-joint arm reaches it along
one-dimensional self-motion manifolds.  :func:`solve_many` returns

* for a non-redundant chain: each **branch** once (distinct modulo 2π on the periodic joints,
  see :mod:`swarm_ik.branches`), as its in-limit copy nearest to ``q0`` (else to the middle of
  the ranges); ``windings=True`` adds the other in-limit 2π copies of each branch;
* for a redundant chain (more joints than pose constraints): ``n`` solutions spread over the
  self-motion manifolds by farthest-point selection in joint space.

Two paths: ``method="analytic"`` uses eaik (:mod:`swarm_ik.solvers.analytic`) on the 6R
chains it decomposes (UR, z1, spherical wrists), ``method="numerical"`` polishes starts with
the compiled Levenberg–Marquardt kernel of ``swarm``, ``"auto"`` (default) takes the analytic
path when it applies and eaik is installed, else the numerical one.

>>> import swarm_ik
>>> robot = swarm_ik.load_robot("yumi_left")
>>> problem = swarm_ik.IKProblem.from_q(robot, [0.1, -0.5, 0.2, 0.3, -0.2, 0.4, 0.1])
>>> sols = swarm_ik.solve_many(problem, n=4, seed=0)
>>> len(sols), all(s.success for s in sols)
(4, True)
"""

from __future__ import annotations

import time
import weakref
from typing import Any

import numpy as np
import pinocchio as pin

from swarm_ik.api import prepare_q0, verify
from swarm_ik.branches import (
    BRANCH_TOL,
    ROUNDOFF_TOL,
    TWO_PI,
    BranchSet,
    branch_distance,
    periodic_mask,
    refine,
    revolute_mask,
    spread_select,
)
from swarm_ik.branches import (
    windings as _windings,
)
from swarm_ik.errors import InvalidArgumentError, unknown
from swarm_ik.optimize import check_budget, make_rng
from swarm_ik.problem import IKProblem
from swarm_ik.result import Result
from swarm_ik.solvers import analytic
from swarm_ik.solvers.hybrid import Polisher

SOLVER_NAME = "swarm"
"""Solver name recorded in the numerical path's results (its polish is ``swarm``'s)."""
METHODS = ("auto", "numerical", "analytic")
"""Values of ``solve_many(method=...)``."""
PATIENCE = 48
"""Default ``patience``: random starts in a row without a new branch that end the search."""
POOL_FACTOR = 4
"""A redundant arm's search collects ``POOL_FACTOR · n`` distinct solutions, then spreads."""
_HOP_SKIP = 0.05
"""A hop start within this wrapped distance (rad) of a known branch is not polished."""

FloatArray = np.ndarray


# ------------------------------------------------------------------------ branch hops
class _Hops:
    """Starts that map one branch of a 6R-like chain onto its neighbours.

    * **elbow mirror** (exact) for three consecutive parallel axes ``j, j+1, j+2``: the middle
      joint's origin is reflected across the line through the outer two, the first two joints
      turn to follow it and the third keeps the distal orientation;
    * **wrist flip** ``(q_j + π, −q_{j+1}, q_{j+2} + π)`` (exact for a spherical wrist with
      perpendicular axes, a good start otherwise);
    * **shoulder flip** ``(q_j + π, π − q_{j+1}, −q_{j+2}, π − q_{j+3})`` (a start);
    * each joint turned by π.

    The polish then lands on the neighbouring branch (or back on a known one).
    """

    def __init__(self, robot: Any) -> None:
        self.robot = robot
        model = robot.model
        self.data = model.createData()
        q_pin = robot.to_pinocchio(np.zeros(robot.nq))
        jac = np.asarray(pin.computeJointJacobians(model, self.data, q_pin)).reshape(6, model.nv)
        axes = jac[3:].T
        self.local = [np.array(self.data.oMi[j + 1].rotation).T @ axes[j] for j in range(robot.nq)]
        self.revolute = revolute_mask(robot)
        n = robot.nq
        self.parallel: list[tuple[int, tuple[float, float, float]]] = []
        for j in range(n - 2):
            if not self.revolute[j : j + 3].all():
                continue
            h = axes[j]
            if all(np.linalg.norm(np.cross(h, axes[k])) < 1e-9 for k in (j + 1, j + 2)):
                signs = tuple(float(np.sign(h @ axes[k])) for k in (j, j + 1, j + 2))
                self.parallel.append((j, signs))  # type: ignore[arg-type]

    def elbow(self, q: FloatArray) -> list[FloatArray]:
        """Exact elbow mirrors of ``q`` (one per parallel triple)."""
        if not self.parallel:
            return []
        pin.forwardKinematics(self.robot.model, self.data, self.robot.to_pinocchio(q))
        out = []
        for j, (s0, s1, s2) in self.parallel:
            frames = self.data.oMi
            h = np.array(frames[j + 1].rotation) @ self.local[j]
            a = np.array(frames[j + 1].translation)
            ab = np.array(frames[j + 2].translation) - a
            ac = np.array(frames[j + 3].translation) - a
            ab -= (ab @ h) * h
            ac -= (ac @ h) * h
            norm = np.linalg.norm(ac)
            if norm < 1e-12:
                continue
            u = ac / norm
            ab_m = 2.0 * (ab @ u) * u - ab
            phi1 = np.arctan2(h @ np.cross(ab, ab_m), ab @ ab_m)
            bc = ac - ab
            c, s = np.cos(phi1), np.sin(phi1)
            bc_rot = bc * c + np.cross(h, bc) * s + h * (h @ bc) * (1.0 - c)
            want = ac - ab_m
            phi2 = np.arctan2(h @ np.cross(bc_rot, want), bc_rot @ want)
            hop = q.copy()
            hop[j] += s0 * phi1
            hop[j + 1] += s1 * phi2
            hop[j + 2] -= s2 * (phi1 + phi2)
            out.append(hop)
        return out

    def __call__(self, q: FloatArray) -> list[FloatArray]:
        n = q.shape[0]
        rev = self.revolute
        out = self.elbow(q)
        for j in range(n - 2):
            if rev[j : j + 3].all():
                a = q.copy()
                a[j] += np.pi
                a[j + 1] = -a[j + 1]
                a[j + 2] += np.pi
                out.append(a)
        for j in range(n - 3):
            if rev[j : j + 4].all():
                a = q.copy()
                a[j] += np.pi
                a[j + 1] = np.pi - a[j + 1]
                a[j + 2] = -a[j + 2]
                a[j + 3] = np.pi - a[j + 3]
                out.append(a)
        for j in map(int, np.flatnonzero(rev)):
            a = q.copy()
            a[j] += np.pi
            out.append(a)
        return out


_HOPS: weakref.WeakKeyDictionary[Any, _Hops] = weakref.WeakKeyDictionary()


def _hops_for(robot: Any) -> _Hops:
    h = _HOPS.get(robot)
    if h is None:
        h = _HOPS[robot] = _Hops(robot)
    return h


# ------------------------------------------------------------------------------ API
def solve_many(
    problem: IKProblem,
    n: int = 16,
    *,
    method: str = "auto",
    windings: bool = False,
    min_distance: float | None = None,
    seed: int | np.random.Generator | None = 0,
    max_evals: int | None = None,
    time_limit: float | None = None,
    q0: Any = None,
    tol_pos: float = 1e-5,
    tol_rot: float = 1e-5,
    batch: int = 16,
    max_starts: int | None = None,
    max_iters: int = 30,
    patience: int = PATIENCE,
) -> list[Result] | list[list[Result]]:
    """Find the distinct IK solutions of a target: every branch once, or a spread for
    redundant arms.

    **Branches.** Two solutions, polished to round-off (pose error ≤ 1e-12), are one branch
    when their joint distance modulo 2π on the periodic joints (continuous ones and revolute
    ones with a range ≥ 2π) is below :data:`swarm_ik.branches.BRANCH_TOL` (1e-6 rad).  Each
    branch is returned once, as its in-limit copy nearest to ``q0`` (else to the middle of the
    ranges).  ``min_distance`` (optional) additionally drops a solution closer than that to a
    kept one.

    **Numerical path.** Batches of ``batch`` starts (``q0`` or the middle of the ranges first)
    are polished by the compiled Levenberg–Marquardt kernel of ``swarm`` at round-off
    tolerance; a start within ``tol_pos``/``tol_rot`` that stopped short of round-off is
    finished by Gauss–Newton on Pinocchio.  Each new branch is verified with Pinocchio's FK at
    once (so ``time_limit`` covers the verification) and queues *hop* starts towards its
    neighbours (exact elbow mirror over three parallel axes, wrist and shoulder flips, each
    joint turned by π), which are polished before new random starts.  The search stops at
    ``n`` branches, or when every hop start is spent and ``patience`` random starts in a row
    gave no new branch, or at the budget (``max_starts``, ``max_evals``, ``time_limit``).

    **Redundant arms** (more joints than constrained pose coordinates: 7-joint arms, or a
    position-only problem with more than 3 joints): random starts are polished until
    ``4 · n`` distinct solutions (:data:`POOL_FACTOR`) are pooled or the budget ends, then ``n``
    are picked by farthest-point selection in wrapped joint space, starting from the one
    nearest to ``q0`` / mid-range (:func:`swarm_ik.branches.spread_select`).

    **Analytic path.** eaik's closed form (:func:`swarm_ik.solvers.analytic.solve_all`): the
    complete set at once, verified with Pinocchio.

    Args:
        problem: The IK problem.
        n: Most solutions (branches) returned, ``>= 1``.
        method: ``"auto"`` (analytic when eaik is installed and decomposes the chain, else
            numerical), ``"numerical"`` or ``"analytic"`` (refused with the reason when it does
            not apply).
        windings: Also return the other in-limit 2π copies of each branch: the result is then
            a list of branches, each a list of :class:`Result` (the representative first, then
            the copies by distance to the reference).
        min_distance: Optional coarser filter (rad / m, ``> 0``): drop a solution closer than
            this to a kept one.  Default ``None``: branches only.
        seed: Seed or Generator for the random starts.
        max_evals: Most FK + Jacobian evaluations in total (numerical path).
        time_limit: Most wall-clock seconds, verification included (numerical path).
        q0: Optional reference and first start, shape ``(nq,)`` (clipped into the limits with a
            warning).
        tol_pos: Position tolerance [m] of every solution.
        tol_rot: Rotation tolerance [rad] of every solution.
        batch: Starts polished per compiled call.
        max_starts: Most starts; default ``64 · n`` when neither ``max_evals`` nor
            ``time_limit`` is given, else unlimited.
        max_iters: Evaluations per start before it is abandoned.
        patience: Random starts in a row without a new branch that end the search
            (default :data:`PATIENCE` = 48; on UR5/UR10/z1 this gives 100 % recall of eaik's
            sets in the benchmark ``swarm-ik bench many``).

    Returns:
        The solutions, nearest to the reference first, each verified with Pinocchio's FK
        (``success`` True).  ``n_evals`` and ``time_s`` are the totals spent when each was found
        (0 evaluations on the analytic path).  ``solver`` is ``"swarm"`` (numerical) or
        ``"analytic"``.  Empty when nothing was found.  With ``windings=True``, a list of lists.

    Raises:
        InvalidArgumentError: ``n``, ``min_distance``, ``batch``, ``patience``, a tolerance or
            the budget is out of range, or ``problem`` is not an :class:`IKProblem`.
        UnknownNameError: ``method`` is not one of :data:`METHODS`.
        swarm_ik.solvers.analytic.AnalyticUnavailableError: ``method="analytic"`` without eaik.
        swarm_ik.solvers.analytic.AnalyticUnsupportedError: ``method="analytic"`` on a chain
            or problem eaik cannot solve.
    """
    if not isinstance(problem, IKProblem):
        raise InvalidArgumentError(f"problem must be an IKProblem, got {type(problem).__name__}")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise InvalidArgumentError(f"n must be a positive integer, got {n!r}")
    if method not in METHODS:
        raise unknown("method", method, METHODS)
    if min_distance is not None and not (np.isfinite(min_distance) and min_distance > 0):
        raise InvalidArgumentError(
            f"min_distance must be a positive number or None, got {min_distance!r}"
        )
    if batch < 1 or max_iters < 2 or (max_starts is not None and max_starts < 1) or patience < 1:
        raise InvalidArgumentError(
            f"need batch >= 1, max_iters >= 2, max_starts >= 1 and patience >= 1; got "
            f"batch={batch}, max_iters={max_iters}, max_starts={max_starts}, patience={patience}"
        )
    for label, tol in (("tol_pos", tol_pos), ("tol_rot", tol_rot)):
        if not (np.isfinite(tol) and tol > 0):
            raise InvalidArgumentError(f"{label} must be a positive number, got {tol!r}")
    check_budget(max_evals, time_limit)
    rng = make_rng(seed)
    start_q = prepare_q0(problem, q0)
    ref = start_q if start_q is not None else 0.5 * (problem.lower + problem.upper)
    seed_label = (
        None if isinstance(seed, np.random.Generator) else (0 if seed is None else int(seed))
    )

    use_analytic = False
    if method == "analytic":
        reason = analytic.support(problem)  # raises AnalyticUnavailableError without eaik
        if reason:
            raise analytic.AnalyticUnsupportedError(f"method='analytic' refused: {reason}")
        use_analytic = True
    elif method == "auto" and analytic.eaik_available():
        use_analytic = not analytic.support(problem)

    t0 = time.perf_counter()
    if use_analytic:
        qs, _dps, _drs = analytic.solve_all(problem, ref=ref, tol_pos=tol_pos, tol_rot=tol_rot)
        found = BranchSet(
            periodic_mask(problem.robot, problem.lower, problem.upper), BRANCH_TOL, min_distance
        )
        keep = [i for i in range(qs.shape[0]) if found.add(qs[i])][:n]
        elapsed = time.perf_counter() - t0
        # the errors reported exactly as swarm_ik.verify computes them
        reps = [(qs[i], *verify(problem, qs[i]), 0, elapsed) for i in keep]
        solver = "analytic"
    else:
        reps = _numerical(
            problem, int(n), ref, start_q, rng, min_distance, max_evals, time_limit,
            tol_pos, tol_rot, batch, max_starts, max_iters, patience, t0,
        )  # fmt: skip
        solver = SOLVER_NAME
    qs_all = np.array([r[0] for r in reps]).reshape(-1, problem.nq)
    fits = problem.fitness(qs_all) if reps else np.empty(0)
    order = np.argsort(
        branch_distance(qs_all, ref, periodic_mask(problem.robot, problem.lower, problem.upper)),
        kind="stable",
    )
    results = [
        _result(
            reps[i][0],
            reps[i][1],
            reps[i][2],
            reps[i][3],
            reps[i][4],
            float(fits[i]),
            solver,
            seed_label,
        )
        for i in order
    ]
    if not windings:
        return results
    return [_with_windings(problem, r, ref) for r in results]


# -------------------------------------------------------------------------- helpers
def _result(
    q: FloatArray,
    dp: float,
    dr: float,
    n_evals: int,
    t_found: float,
    fit: float,
    solver: str,
    seed: int | None,
) -> Result:
    return Result(
        q=np.array(q, dtype=float),
        fitness=fit,
        position_error=float(dp),
        rotation_error=float(dr),
        n_evals=int(n_evals),
        time_s=float(t_found),
        success=True,
        within_limits=True,
        history=np.array([fit]),
        solver=solver,
        seed=seed,
    )


def _with_windings(problem: IKProblem, rep: Result, ref: FloatArray) -> list[Result]:
    """The representative and its other in-limit 2π copies, each verified with Pinocchio."""
    copies = _windings(rep.q, problem.lower, problem.upper, revolute_mask(problem.robot))
    if copies.shape[0] == 0:
        return [rep]
    periodic = np.zeros(problem.nq, dtype=bool)  # order by the plain distance to the reference
    copies = copies[np.argsort(branch_distance(copies, ref, periodic))]
    others = copies[branch_distance(copies, rep.q, periodic) > 1e-9]
    if others.shape[0] == 0:
        return [rep]
    errs = [verify(problem, q) for q in others]
    fits = problem.fitness(others)
    out = [rep]
    for q, (a, b), f in zip(others, errs, fits, strict=True):
        out.append(_result(q, a, b, rep.n_evals, rep.time_s, float(f), rep.solver, rep.seed))
    return out


def _redundant(problem: IKProblem) -> bool:
    task = 3 if problem.position_only else 6
    return problem.nq > task


class _Folder:
    """Vectorised :func:`~swarm_ik.branches.nearest_winding` for one problem and reference,
    and the wrapped distance to the branches kept so far."""

    def __init__(self, lower: FloatArray, upper: FloatArray, revolute: Any, periodic: Any,
                 ref: FloatArray) -> None:  # fmt: skip
        self.lo, self.hi = lower, upper
        self.lo_s, self.hi_s = lower - 1e-9, upper + 1e-9
        self.rev = revolute.astype(float)
        self.periodic = periodic
        self.ref = ref
        self.kept = np.empty((0, lower.shape[0]))

    def __call__(self, qs: FloatArray) -> tuple[FloatArray, Any]:
        inv = 1.0 / TWO_PI
        m_min = np.ceil((self.lo_s - qs) * inv)
        m_max = np.floor((self.hi_s - qs) * inv)
        m = np.minimum(np.maximum(np.rint((self.ref - qs) * inv), m_min), m_max) * self.rev
        out = np.minimum(np.maximum(qs + TWO_PI * m, self.lo), self.hi)
        ok = np.all((m_min <= m_max) | (self.rev == 0.0), axis=-1)
        return out, ok

    def dist(self, qs: FloatArray) -> FloatArray:
        """Wrapped distance of each row of ``qs`` ``(m, nq)`` to its nearest kept branch."""
        if self.kept.shape[0] == 0:
            return np.full(qs.shape[0], np.inf)
        d = qs[:, None, :] - self.kept[None, :, :]
        p = self.periodic
        if p.any():
            d[..., p] = (d[..., p] + np.pi) % TWO_PI - np.pi
        return np.sqrt(np.min(np.einsum("mki,mki->mk", d, d), axis=1))


def _numerical(
    problem: IKProblem,
    n: int,
    ref: FloatArray,
    start_q: FloatArray | None,
    rng: np.random.Generator,
    min_distance: float | None,
    max_evals: int | None,
    time_limit: float | None,
    tol_pos: float,
    tol_rot: float,
    batch: int,
    max_starts: int | None,
    max_iters: int,
    patience: int,
    t0: float,
) -> list[tuple[FloatArray, float, float, int, float]]:
    """The numerical search; returns ``(q, dp, dr, evals when found, seconds when found)``."""
    robot = problem.robot
    nq = robot.nq
    lower, upper = problem.lower, problem.upper
    periodic = periodic_mask(robot, lower, upper)
    revolute = revolute_mask(robot)
    redundant = _redundant(problem)
    target_count = POOL_FACTOR * n if redundant else n
    if max_starts is None and max_evals is None and time_limit is None:
        max_starts = 64 * n
    pol = Polisher.from_problem(
        problem, lower, upper, tol_pos=ROUNDOFF_TOL, tol_rot=ROUNDOFF_TOL,
        wrap=robot.continuous_mask, max_iters=max_iters,
    )  # fmt: skip
    hops = None if redundant else _hops_for(robot)
    fold = _Folder(lower, upper, revolute, periodic, ref)
    merge = BRANCH_TOL if min_distance is None else max(BRANCH_TOL, float(min_distance))
    kept: list[tuple[FloatArray, float, float, int, float]] = []
    queue = np.empty((0, nq))
    first = start_q if start_q is not None else 0.5 * (lower + upper)
    used = 0
    n_starts = 0
    since_new = 0
    sec_per_eval = 5e-6
    while len(kept) < target_count:
        if max_evals is not None and used >= max_evals:
            break
        if time_limit is not None and time.perf_counter() - t0 >= time_limit:
            break
        if max_starts is not None and n_starts >= max_starts:
            break
        if kept and queue.shape[0] == 0 and since_new >= patience:
            break
        k = batch if max_starts is None else min(batch, max_starts - n_starts)
        starts = np.empty((k, nq))
        n_hop = 0
        while queue.shape[0] and n_hop < k:  # hop starts not yet next to a known branch
            take, queue = queue[: k - n_hop], queue[k - n_hop :]
            take = take[fold.dist(take) >= _HOP_SKIP]
            starts[n_hop : n_hop + take.shape[0]] = take
            n_hop += take.shape[0]
        starts[n_hop:] = rng.uniform(lower, upper, size=(k - n_hop, nq))
        if n_starts == 0:
            starts[0] = first
            n_hop = max(n_hop, 1)  # the first start is not a random one
        cap = 2**62 if max_evals is None else max_evals - used
        if time_limit is not None:  # keep each compiled call within the time left
            left = time_limit - (time.perf_counter() - t0)
            cap = min(cap, max(8, int(0.8 * left / sec_per_eval)))
        t1 = time.perf_counter()
        out = pol.polish(starts, cap, stop_first=False)
        if out.used > 0:
            sec_per_eval = 0.5 * sec_per_eval + 0.5 * (time.perf_counter() - t1) / out.used
        used += out.used
        ran = int(np.count_nonzero(out.status))
        n_starts += ran
        good = (out.position_error[:ran] <= tol_pos) & (out.rotation_error[:ran] <= tol_rot)
        deadline = None if time_limit is None else t0 + time_limit
        for i in range(ran):
            if i >= n_hop:
                since_new += 1
            if not good[i]:
                continue
            if deadline is not None and time.perf_counter() >= deadline:
                break  # verification counts against the time limit too
            q = out.q[i]
            if out.position_error[i] > ROUNDOFF_TOL or out.rotation_error[i] > ROUNDOFF_TOL:
                q = refine(problem, q)[0]  # near a singularity the damped polish crawls
            q = fold(q[None])[0][0]
            if fold.dist(q[None])[0] < merge:
                continue
            dp, dr = verify(problem, q)  # Pinocchio's FK, as swarm_ik.verify reports it
            if not (dp <= tol_pos and (problem.position_only or dr <= tol_rot)):
                continue  # the kernel's check disagrees with Pinocchio's: never report it
            since_new = 0
            fold.kept = np.vstack([fold.kept, q])
            kept.append((q, dp, dr, used, time.perf_counter() - t0))
            if hops is not None:
                cand, ok = fold(np.asarray(hops(q)).reshape(-1, nq))
                cand = cand[ok]
                queue = np.vstack([queue, cand[fold.dist(cand) >= _HOP_SKIP]])
            if len(kept) >= target_count:
                break
    if not redundant:
        return kept
    picks = spread_select(np.array([k[0] for k in kept]).reshape(-1, nq), n, periodic, ref)
    return [kept[i] for i in picks]
