"""``swarm``: the default solver, a memetic swarm + Levenberg–Marquardt hybrid.

Paper 004 (Zhao, cuckoo search + Newton; SEEDS.md) draws the lesson: a global population
finds the basin, a Jacobian method finishes.  This module turns that into a solver that is
exact (it stops at the tolerance, down to 1e-10), stays inside the joint limits, and is fast
enough to compare with TRAC-IK:

* **The polish** (:func:`lm_polish`) is one numba-compiled function: for a batch of starts
  ``(k, nq)`` it runs a bounded Levenberg–Marquardt iteration on the pose residual
  ``r(q) = [p* − p(q); log(R* R(q)ᵀ)]`` (world axes) with the exact residual Jacobian
  ``[J_v; J_r⁻¹(φ) J_ω]`` built from the LOCAL_WORLD_ALIGNED frame Jacobian of
  :func:`swarm_ik.kinematics.fk_jac_one` (checked against finite differences in the tests).
  Joint limits are handled as an active set (a joint at a limit whose Gauss–Newton direction
  points outwards is frozen for that step) and by projection (clipping; continuous joints
  wrapped).  Each start stops at the tolerance, at a local minimum (no progress), or at its
  iteration cap.  Every FK + Jacobian evaluation counts as one evaluation.
* **The swarm** keeps the best polished points that did not converge (an archive of
  ``pop_size`` local minima) as its population and proposes half of each next generation's
  starts from them with the grey wolf move of :mod:`swarm_ik.solvers.gwo`
  (:func:`swarm_ik.solvers.gwo.gwo_move`, Mirjalili 2014 eqs. 3.3–3.7, the update paper
  003's MGWO builds on); the other half are uniform random starts.  Measured honestly (see
  :func:`run`): the uniform starts carry most of the global search, the swarm moves do not
  hurt, a swarm-only generation does.

The first start is ``q0`` when given, else the middle of the joint ranges (TRAC-IK's
benchmark seed).  One polish iteration costs about a microsecond, so a typical pose is solved
in well under a millisecond, most of it Python bookkeeping; see ``docs/performance.md``.
"""

from __future__ import annotations

import math
import time
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

from swarm_ik.errors import InvalidArgumentError, unknown
from swarm_ik.kinematics import fk_jac_one
from swarm_ik.problem import IKProblem
from swarm_ik.solvers.base import Evaluator, FloatArray, register
from swarm_ik.solvers.gwo import gwo_move

IntArray = NDArray[np.int64]

FULL_BUDGET_TOL = 1e-14
"""Polish tolerance [m, rad] when the run is not to stop at success (``stop_on_success=False``,
as in the papers' experiments): each start is polished to round-off."""

# Status codes of a polished start (``status`` output of :func:`lm_polish`).
NOT_RUN = 0
"""The start was not reached (budget spent, or an earlier start succeeded)."""
CONVERGED = 1
"""Both errors within tolerance."""
LOCAL_MIN = 2
"""No further progress: a local minimum of the residual (often at a joint limit)."""
ITER_CAP = 3
"""The start used its iteration cap without converging or stalling."""
BUDGET = 4
"""The evaluation budget of the call ran out during this start (it may be resumed)."""

PREFER = ("best", "nearest")
"""Answer selection modes of the ``swarm`` solver (``prefer`` parameter)."""


# --------------------------------------------------------------------------- kernels
@numba.njit(cache=True)
def _log3(m: FloatArray, out: FloatArray) -> float:  # pragma: no cover - compiled
    """Rotation vector of the rotation ``m`` (3, 3) into ``out`` (3,); returns the angle.

    Accurate near 0 (``atan2`` of the skew part) and near π (axis from the symmetric part).
    """
    s0 = 0.5 * (m[2, 1] - m[1, 2])
    s1 = 0.5 * (m[0, 2] - m[2, 0])
    s2 = 0.5 * (m[1, 0] - m[0, 1])
    sn = math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
    c = 0.5 * (m[0, 0] + m[1, 1] + m[2, 2] - 1.0)
    theta = math.atan2(sn, c)
    if theta < 1e-5:
        scale = 1.0 + theta * theta / 6.0
        out[0] = s0 * scale
        out[1] = s1 * scale
        out[2] = s2 * scale
    elif theta < math.pi - 1e-3:
        scale = theta / sn
        out[0] = s0 * scale
        out[1] = s1 * scale
        out[2] = s2 * scale
    else:
        # symmetric part: B = c I + (1 - c) a aᵀ
        i = 0
        if m[1, 1] > m[i, i]:
            i = 1
        if m[2, 2] > m[i, i]:
            i = 2
        one_c = 1.0 - c
        ai = math.sqrt(max((m[i, i] - c) / one_c, 0.0))
        a0 = 0.5 * (m[0, i] + m[i, 0]) / (one_c * ai)
        a1 = 0.5 * (m[1, i] + m[i, 1]) / (one_c * ai)
        a2 = 0.5 * (m[2, i] + m[i, 2]) / (one_c * ai)
        if i == 0:
            a0 = ai
        elif i == 1:
            a1 = ai
        else:
            a2 = ai
        norm = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
        if a0 * s0 + a1 * s1 + a2 * s2 < 0.0:
            norm = -norm
        out[0] = theta * a0 / norm
        out[1] = theta * a1 / norm
        out[2] = theta * a2 / norm
    return theta


@numba.njit(cache=True)
def _step_into_bounds(
    q: FloatArray,
    delta: FloatArray,
    scale: float,
    wrap: NDArray[np.bool_],
    lower: FloatArray,
    upper: FloatArray,
    out: FloatArray,
) -> None:  # pragma: no cover - compiled
    """``out = q + scale·delta``, continuous joints wrapped into [-π, π), then clipped."""
    for j in range(q.shape[0]):
        v = q[j] + scale * delta[j]
        if wrap[j]:
            v = (v + math.pi) % (2.0 * math.pi) - math.pi
        if v < lower[j]:
            v = lower[j]
        elif v > upper[j]:
            v = upper[j]
        out[j] = v


@numba.njit(cache=True)
def _residual(
    q: FloatArray,
    kinds: IntArray,
    axes: FloatArray,
    rot_p: FloatArray,
    pos_p: FloatArray,
    rot_f: FloatArray,
    pos_f: FloatArray,
    t_rot: FloatArray,
    t_pos: FloatArray,
    rot_w: float,
    want_jac: bool,
    res: FloatArray,
    jac: FloatArray,
    rot: FloatArray,
    pos: FloatArray,
    jraw: FloatArray,
    w_buf: FloatArray,
    o_buf: FloatArray,
    mot: FloatArray,
    tmp: FloatArray,
) -> tuple[float, float, float]:  # pragma: no cover - compiled
    """Residual ``r = [p* − p; w·log(R* Rᵀ)]`` (6,) and its Jacobian w.r.t. a step.

    ``jac`` (6, nq) is ``[J_v; w·J_r⁻¹(φ) J_ω]``: ``r(q + δ) ≈ r(q) − jac @ δ``.

    Returns:
        ``(cost ‖r‖², position error [m], rotation angle [rad])``.
    """
    fk_jac_one(
        q, kinds, axes, rot_p, pos_p, rot_f, pos_f, rot, pos, jraw, w_buf, o_buf, mot, tmp, want_jac
    )
    for a in range(3):
        res[a] = t_pos[a] - pos[a]
    # M = R* Rᵀ
    for a in range(3):
        for b in range(3):
            tmp[a, b] = t_rot[a, 0] * rot[b, 0] + t_rot[a, 1] * rot[b, 1] + t_rot[a, 2] * rot[b, 2]
    phi = np.empty(3)
    theta = _log3(tmp, phi)
    dp = math.sqrt(res[0] * res[0] + res[1] * res[1] + res[2] * res[2])
    for a in range(3):
        res[3 + a] = rot_w * phi[a]
    cost = dp * dp + rot_w * rot_w * theta * theta
    if want_jac:
        n = q.shape[0]
        for a in range(3):
            for j in range(n):
                jac[a, j] = jraw[a, j]
        if rot_w == 0.0:
            for a in range(3, 6):
                for j in range(n):
                    jac[a, j] = 0.0
        else:
            # J_r⁻¹(φ) = I + ½[φ]× + k [φ]×², k = 1/θ² − (1 + cos θ)/(2 θ sin θ)
            if theta < 1e-3:
                k = 1.0 / 12.0 + theta * theta / 720.0
            else:
                k = 1.0 / (theta * theta) - (1.0 + math.cos(theta)) / (
                    2.0 * theta * math.sin(theta)
                )
            px, py, pz = phi[0], phi[1], phi[2]
            # [φ]× and [φ]×²
            sk = mot
            sk[0, 0] = 0.0
            sk[0, 1] = -pz
            sk[0, 2] = py
            sk[1, 0] = pz
            sk[1, 1] = 0.0
            sk[1, 2] = -px
            sk[2, 0] = -py
            sk[2, 1] = px
            sk[2, 2] = 0.0
            for a in range(3):
                for b in range(3):
                    sq = sk[a, 0] * sk[0, b] + sk[a, 1] * sk[1, b] + sk[a, 2] * sk[2, b]
                    tmp[a, b] = (1.0 if a == b else 0.0) + 0.5 * sk[a, b] + k * sq
            for a in range(3):
                for j in range(n):
                    jac[3 + a, j] = rot_w * (
                        tmp[a, 0] * jraw[3, j] + tmp[a, 1] * jraw[4, j] + tmp[a, 2] * jraw[5, j]
                    )
    return cost, dp, theta


@numba.njit(cache=True)
def _chol_solve(a: FloatArray, b: FloatArray, n: int, x: FloatArray) -> bool:  # pragma: no cover
    """Solve ``a x = b`` for SPD ``a`` (n, n) in place (``a`` overwritten by its Cholesky
    factor); False when ``a`` is not numerically positive definite."""
    for j in range(n):
        s = a[j, j]
        for k in range(j):
            s -= a[j, k] * a[j, k]
        if s <= 0.0:
            return False
        d = math.sqrt(s)
        a[j, j] = d
        for i in range(j + 1, n):
            s = a[i, j]
            for k in range(j):
                s -= a[i, k] * a[j, k]
            a[i, j] = s / d
    for i in range(n):
        s = b[i]
        for k in range(i):
            s -= a[i, k] * x[k]
        x[i] = s / a[i, i]
    for i in range(n - 1, -1, -1):
        s = x[i]
        for k in range(i + 1, n):
            s -= a[k, i] * x[k]
        x[i] = s / a[i, i]
    return True


@numba.njit(cache=True)
def lm_polish(
    starts: FloatArray,
    kinds: IntArray,
    axes: FloatArray,
    rot_p: FloatArray,
    pos_p: FloatArray,
    rot_f: FloatArray,
    pos_f: FloatArray,
    t_rot: FloatArray,
    t_pos: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
    wrap: NDArray[np.bool_],
    rot_w: float,
    tol_pos: float,
    tol_rot: float,
    max_iters: int,
    max_evals: int,
    stop_first: bool,
    lam0: float,
    max_step: float,
    stall_rel: float,
    stall_iters: int,
    out_q: FloatArray,
    out_dp: FloatArray,
    out_dr: FloatArray,
    out_status: IntArray,
    out_evals: IntArray,
) -> int:  # pragma: no cover - compiled
    """Bounded Levenberg–Marquardt polish of a batch of starts; returns evaluations used.

    Starts are polished one after the other; with ``stop_first`` the call returns as soon as
    one converges.  Each FK + Jacobian evaluation counts as one evaluation and the call never
    uses more than ``max_evals``.

    Args:
        starts: Starting joint vectors, shape ``(k, nq)``, inside the bounds.
        kinds, axes, rot_p, pos_p, rot_f, pos_f: The chain (:class:`ChainKinematics`).
        t_rot: Target rotation, shape ``(3, 3)``.
        t_pos: Target position [m], shape ``(3,)``.
        lower, upper: Bounds, shape ``(nq,)``.
        wrap: Continuous joints (wrapped into ``[-π, π)``), shape ``(nq,)``.
        rot_w: Weight of the rotation residual [m/rad]; 0 = position only.
        tol_pos: Position tolerance [m].
        tol_rot: Rotation tolerance [rad] (ignored when ``rot_w == 0``).
        max_iters: Most evaluations per start.
        max_evals: Most evaluations in this call (all starts together).
        stop_first: Return at the first converged start.
        lam0: Initial damping, relative to the mean diagonal of ``JᵀJ``.
        max_step: Largest step per joint per iteration (rad or m).
        stall_rel: A step is "no progress" when the cost falls by less than this fraction…
        stall_iters: …this many times in a row: the start is at a local minimum.
        out_q: Polished points, shape ``(k, nq)``.
        out_dp: Their position errors [m], ``(k,)``.
        out_dr: Their rotation errors [rad], ``(k,)``.
        out_status: ``NOT_RUN``, ``CONVERGED``, ``LOCAL_MIN``, ``ITER_CAP`` or ``BUDGET``.
        out_evals: Evaluations used per start, ``(k,)``.
    """
    k_starts, n = starts.shape
    res = np.empty(6)
    jac = np.empty((6, n))
    res_t = np.empty(6)
    jac_t = np.empty((6, n))
    rot = np.empty((3, 3))
    pos = np.empty(3)
    jraw = np.empty((6, n))
    w_buf = np.empty((n, 3))
    o_buf = np.empty((n, 3))
    mot = np.empty((3, 3))
    tmp = np.empty((3, 3))
    a_mat = np.empty((n, n))
    g = np.empty(n)
    delta = np.empty(n)
    q = np.empty(n)
    q_t = np.empty(n)
    free = np.empty(n, dtype=np.bool_)
    idx = np.empty(n, dtype=np.int64)
    a_red = np.empty((n, n))
    b_red = np.empty(n)
    x_red = np.empty(n)
    used = 0
    for s in range(k_starts):
        out_status[s] = NOT_RUN
        out_evals[s] = 0
        out_dp[s] = np.inf
        out_dr[s] = np.inf
    for s in range(k_starts):
        for j in range(n):
            out_q[s, j] = starts[s, j]
    for s in range(k_starts):
        if used >= max_evals:
            break
        for j in range(n):
            q[j] = starts[s, j]
        cost, dp, dr = _residual(
            q,
            kinds,
            axes,
            rot_p,
            pos_p,
            rot_f,
            pos_f,
            t_rot,
            t_pos,
            rot_w,
            True,
            res,
            jac,
            rot,
            pos,
            jraw,
            w_buf,
            o_buf,
            mot,
            tmp,
        )
        used += 1
        ev_s = 1
        status = ITER_CAP
        lam = lam0
        stall = 0
        while True:
            if dp <= tol_pos and (rot_w == 0.0 or dr <= tol_rot):
                status = CONVERGED
                break
            if ev_s >= max_iters:
                status = ITER_CAP
                break
            if used >= max_evals:
                status = BUDGET
                break
            # normal equations A = JᵀJ, g = Jᵀr
            trace = 0.0
            for i in range(n):
                s_g = 0.0
                for a in range(6):
                    s_g += jac[a, i] * res[a]
                g[i] = s_g
                for j in range(i, n):
                    s_a = 0.0
                    for a in range(6):
                        s_a += jac[a, i] * jac[a, j]
                    a_mat[i, j] = s_a
                    a_mat[j, i] = s_a
                trace += a_mat[i, i]
            scale = trace / n + 1e-300
            # active set: a joint at a limit whose descent direction points outwards is fixed
            m = 0
            for j in range(n):
                at_lo = (not wrap[j]) and q[j] <= lower[j] and g[j] < 0.0
                at_hi = (not wrap[j]) and q[j] >= upper[j] and g[j] > 0.0
                free[j] = not (at_lo or at_hi)
                if free[j]:
                    idx[m] = j
                    m += 1
            ok = False
            while not ok:
                for i in range(m):
                    for j in range(m):
                        a_red[i, j] = a_mat[idx[i], idx[j]]
                    a_red[i, i] += lam * scale
                    b_red[i] = g[idx[i]]
                ok = _chol_solve(a_red, b_red, m, x_red)
                if not ok:
                    lam *= 10.0
                    if lam > 1e12:
                        break
            if not ok:
                status = LOCAL_MIN
                break
            for j in range(n):
                delta[j] = 0.0
            big = 0.0
            for i in range(m):
                delta[idx[i]] = x_red[i]
                if abs(x_red[i]) > big:
                    big = abs(x_red[i])
            shrink = 1.0
            if big > max_step:
                shrink = max_step / big
            _step_into_bounds(q, delta, shrink, wrap, lower, upper, q_t)
            cost_t, dp_t, dr_t = _residual(
                q_t,
                kinds,
                axes,
                rot_p,
                pos_p,
                rot_f,
                pos_f,
                t_rot,
                t_pos,
                rot_w,
                True,
                res_t,
                jac_t,
                rot,
                pos,
                jraw,
                w_buf,
                o_buf,
                mot,
                tmp,
            )
            used += 1
            ev_s += 1
            if cost_t < cost:
                if cost_t > cost * (1.0 - stall_rel):
                    stall += 1
                else:
                    stall = 0
                for j in range(n):
                    q[j] = q_t[j]
                for a in range(6):
                    res[a] = res_t[a]
                    for j in range(n):
                        jac[a, j] = jac_t[a, j]
                cost, dp, dr = cost_t, dp_t, dr_t
                lam = max(lam * 0.1, 1e-12)
                if stall >= stall_iters and not (dp <= tol_pos and (rot_w == 0.0 or dr <= tol_rot)):
                    status = LOCAL_MIN
                    break
            else:
                lam *= 10.0
                stall += 1
                if lam > 1e8 or stall >= stall_iters:
                    status = LOCAL_MIN
                    break
        for j in range(n):
            out_q[s, j] = q[j]
        out_dp[s] = dp
        out_dr[s] = dr
        out_status[s] = status
        out_evals[s] = ev_s
        if stop_first and status == CONVERGED:
            break
    return used


@numba.njit(cache=True)
def nullspace_toward(
    q_in: FloatArray,
    q_ref: FloatArray,
    kinds: IntArray,
    axes: FloatArray,
    rot_p: FloatArray,
    pos_p: FloatArray,
    rot_f: FloatArray,
    pos_f: FloatArray,
    t_rot: FloatArray,
    t_pos: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
    wrap: NDArray[np.bool_],
    rot_w: float,
    tol_pos: float,
    tol_rot: float,
    gain: float,
    max_evals: int,
    out_q: FloatArray,
) -> int:  # pragma: no cover - compiled
    """Slide a solution along its self-motion towards ``q_ref``, staying on the target.

    Iterates ``δ = J⁺ r + (I − J⁺ J)·gain·(q_ref − q)`` (``J⁺ = Jᵀ (J Jᵀ + εI)⁻¹``, the
    residual Jacobian of :func:`lm_polish`), clipped to the bounds, keeping a step only when
    the pose stays within tolerance and the (wrapped) distance to ``q_ref`` decreases.  For a
    non-redundant arm the null space is empty and nothing moves.  Used by ``prefer="nearest"``.

    Args:
        q_in: A solution, shape ``(nq,)``.
        q_ref: The joint vector to approach (``q0``), shape ``(nq,)``.
        kinds … wrap: As :func:`lm_polish`.
        rot_w, tol_pos, tol_rot: As :func:`lm_polish`.
        gain: Fraction of the remaining distance attempted per step (0–1].
        max_evals: Most FK + Jacobian evaluations.
        out_q: The refined solution, shape ``(nq,)`` (``q_in`` if no step was kept).

    Returns:
        Evaluations used.
    """
    n = q_in.shape[0]
    res = np.empty(6)
    jac = np.empty((6, n))
    res_t = np.empty(6)
    jac_t = np.empty((6, n))
    rot = np.empty((3, 3))
    pos = np.empty(3)
    jraw = np.empty((6, n))
    w_buf = np.empty((n, 3))
    o_buf = np.empty((n, 3))
    mot = np.empty((3, 3))
    tmp = np.empty((3, 3))
    jjt = np.empty((6, 6))
    y = np.empty(6)
    b = np.empty(6)
    d = np.empty(n)
    delta = np.empty(n)
    q = q_in.copy()
    q_t = np.empty(n)
    for j in range(n):
        out_q[j] = q[j]
    if max_evals < 1:
        return 0
    _residual(
        q,
        kinds,
        axes,
        rot_p,
        pos_p,
        rot_f,
        pos_f,
        t_rot,
        t_pos,
        rot_w,
        True,
        res,
        jac,
        rot,
        pos,
        jraw,
        w_buf,
        o_buf,
        mot,
        tmp,
    )
    used = 1
    dist = 0.0
    for j in range(n):
        dj = q_ref[j] - q[j]
        if wrap[j]:
            dj = (dj + math.pi) % (2.0 * math.pi) - math.pi
        d[j] = dj
        dist += dj * dj
    step_gain = gain
    while used < max_evals and dist > 1e-24 and step_gain > 1e-4:
        # y = (J Jᵀ + εI)⁻¹ (r − J·g·d);  δ = g·d + Jᵀ y
        for a in range(6):
            s_b = res[a]
            for j in range(n):
                s_b -= jac[a, j] * step_gain * d[j]
            b[a] = s_b
            for c in range(6):
                s_a = 0.0
                for j in range(n):
                    s_a += jac[a, j] * jac[c, j]
                jjt[a, c] = s_a
            jjt[a, a] += 1e-12
        if rot_w == 0.0:
            for a in range(3, 6):
                b[a] = 0.0
                for c in range(6):
                    jjt[a, c] = 0.0
                    jjt[c, a] = 0.0
                jjt[a, a] = 1.0
        if not _chol_solve(jjt, b, 6, y):
            break
        for j in range(n):
            v = step_gain * d[j]
            for a in range(6):
                v += jac[a, j] * y[a]
            delta[j] = v
        _step_into_bounds(q, delta, 1.0, wrap, lower, upper, q_t)
        _c, dp_t, dr_t = _residual(
            q_t,
            kinds,
            axes,
            rot_p,
            pos_p,
            rot_f,
            pos_f,
            t_rot,
            t_pos,
            rot_w,
            True,
            res_t,
            jac_t,
            rot,
            pos,
            jraw,
            w_buf,
            o_buf,
            mot,
            tmp,
        )
        used += 1
        dist_t = 0.0
        for j in range(n):
            dj = q_ref[j] - q_t[j]
            if wrap[j]:
                dj = (dj + math.pi) % (2.0 * math.pi) - math.pi
            dist_t += dj * dj
        on_target = dp_t <= tol_pos and (rot_w == 0.0 or dr_t <= tol_rot)
        if on_target and dist_t < dist * (1.0 - 1e-6):
            for j in range(n):
                q[j] = q_t[j]
                out_q[j] = q_t[j]
                dj = q_ref[j] - q_t[j]
                if wrap[j]:
                    dj = (dj + math.pi) % (2.0 * math.pi) - math.pi
                d[j] = dj
            for a in range(6):
                res[a] = res_t[a]
                for j in range(n):
                    jac[a, j] = jac_t[a, j]
            dist = dist_t
            step_gain = min(gain, step_gain * 2.0)
        elif on_target:
            break  # no more progress along the self-motion
        else:
            step_gain *= 0.5
    return used


# --------------------------------------------------------------------------- python side
class PolishOutcome(NamedTuple):
    """What one call of the compiled polish returns.

    Attributes:
        q: Polished points, shape ``(k, nq)`` (the start where not run).
        position_error: ‖Δp‖ [m], ``(k,)`` (``inf`` where not run).
        rotation_error: θ [rad], ``(k,)`` (``inf`` where not run).
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


class Polisher(NamedTuple):
    """The compiled LM polish bound to one IK problem (the chain, target, bounds, tolerance).

    Build with :meth:`from_problem`.  Attributes are the kernel's arguments (see
    :func:`lm_polish`); ``kernel_tol_*`` are the tolerances the kernel stops at
    (``tol_margin`` × the success tolerances, so that Pinocchio's check passes with margin).
    """

    kinds: IntArray
    axes: FloatArray
    rot_p: FloatArray
    pos_p: FloatArray
    rot_f: FloatArray
    pos_f: FloatArray
    t_rot: FloatArray
    t_pos: FloatArray
    lower: FloatArray
    upper: FloatArray
    wrap: NDArray[np.bool_]
    rot_w: float
    kernel_tol_pos: float
    kernel_tol_rot: float
    max_iters: int = 30
    lam0: float = 1e-2
    max_step: float = 1.0
    stall_rel: float = 1e-2
    stall_iters: int = 3

    @classmethod
    def from_problem(
        cls,
        problem: IKProblem,
        lower: FloatArray,
        upper: FloatArray,
        tol_pos: float = 1e-5,
        tol_rot: float = 1e-5,
        *,
        wrap: NDArray[np.bool_] | None = None,
        tol_margin: float = 0.5,
        max_iters: int = 30,
        lam0: float = 1e-2,
        max_step: float = 1.0,
        stall_rel: float = 1e-2,
        stall_iters: int = 3,
    ) -> Polisher:
        """Bind the kernel to ``problem`` (its robot's chain and target) within the bounds.

        Args:
            problem: The IK problem.
            lower: Lower bounds, shape ``(nq,)``.
            upper: Upper bounds, shape ``(nq,)``.
            tol_pos: Position tolerance of success [m].
            tol_rot: Rotation tolerance of success [rad].
            wrap: Continuous-joint mask, shape ``(nq,)`` (default: the robot's).
            tol_margin: The kernel stops at ``tol_margin`` × the tolerances.
            max_iters, lam0, max_step, stall_rel, stall_iters: See :func:`lm_polish`.
        """
        chain = problem.robot.chain
        target = problem.target
        return cls(
            kinds=chain.kinds,
            axes=chain.axes,
            rot_p=chain.rot_p,
            pos_p=chain.pos_p,
            rot_f=chain.rot_f,
            pos_f=chain.pos_f,
            t_rot=np.ascontiguousarray(target[:3, :3]),
            t_pos=np.ascontiguousarray(target[:3, 3]),
            lower=np.ascontiguousarray(lower, dtype=float),
            upper=np.ascontiguousarray(upper, dtype=float),
            wrap=np.ascontiguousarray(problem.robot.continuous_mask if wrap is None else wrap),
            rot_w=0.0 if problem.position_only else 1.0,
            kernel_tol_pos=float(tol_pos) * tol_margin,
            kernel_tol_rot=float(tol_rot) * tol_margin,
            max_iters=int(max_iters),
            lam0=float(lam0),
            max_step=float(max_step),
            stall_rel=float(stall_rel),
            stall_iters=int(stall_iters),
        )

    def polish(self, starts: FloatArray, max_evals: int, stop_first: bool = True) -> PolishOutcome:
        """Polish ``starts`` ``(k, nq)`` (inside the bounds) with at most ``max_evals``
        evaluations; with ``stop_first`` the call ends at the first converged start."""
        starts = np.ascontiguousarray(starts, dtype=float)
        k, n = starts.shape
        out_q = np.empty((k, n))
        dp = np.empty(k)
        dr = np.empty(k)
        status = np.empty(k, dtype=np.int64)
        evals = np.empty(k, dtype=np.int64)
        used = lm_polish(
            starts,
            self.kinds,
            self.axes,
            self.rot_p,
            self.pos_p,
            self.rot_f,
            self.pos_f,
            self.t_rot,
            self.t_pos,
            self.lower,
            self.upper,
            self.wrap,
            self.rot_w,
            self.kernel_tol_pos,
            self.kernel_tol_rot,
            self.max_iters,
            int(max_evals),
            bool(stop_first),
            self.lam0,
            self.max_step,
            self.stall_rel,
            self.stall_iters,
            out_q,
            dp,
            dr,
            status,
            evals,
        )
        return PolishOutcome(out_q, dp, dr, status, evals, int(used))

    def toward(
        self, q: FloatArray, q_ref: FloatArray, max_evals: int, gain: float = 0.5
    ) -> tuple[FloatArray, int]:
        """Move the solution ``q`` along its self-motion towards ``q_ref`` (see
        :func:`nullspace_toward`); returns ``(q', evaluations used)``."""
        out = np.empty_like(q)
        used = nullspace_toward(
            np.ascontiguousarray(q, dtype=float),
            np.ascontiguousarray(q_ref, dtype=float),
            self.kinds,
            self.axes,
            self.rot_p,
            self.pos_p,
            self.rot_f,
            self.pos_f,
            self.t_rot,
            self.t_pos,
            self.lower,
            self.upper,
            self.wrap,
            self.rot_w,
            self.kernel_tol_pos,
            self.kernel_tol_rot,
            float(gain),
            int(max_evals),
            out,
        )
        return out, int(used)

    def residual(self, q: FloatArray) -> tuple[FloatArray, FloatArray, float, float]:
        """Residual ``r (6,)``, its step Jacobian ``(6, nq)`` (``r(q + δ) ≈ r − jac @ δ``),
        position error [m] and rotation angle [rad] at one ``q`` (for tests and tools)."""
        q = np.ascontiguousarray(q, dtype=float)
        n = q.shape[0]
        res = np.empty(6)
        jac = np.empty((6, n))
        _c, dp, dr = _residual(
            q,
            self.kinds,
            self.axes,
            self.rot_p,
            self.pos_p,
            self.rot_f,
            self.pos_f,
            self.t_rot,
            self.t_pos,
            self.rot_w,
            True,
            res,
            jac,
            np.empty((3, 3)),
            np.empty(3),
            np.empty((6, n)),
            np.empty((n, 3)),
            np.empty((n, 3)),
            np.empty((3, 3)),
            np.empty((3, 3)),
        )
        return res, jac, float(dp), float(dr)


def wrapped_distance(a: FloatArray, b: FloatArray, wrap: NDArray[np.bool_]) -> FloatArray:
    """Euclidean joint-space distance with continuous joints' differences wrapped to
    ``[-π, π)``: ``a (..., nq)`` against ``b (nq,)`` → ``(...)``."""
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    if wrap.any():
        d[..., wrap] = (d[..., wrap] + np.pi) % (2 * np.pi) - np.pi
    return np.linalg.norm(d, axis=-1)


def _check_params(
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


def propose(
    ev: Evaluator,
    rng: np.random.Generator,
    arch_x: FloatArray,
    arch_f: FloatArray,
    n_swarm: int,
    n_total: int,
    a: float,
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
        parts.append(ev.lower + (ev.upper - ev.lower) * rng.random((n_total - n_swarm, ev.dim)))
    return np.concatenate(parts) if parts else np.empty((0, ev.dim))


def run(
    ev: Evaluator,
    rng: np.random.Generator,
    *,
    pop_size: int = 12,
    iterations: int = 100,
    swarm_fraction: float = 0.5,
    max_iters: int = 30,
    lam0: float = 1e-2,
    max_step: float = 1.0,
    stall_rel: float = 1e-2,
    stall_iters: int = 3,
    tol_margin: float = 0.5,
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
    (:func:`propose`; Mirjalili 2014 eqs. 3.3–3.7, ``a`` falling from 2 to 0 with the spent
    share of the budget) and uniform random starts for the rest.  Paper 004 (SEEDS.md) is the
    model: the population finds the basin, the Jacobian method finishes; here the Jacobian
    method does most of the work and the population supplies starts.

    Every FK + Jacobian evaluation of the compiled polish counts as one evaluation
    (``ev.add_evals``); a time limit is honoured by giving each compiled call only as many
    evaluations as the remaining time allows at the measured cost per evaluation.  The polish
    stops each start at ``tol_margin`` × the tolerance of ``ev.tolerance`` (1e-5 m / 1e-5 rad
    when the evaluator has none).

    With ``prefer="nearest"`` the answer is the solution nearest to ``q0`` (wrapped joint
    distance) rather than the lowest fitness: once a first solution is found, ``nearest_starts``
    more starts drawn around ``q0`` are polished, the nearest converged one is kept and, on a
    redundant arm, slid along its self-motion towards ``q0`` (:func:`nullspace_toward`).

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
            about 10–20 on 6–7 joint arms).  ``max_iters``, ``lam0``, ``max_step`` and
            ``stall_rel`` were tuned together on Panda, UR10 and Baxter (2000 targets each,
            300 evaluations): 30 / 1e-2 / 1 rad / 1e-2 beat 60 / 1e-3 / 0.5 rad / 1e-3 by
            0.2–0.6 points of success at fewer evaluations.
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
    _check_params(
        pop_size, iterations, swarm_fraction, max_iters, prefer, nearest_starts, tol_margin
    )
    tol_pos, tol_rot = ev.tolerance if ev.tolerance is not None else (1e-5, 1e-5)
    if not ev.stops_on_success:  # the whole budget runs: polish down to round-off
        tol_pos, tol_rot = min(tol_pos, FULL_BUDGET_TOL), min(tol_rot, FULL_BUDGET_TOL)
    pol = Polisher.from_problem(
        problem,
        ev.lower,
        ev.upper,
        tol_pos,
        tol_rot,
        wrap=ev.wrap_mask,
        tol_margin=tol_margin,
        max_iters=max_iters,
        lam0=lam0,
        max_step=max_step,
        stall_rel=stall_rel,
        stall_iters=stall_iters,
    )
    # the se3 fitness is dp + w_rot·θ, which the kernel computes; any other fitness (or an
    # overridden one) is evaluated by the problem itself
    se3 = problem.fitness_name == "se3" and type(problem).fitness is IKProblem.fitness
    w_rot = 0.0 if problem.position_only else problem.w_rot

    def fitness_of(q: FloatArray, dp: FloatArray, dr: FloatArray) -> FloatArray:
        if se3:
            return dp + w_rot * dr
        return np.asarray(problem.fitness(q), dtype=float)

    nearest = prefer == "nearest"
    seed = ev.q0.copy() if ev.q0 is not None else 0.5 * (ev.lower + ev.upper)
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
    lo, width = ev.lower, ev.upper - ev.lower
    near_done = False
    open_gen = False
    sec_per_eval = 5e-6
    t = 0
    while not ev.done and (not unlimited or t < iterations):
        cap = ev.remaining
        if ev.time_limit is not None:
            left = ev.time_limit - ev.elapsed
            cap = min(cap, max(8, int(0.8 * left / sec_per_eval)))
        t1 = time.perf_counter()
        out = pol.polish(queue, cap, stop_first=not (nearest and sol_x))
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
            queue = propose(ev, rng, arch_x, arch_f, n_swarm, m, a)
    if nearest:
        if sol_x:
            sols = np.asarray(sol_x)
            k = int(np.argmin(wrapped_distance(sols, seed, pol.wrap)))
            q_best = sols[k]
            if problem.nq > (3 if problem.position_only else 6) and ev.remaining > 0:
                q_best, used = pol.toward(q_best, seed, min(ev.remaining, 200))
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


register(
    "swarm",
    run,
    description="default: memetic swarm (grey wolf proposals) + compiled bounded "
    "Levenberg-Marquardt polish; exact, within limits, fast",
    needs_jacobian=True,
)
