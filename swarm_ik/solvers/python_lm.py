"""The Levenberg–Marquardt polish in numpy, for problems with goals written in Python.

:class:`PythonPolisher` has the interface of :class:`swarm_ik.solvers.hybrid.Polisher` and
the rules of :func:`swarm_ik.kernels.lm.lm_run` (the damped normal equations over the free
joints, joints at a limit whose step points outwards frozen, steps clipped to ``max_step``,
accept/reject with the damping ×0.1/×10, a local minimum after ``stall_iters`` steps that
lower the cost by less than ``stall_rel``), on the problem's stacked residual
(:meth:`swarm_ik.problem.IKProblem.residual_jacobian`: compiled goals through the kernels,
Python goals on Pinocchio's state).  Slower than the compiled polish, equally exact: success
is judged by the same errors (:meth:`IKProblem.goal_errors`).

A Python goal may take milliseconds a call, so the polish also reads the clock: given a
``deadline`` it starts no evaluation after it (the start it was polishing ends ``BUDGET``, as
when the evaluations run out), and each point's rows and errors come from one evaluation of
the goals (:func:`swarm_ik.goals.base.reuse_goal_values`).
"""

from __future__ import annotations

import time
from typing import Any, NamedTuple

import numpy as np

from swarm_ik._types import FloatArray, IntArray
from swarm_ik.goals.base import reuse_goal_values
from swarm_ik.kernels import lm
from swarm_ik.kernels.lm import BUDGET, CONVERGED, ITER_CAP, LOCAL_MIN, NOT_RUN, LMSettings
from swarm_ik.problem import IKProblem, pushed_out


class PolishOutcome(NamedTuple):
    """What one call of a polish returns (the compiled one and this one).

    Attributes:
        q: Polished points, shape ``(k, nq)`` (the start where not run).
        position_error: Largest primary position error [m], ``(k,)`` (``inf`` where not run).
        rotation_error: Largest primary angular error [rad], ``(k,)`` (``inf`` where not run).
        status: ``NOT_RUN``, ``CONVERGED``, ``LOCAL_MIN``, ``ITER_CAP`` or ``BUDGET``, ``(k,)``.
        evals: Evaluations per start, ``(k,)``.
        used: Evaluations of the call in total.
    """

    q: FloatArray
    position_error: FloatArray
    rotation_error: FloatArray
    status: IntArray
    evals: IntArray
    used: int


class PythonPolisher(NamedTuple):
    """The LM polish of a problem with Python goals (see the module docstring).

    Attributes:
        problem: The problem.
        bounds: Search bounds.
        cfg: LM settings.
        kernel_tol_pos: Position tolerance the polish stops at [m].
        kernel_tol_rot: Angular tolerance the polish stops at [rad].
        q0: The solve's start (what ``MinimalDisplacement`` goals hold to), or None.
    """

    problem: IKProblem
    bounds: lm.Bounds
    cfg: LMSettings
    kernel_tol_pos: float
    kernel_tol_rot: float
    q0: FloatArray | None = None

    @property
    def wrap(self) -> Any:
        """Continuous-joint mask, ``(nq,)``."""
        return self.bounds.wrap

    def _within(self, err: FloatArray) -> bool:
        """Every primary goal within the polish tolerances; a Python goal with its own
        ``tolerance`` within it (its errors here are the judge's, on Pinocchio's state: no
        margin is needed, and its rows vanish within :data:`~swarm_ik.goals.base.SLACK_SHARE`
        of it, so the polish must stop beyond that)."""
        for gl, e, prim in zip(self.problem.goals, err, self.problem.primary, strict=True):
            if not prim:
                continue
            own = gl.own_tolerance()
            tp = self.kernel_tol_pos if own is None else own
            if e[0] > tp or e[1] > self.kernel_tol_rot or (np.isnan(e[0]) and np.isnan(e[1])):
                return False
        return True

    def _errors(self, q: FloatArray) -> tuple[FloatArray, float, float]:
        err = self.problem.goal_errors(q[None], self.q0)[0]
        e = np.where(np.isnan(err), 0.0, err)[self.problem.primary]
        return err, float(e[:, 0].max(initial=0.0)), float(e[:, 1].max(initial=0.0))

    def _into_bounds(self, q: FloatArray) -> FloatArray:
        q = q.copy()
        w = self.bounds.wrap
        q[w] = (q[w] + np.pi) % (2 * np.pi) - np.pi
        return np.clip(q, self.bounds.lower, self.bounds.upper)

    def _rj(self, q: FloatArray, primary: bool = True) -> tuple[FloatArray, FloatArray]:
        r, j = self.problem.stacked_rows(q[None], primary, self.q0)
        return r[0], j[0]

    def polish(
        self,
        starts: FloatArray,
        max_evals: int,
        stop_first: bool = True,
        deadline: float | None = None,
    ) -> Any:
        """Polish ``starts`` ``(k, nq)`` with at most ``max_evals`` evaluations (the
        :class:`swarm_ik.solvers.hybrid.PolishOutcome` of the compiled polish), starting none
        after ``deadline`` (``time.perf_counter()`` seconds; None: no deadline)."""
        with reuse_goal_values():
            return self._polish(starts, max_evals, stop_first, deadline)

    def _polish(
        self, starts: FloatArray, max_evals: int, stop_first: bool, deadline: float | None
    ) -> Any:
        starts = np.atleast_2d(np.asarray(starts, dtype=float))
        k, n = starts.shape
        out_q = starts.copy()
        dp = np.full(k, np.inf)
        dr = np.full(k, np.inf)
        status = np.full(k, NOT_RUN, dtype=np.int64)
        evals = np.zeros(k, dtype=np.int64)
        cfg, b = self.cfg, self.bounds
        used = 0
        late = _clock(deadline)
        for s in range(k):
            if used >= max_evals or late():
                break
            q = starts[s].copy()
            r, jac = self._rj(q)
            err, e_p, e_r = self._errors(q)
            cost = float(r @ r)
            used += 1
            ev = 1
            lam, stall, st = cfg.lam0, 0, ITER_CAP
            while True:
                if self._within(err):
                    st = CONVERGED
                    break
                if ev >= cfg.max_iters:
                    st = ITER_CAP
                    break
                if used >= max_evals or late():
                    st = BUDGET
                    break
                a = jac.T @ jac
                g = jac.T @ r
                scale = np.trace(a) / n + 1e-300
                free = ~pushed_out(q, g, b)
                if not free.any():
                    st = LOCAL_MIN
                    break
                af = a[np.ix_(free, free)] + lam * scale * np.eye(int(free.sum()))
                try:
                    step = np.linalg.solve(af, g[free])
                except np.linalg.LinAlgError:
                    lam *= 10.0
                    if lam > 1e12:
                        st = LOCAL_MIN
                        break
                    continue
                delta = np.zeros(n)
                delta[free] = step
                big = float(np.abs(delta).max())
                if big > cfg.max_step:
                    delta *= cfg.max_step / big
                q_t = self._into_bounds(q + delta)
                r_t, jac_t = self._rj(q_t)
                used += 1
                ev += 1
                cost_t = float(r_t @ r_t)
                accepted = cost_t < cost
                lam, stall, stuck = lm.damping(accepted, cost_t, cost, lam, stall, cfg)
                if accepted:
                    q, r, jac, cost = q_t, r_t, jac_t, cost_t
                    err, e_p, e_r = self._errors(q)
                    if stall >= cfg.stall_iters and not self._within(err):
                        st = LOCAL_MIN
                        break
                elif stuck:
                    st = LOCAL_MIN
                    break
            out_q[s], dp[s], dr[s], status[s], evals[s] = q, e_p, e_r, st, ev
            if stop_first and st == CONVERGED:
                break
        return PolishOutcome(out_q, dp, dr, status, evals, int(used))

    def secondary(
        self, q: FloatArray, max_evals: int, deadline: float | None = None
    ) -> tuple[FloatArray, int]:
        """Lower the secondary goals' cost in the null space of the primary ones: the rules of
        :func:`swarm_ik.kernels.lm.secondary_descent` in numpy (``δ = J₁⁺ r₁ + N z``,
        ``N = I − J₁⁺J₁``, ``(NᵀJ₂ᵀJ₂N + μ·tr/n·I) z = NᵀJ₂ᵀ r₂``, a joint at a limit that the
        step pushes outwards held, :func:`_null_space_step`; the step cut to the trust
        radius, the primary goals brought back by Gauss–Newton steps, and the step kept only
        when every primary goal is within the polish tolerances and the secondary cost
        falls); no evaluation is started after ``deadline``.  Returns ``(q', evaluations)``."""
        with reuse_goal_values():
            return self._secondary(q, max_evals, deadline)

    def _secondary(
        self, q: FloatArray, max_evals: int, deadline: float | None
    ) -> tuple[FloatArray, int]:
        q = np.asarray(q, dtype=float).copy()
        prob, n = self.problem, q.shape[0]
        if max_evals < 1 or not prob.has_secondary:
            return q, 0
        r1, j1 = self._rj(q)
        r2, j2 = self._rj(q, primary=False)
        used = 1
        if not self._within(self._errors(q)[0]):
            return q, used
        cost2 = float(r2 @ r2)
        mu, reach = 1e-3, lm.SECONDARY_REACH
        late = _clock(deadline)
        while used < max_evals and mu < 1e6 and reach > 1e-6 and cost2 > 0.0 and not late():
            delta, grow = _null_space_step(q, r1, j1, r2, j2, mu, self.bounds)
            if delta is None:
                if grow:
                    mu *= 10.0
                    continue
                break  # the secondary goals cannot move in the null space
            big = float(np.abs(delta).max())
            q_t = self._into_bounds(q + (min(1.0, reach / big) if big > 0.0 else 1.0) * delta)
            r1_t, j1_t = self._rj(q_t)
            used += 1
            for _ in range(lm.SECONDARY_RESTORE):  # back onto the primary goals
                if self._within(self._errors(q_t)[0]) or used >= max_evals or late():
                    break
                a = j1_t.T @ j1_t
                a += (1e-10 * np.trace(a) / n + 1e-14) * np.eye(n)
                try:
                    q_t = self._into_bounds(q_t + np.linalg.solve(a, j1_t.T @ r1_t))
                except np.linalg.LinAlgError:
                    break
                r1_t, j1_t = self._rj(q_t)
                used += 1
            r2_t, j2_t = self._rj(q_t, primary=False)
            cost2_t = float(r2_t @ r2_t)
            if cost2_t < cost2 and self._within(self._errors(q_t)[0]):
                rel = (cost2 - cost2_t) / cost2
                q, r1, j1, r2, j2, cost2 = q_t, r1_t, j1_t, r2_t, j2_t, cost2_t
                mu, reach = lm.secondary_rule(True, mu, reach)
                if rel < 1e-9:
                    break
            else:
                mu, reach = lm.secondary_rule(False, mu, reach)
        return q, used

    def with_posture(self, q_ref: FloatArray) -> PythonPolisher:
        """The same polisher (``prefer="nearest"`` keeps the nearest converged start)."""
        return self

    def toward(self, q: FloatArray, q_ref: FloatArray, max_evals: int) -> tuple[FloatArray, int]:
        """No self-motion slide for problems with Python goals: ``q`` unchanged."""
        return np.asarray(q, dtype=float), 0

    def residual(self, q: FloatArray) -> tuple[FloatArray, FloatArray, float, float]:
        """Stacked primary residual, its step Jacobian, largest position [m] and angular
        [rad] errors."""
        q = np.asarray(q, dtype=float)
        with reuse_goal_values():  # (the rows and the errors of one evaluation)
            r, jac = self._rj(q)
            _err, e_p, e_r = self._errors(q)
        return r, jac, e_p, e_r

    def secondary_cost(self, q_batch: FloatArray) -> FloatArray:
        """Squared norm of the secondary stack for each row of ``q_batch`` ``(k, nq)``."""
        return np.asarray(self.problem._errors_and_cost2(q_batch, self.q0)[1])


def _clock(deadline: float | None) -> Any:
    """A test of whether ``deadline`` (``time.perf_counter()`` seconds) has passed (always
    False without one)."""
    if deadline is None:
        return lambda: False
    return lambda: time.perf_counter() >= deadline


def _null_space_step(
    q: FloatArray,
    r1: FloatArray,
    j1: FloatArray,
    r2: FloatArray,
    j2: FloatArray,
    mu: float,
    bounds: lm.Bounds,
) -> tuple[FloatArray | None, bool]:
    """One step of the secondary descent over the joints free to move (the numpy twin of the
    step in :func:`swarm_ik.kernels.lm.secondary_descent`): ``δ = J₁⁺ r₁ + N z`` on the free
    joints ``F`` (``J₁`` with the other columns zeroed, ``N = D_F − J₁⁺J₁``), a joint at a
    limit that ``δ`` pushes outwards then held (out of ``F``) and the step made again, so
    that the step slides along the limit instead of being clipped there.

    Args:
        q: The point ``(nq,)``; ``r1``, ``j1``: primary residual and step Jacobian; ``r2``,
            ``j2``: the secondary ones; ``mu``: the damping; ``bounds``: the limits.

    Returns:
        ``(δ, False)``; ``(None, True)`` when the damped system is singular (grow ``mu``);
        ``(None, False)`` when the secondary goals cannot move in the null space.
    """
    n = q.shape[0]
    eye = np.eye(n)
    free = np.ones(n, dtype=bool)
    while True:
        j1f = j1 * free
        a1 = j1f.T @ j1f
        try:
            pinv = np.linalg.solve(a1 + (1e-10 * np.trace(a1) / n + 1e-14) * eye, j1f.T)
        except np.linalg.LinAlgError:
            return None, False  # (the kernel stops there too)
        proj = np.diag(free.astype(float)) - pinv @ j1f
        b = j2 @ proj
        a2 = b.T @ b
        tr2 = float(np.trace(a2))
        if tr2 <= 1e-300:
            return None, False
        try:
            z = np.linalg.solve(a2 + mu * tr2 / n * eye, b.T @ r2)
        except np.linalg.LinAlgError:
            return None, True
        delta = pinv @ r1 + proj @ z
        out = free & pushed_out(q, delta, bounds)
        if not out.any():
            return delta, False
        free &= ~out
