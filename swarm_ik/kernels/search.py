"""The restart search around the LM kernel, in one compiled call: starts, grey-wolf
proposals, LM polish, stop test, clipping and the time check.

:func:`swarm_search` is the compiled twin of the Python loop of
:func:`swarm_ik.solvers.hybrid.run` (``prefer="best"``, stopping at success, no secondary
goal): generation 0 polishes the seed and then ``pop_size − 1`` uniform starts, one after the
other, until one converges; the polished points that did not converge form an archive of
local minima (best first, ``pop_size`` kept); each later generation polishes ``n_swarm``
grey-wolf moves of the archive ([GWO] eqs. 3.3–3.7, :func:`gwo_move_into`, the twin of
:func:`swarm_ik.solvers.gwo.gwo_move`) and uniform starts for the rest.  The polish is
:func:`swarm_ik.kernels.lm.lm_run`; the goals are any goal table (one frame or many,
compiled goal kernels of any kind).

Randomness is a counter-based stream: uniform number ``c`` of a run is
``splitmix64(key + c) >> 11 · 2⁻⁵³`` (SplitMix64: Steele, Lea & Flood, OOPSLA 2014), with
``key`` one ``uint64`` (:func:`key_of_seed` of an integer seed, :func:`stream_key` of a
numpy Generator), so the same seed gives the same result.

The clock: numba has none; :func:`now` reads ``time.perf_counter`` in ``numba.objmode``
(about a microsecond), once per polish call under a time limit and every 16th call in any
case.  Entering Python there also lets a Ctrl-C raise ``KeyboardInterrupt`` out of the
compiled call (within 16 polish calls: a few milliseconds).

Called from Python on a :class:`SearchState` made once (one argument
numba types at once; the structures one by one are typed in Python on every call).
"""

from __future__ import annotations

import functools
import time
from typing import Any, NamedTuple

import numba
import numpy as np
from numba import types
from numba.experimental import structref

from swarm_ik._types import FloatArray, IntArray
from swarm_ik.kernels import lm
from swarm_ik.kernels.fk import TreeArrays
from swarm_ik.kernels.lm import BUDGET, CONVERGED, Bounds, GoalKernels, GoalTable, LMSettings

NO_LIMIT = -1.0
"""``time_limit`` value meaning "no time limit"."""


@numba.njit(cache=True)
def now() -> float:  # pragma: no cover - compiled
    """Seconds of ``time.perf_counter`` (in ``numba.objmode``: usable in compiled code)."""
    with numba.objmode(t="float64"):
        t = time.perf_counter()
    return t


@numba.njit(cache=True)
def wall_clock() -> float:  # pragma: no cover - compiled
    """Seconds since the epoch (``time.time``, in ``numba.objmode``): the clock of a batch's
    ``time_limit``, comparable between the processes of one machine (Dask workers)."""
    with numba.objmode(t="float64"):
        t = time.time()
    return t


# --------------------------------------------------------------------------- randomness
@numba.njit(cache=True)
def splitmix64(x: np.uint64) -> np.uint64:  # pragma: no cover - compiled
    """One SplitMix64 output for state ``x`` (the state advances by the golden gamma)."""
    z = x + np.uint64(0x9E3779B97F4A7C15)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


SAMPLING_WIDTH = 20.0
"""Widest joint range [rad or m] random starts sample uniformly (the compiled twin of
:data:`swarm_ik.urdf.DEFAULT_MAX_SAMPLING_WIDTH`)."""


@numba.njit(cache=True)
def uniform_at(key: np.uint64, c: np.uint64) -> float:  # pragma: no cover - compiled
    """Uniform number ``c`` in ``[0, 1)`` of the stream ``key``: ``splitmix64(key + c) >> 11
    · 2⁻⁵³`` (every compiled draw of the package, the batch's included)."""
    return float(splitmix64(key + c) >> np.uint64(11)) * (2.0**-53)


@numba.njit(cache=True)
def uniform_in(
    lo: float, hi: float, key: np.uint64, c: np.uint64
) -> float:  # pragma: no cover - compiled
    """Draw ``c`` of the stream ``key`` uniform in ``[lo, hi]`` (a random start's joint in
    its sampling window: the search's restarts and the batch's)."""
    return min(lo + (hi - lo) * uniform_at(key, c), hi)


@numba.njit(cache=True)
def uniforms(key: np.uint64, first: int, n: int) -> FloatArray:  # pragma: no cover
    """Uniforms ``first + 1 … first + n`` of the stream ``key`` in ``[0, 1)`` (tests, tools)."""
    out = np.empty(n)
    for c in range(n):
        out[c] = uniform_at(key, np.uint64(first + c + 1))
    return out


def stream_key(rng: np.random.Generator) -> np.uint64:
    """The ``uint64`` key of a search's random stream, one draw from ``rng``."""
    return np.uint64(rng.integers(0, 2**64, dtype=np.uint64))


@functools.lru_cache(maxsize=1024)
def key_of_seed(seed: int) -> np.uint64:
    """The ``uint64`` key of a search's random stream for an integer seed ``0 <= seed <
    2**64``: one SplitMix64 output of the seed (the same in every process and platform;
    compiled: Python's integers cost several µs per call; remembered per seed, as most
    solves pass the same few seeds and a compiled call costs 2 µs)."""
    return np.uint64(splitmix64(np.uint64(seed)))


# --------------------------------------------------------------------------- grey wolf
@numba.njit(cache=True)
def gwo_move_into(
    x: FloatArray,
    rows: int,
    leaders: FloatArray,
    a: float,
    r1: FloatArray,
    r2: FloatArray,
    out: FloatArray,
) -> None:  # pragma: no cover - compiled
    """One grey-wolf move of ``x[:rows]`` (``(p, n)``) towards the leaders ``(3, n)``
    ([GWO] eqs. 3.3–3.7): ``A = 2a·r1 − a``, ``C = 2·r2``, ``X_l' = X_l − A·|C·X_l − X|``,
    ``X ← mean over α, β, δ``; ``r1``, ``r2`` of shape ``(3, p, n)`` as drawn by
    :func:`swarm_ik.solvers.gwo.gwo_move` (the numpy twin; equal on the same numbers).
    Writes ``out[:rows]``, not clipped."""
    n = x.shape[1]
    for i in range(rows):
        for j in range(n):
            s = 0.0
            for L in range(3):
                big_a = 2.0 * a * r1[L, i, j] - a
                big_c = 2.0 * r2[L, i, j]
                s += leaders[L, j] - big_a * abs(big_c * leaders[L, j] - x[i, j])
            out[i, j] = s / 3.0


@numba.njit(cache=True)
def _clip_row(q: FloatArray, b: Bounds) -> None:  # pragma: no cover - compiled
    """Continuous joints wrapped into ``[-π, π)``, then clipped to the bounds (in place; the
    twin of :meth:`swarm_ik.solvers.base.Evaluator.clip`)."""
    for j in range(q.shape[0]):
        q[j] = lm.into_bounds(q[j], j, b)


# --------------------------------------------------------------------------- the search
@numba.njit(cache=True)
def _offer(
    q: FloatArray, f: float, dp: float, dr: float, ev_q: FloatArray
) -> tuple[float, float, float]:  # pragma: no cover - compiled
    """Offer the best point ``q`` (fitness, errors) to the evaluator's best ``ev_q`` (copied
    in); returns the evaluator's new fitness and errors."""
    for j in range(q.shape[0]):
        ev_q[j] = q[j]
    return f, dp, dr


@numba.njit(cache=True)
def sampling_window(
    lower: FloatArray, upper: FloatArray, seed_q: FloatArray, lo: FloatArray, hi: FloatArray
) -> None:  # pragma: no cover - compiled
    """The box random starts are drawn from, into ``lo``/``hi`` ``(nq,)``: the bounds, with a
    range wider than :data:`SAMPLING_WIDTH` narrowed to a window around the seed (the
    compiled twin of :func:`swarm_ik.urdf.sampling_bounds`; mobile-base joints)."""
    for j in range(lower.shape[0]):
        lo[j] = lower[j]
        hi[j] = upper[j]
        if hi[j] - lo[j] > SAMPLING_WIDTH:
            a = min(max(seed_q[j] - 0.5 * SAMPLING_WIDTH, lo[j]), hi[j] - SAMPLING_WIDTH)
            lo[j] = a
            hi[j] = a + SAMPLING_WIDTH


class SearchWork(NamedTuple):
    """Scratch of :func:`swarm_search`: every buffer it writes, made once by
    :func:`make_search_work`.  Each call sets what it reads before reading it, so a reused
    scratch gives the results of a new one."""

    queue: FloatArray
    """Starts to polish, ``(rows, nq)``."""
    pq: FloatArray
    """Polished points, ``(rows, nq)``; ``pdp``, ``pdr``, ``pst``, ``pev``: their errors,
    status and evaluations (:func:`swarm_ik.kernels.lm.polish_outputs`)."""
    pdp: FloatArray
    pdr: FloatArray
    pst: IntArray
    pev: IntArray
    arch_x: FloatArray
    """Archive of local minima, ``(2 rows, nq)``, and their fitness ``arch_f``."""
    arch_f: FloatArray
    lead: FloatArray
    """The three leaders, ``(3, nq)``; ``r1``, ``r2``: the grey-wolf draws ``(3, rows, nq)``;
    ``moved``: the moved wolves ``(rows, nq)``; ``tmp_x``, ``best_q``, ``ev_q``, ``lo``,
    ``hi``: ``(nq,)``."""
    r1: FloatArray
    r2: FloatArray
    moved: FloatArray
    tmp_x: FloatArray
    best_q: FloatArray
    ev_q: FloatArray
    lo: FloatArray
    hi: FloatArray
    lm_work: lm.Work
    """The scratch of :func:`swarm_ik.kernels.lm.lm_run`."""


def make_search_work(t: TreeArrays, g: GoalTable, pop_size: int) -> SearchWork:
    """The :class:`SearchWork` of :func:`swarm_search` for ``pop_size`` starts per
    generation (numpy's allocations, in Python: nothing to compile)."""
    n = t.nq
    rows = max(pop_size, 1)
    pq, pdp, pdr, pst, pev = lm.polish_outputs(rows, n)
    return SearchWork(
        np.empty((rows, n)), pq, pdp, pdr, pst, pev, np.empty((2 * rows, n)),
        np.empty(2 * rows), np.empty((3, n)), np.empty((3, rows, n)), np.empty((3, rows, n)),
        np.empty((rows, n)), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n),
        lm.make_work(t, g, g.rows_primary),
    )  # fmt: skip


@numba.njit(cache=True)
def grown(hist: FloatArray, n: int) -> FloatArray:  # pragma: no cover - compiled
    """A copy of ``hist``'s first ``n`` entries in a buffer twice as long."""
    bigger = np.empty(max(2 * hist.shape[0], n + 1, 1))
    for i in range(n):  # (a loop: a slice assignment compiles numba's broadcasting too)
        bigger[i] = hist[i]
    return bigger


@numba.njit(cache=True)
def swarm_search(
    s: Any,
    seed_q: FloatArray,
    kernel_tol_pos: float,
    kernel_tol_rot: float,
    tol_pos: float,
    tol_rot: float,
    w_rot: float,
    pop_size: int,
    n_swarm: int,
    iterations: int,
    unlimited: bool,
    max_evals: int,
    budget_total: int,
    evals_before: int,
    time_limit: float,
    t0: float,
    key: np.uint64,
    out_q: FloatArray,
) -> tuple[int, float, float, float, bool, FloatArray]:  # pragma: no cover - compiled
    """The memetic search of the ``swarm`` solver (see the module docstring).

    Args:
        s: The :class:`SearchState` (tree, goal table without secondary goals, goal kernels,
            bounds, LM settings, scratch made for ``pop_size``).
        seed_q: The first start, ``(nq,)``, inside the bounds.
        kernel_tol_pos, kernel_tol_rot: Tolerances the polish stops at [m], [rad].
        tol_pos, tol_rot: Tolerances of the stop test (``IKProblem.is_success``) [m], [rad].
        w_rot: Weight of the angle in the fitness ``dp + w_rot·dr`` [m/rad].
        pop_size: Starts per generation; ``n_swarm``: grey-wolf starts among them.
        iterations: Generations when ``unlimited``; length of the ``a`` schedule.
        unlimited: No evaluation budget and no time limit was given.
        max_evals: Evaluations this call may use (the evaluator's remaining budget).
        budget_total: The evaluator's ``max_evals`` (``-1``: none), for the ``a`` schedule.
        evals_before: Evaluations the evaluator had counted before this call.
        time_limit: Seconds since ``t0`` after which no polish starts (``NO_LIMIT``: none;
            the first, of the seed alone, always runs).
        t0: Start of the solve on the clock of :func:`now` [s].
        key: Random stream key (:func:`key_of_seed`, :func:`stream_key`).
        out_q: The answer (lowest fitness seen), ``(nq,)``.

    Returns:
        ``(evaluations, fitness, dp, dr, stopped, history)``: evaluations used, the answer's
        fitness, its position [m] and angular [rad] errors, whether the stop test ended the
        run, and the best fitness after each generation (the last entry: the answer's).
    """
    t, g, ks, b, cfg, sw = s.tree, s.table, s.kernels, s.bounds, s.cfg, s.work
    n = seed_q.shape[0]
    m = pop_size
    rows = max(m, 1)
    queue, pq, pdp, pdr, pst, pev = sw.queue, sw.pq, sw.pdp, sw.pdr, sw.pst, sw.pev
    arch_x, arch_f, tmp_x, lead, r1, r2 = sw.arch_x, sw.arch_f, sw.tmp_x, sw.lead, sw.r1, sw.r2
    moved, work = sw.moved, sw.lm_work
    if queue.shape[0] < rows or queue.shape[1] != n:
        raise ValueError("swarm_search: scratch made for fewer starts or another robot")
    best_q = sw.best_q  # lowest fitness seen (not yet offered to the stop test)
    ev_q = sw.ev_q  # the evaluator's best (what the stop test has seen)
    lo, hi = sw.lo, sw.hi  # random starts: uniform in the sampling window
    has_time = time_limit >= 0.0
    stream = np.uint64(key)
    hist = np.empty(16)
    lm.reset_work(work)
    n_hist = 0
    n_arch = 0
    for j in range(n):
        queue[0, j] = seed_q[j]
        best_q[j] = seed_q[j]
        ev_q[j] = seed_q[j]
    n_queue = 1
    best_f = np.inf
    best_dp = np.inf
    best_dr = np.inf
    ev_f = np.inf
    ev_dp = np.inf
    ev_dr = np.inf
    stopped = False
    used = 0
    gen0_rest = m > 1
    open_gen = False
    sec_per_eval = 5e-6
    gen = 0
    calls = 0
    counter = np.uint64(0)
    sampling_window(b.lower, b.upper, seed_q, lo, hi)
    # each polish call ends at its first converged start; the flag is a runtime bool (always
    # true), not the literal True: numba compiles a call with a literal flag as a function of
    # its own, and lm_polish would compile twice (6 s), here and for the Python loops' calls
    stop_first = m >= 0
    while True:
        if stopped or used >= max_evals:
            break
        calls += 1
        # the clock: not before the first polish call (one start, at most max_iters
        # evaluations, begun at t0), then before each under a time limit, and every 16th in
        # any case (entering Python there is where a pending Ctrl-C raises KeyboardInterrupt)
        if calls == 1:
            t_call = t0
        else:
            t_call = now() if has_time or (calls & 15) == 0 else 0.0
        if has_time and t_call - t0 >= time_limit:
            break
        if unlimited and gen >= iterations:
            break
        cap = max_evals - used
        if has_time:
            left = time_limit - (t_call - t0)
            cap = min(cap, max(8, int(0.8 * left / sec_per_eval)))
        u = lm.lm_polish(
            queue[:n_queue], t, g, ks, b, cfg, kernel_tol_pos, kernel_tol_rot, cap, stop_first,
            pq[:n_queue], pdp[:n_queue], pdr[:n_queue], pst[:n_queue], pev[:n_queue], work,
        )  # fmt: skip
        open_gen = True
        r = 0
        while r < n_queue and pst[r] != 0:
            r += 1
        fi = np.inf
        i_min = 0
        for s in range(r):
            f = pdp[s] + w_rot * pdr[s]
            if f < fi:
                fi = f
                i_min = s
        used += u
        if fi < best_f:
            best_f = fi
            best_dp = pdp[i_min]
            best_dr = pdr[i_min]
            for j in range(n):
                best_q[j] = pq[i_min, j]
        if r > 0 and pst[r - 1] == CONVERGED:  # offered to the stop test at once
            f_c = pdp[r - 1] + w_rot * pdr[r - 1]
            if f_c < ev_f:
                ev_f = f_c
                ev_dp = pdp[r - 1]
                ev_dr = pdr[r - 1]
                for j in range(n):
                    ev_q[j] = pq[r - 1, j]
                stopped = ev_dp <= tol_pos and ev_dr <= tol_rot
            if stopped or used >= max_evals or (has_time and now() - t0 >= time_limit):
                break
        if u > 0 and has_time:  # (read after the stop test: a run that ends needs no estimate)
            sec_per_eval = 0.5 * sec_per_eval + 0.5 * (now() - t_call) / u
        n_done = r - 1 if (r > 0 and pst[r - 1] == BUDGET) else r
        # archive of polished local minima, best first (stable), pop_size kept
        for s in range(n_done):
            if pst[s] == CONVERGED:
                continue
            f_new = pdp[s] + pdr[s]
            k = n_arch
            while k > 0 and arch_f[k - 1] > f_new:
                k -= 1
            for z in range(n_arch, k, -1):
                arch_f[z] = arch_f[z - 1]
                for j in range(n):
                    arch_x[z, j] = arch_x[z - 1, j]
            arch_f[k] = f_new
            for j in range(n):
                arch_x[k, j] = pq[s, j]
            n_arch += 1
        if n_arch > m:
            n_arch = m
        # unfinished rows (cut by the budget, or not reached) stay queued, partially polished
        for s in range(n_done, n_queue):
            for j in range(n):
                queue[s - n_done, j] = pq[s, j]
        n_queue -= n_done
        if n_queue == 0 and gen0_rest:
            gen0_rest = False
            for s in range(m - 1):
                for j in range(n):
                    counter += np.uint64(1)
                    queue[s, j] = uniform_in(lo[j], hi[j], stream, counter)
            n_queue = m - 1
            continue
        if n_queue != 0:
            continue
        if best_f < np.inf and best_f < ev_f:
            ev_f, ev_dp, ev_dr = _offer(best_q, best_f, best_dp, best_dr, ev_q)
            stopped = ev_dp <= tol_pos and ev_dr <= tol_rot
        if n_hist == hist.shape[0]:
            hist = grown(hist, n_hist)
        hist[n_hist] = ev_f
        n_hist += 1
        open_gen = False
        gen += 1
        frac = gen / max(iterations, 1)
        if budget_total > 0:
            frac = max(frac, (evals_before + used) / budget_total)
        a = 2.0 * max(0.0, 1.0 - frac)
        n_sw = min(n_swarm, m) if n_arch > 0 else 0
        if n_sw > 0:
            for L in range(3):
                for j in range(n):
                    lead[L, j] = arch_x[L % n_arch, j]
            for s in range(n_sw):
                for j in range(n):
                    queue[s, j] = arch_x[s % n_arch, j]
            for rr in (r1, r2):
                for L in range(3):
                    for s in range(n_sw):
                        for j in range(n):
                            counter += np.uint64(1)
                            rr[L, s, j] = uniform_at(stream, counter)
            gwo_move_into(queue, n_sw, lead, a, r1, r2, moved)
            for s in range(n_sw):
                for j in range(n):
                    tmp_x[j] = moved[s, j]
                _clip_row(tmp_x, b)
                for j in range(n):
                    queue[s, j] = tmp_x[j]
        for s in range(n_sw, m):
            for j in range(n):
                counter += np.uint64(1)
                queue[s, j] = uniform_in(lo[j], hi[j], stream, counter)
        n_queue = m
    if best_f < np.inf and best_f < ev_f and not stopped:
        ev_f, ev_dp, ev_dr = _offer(best_q, best_f, best_dp, best_dr, ev_q)
        stopped = ev_dp <= tol_pos and ev_dr <= tol_rot
    for j in range(n):
        out_q[j] = ev_q[j]
    if open_gen or n_hist == 0:
        if n_hist == hist.shape[0]:
            hist = grown(hist, n_hist)
        hist[n_hist] = ev_f
        n_hist += 1
    return used, ev_f, ev_dp, ev_dr, stopped, hist[:n_hist].copy()


@structref.register
class SearchStateType(types.StructRef):
    """The numba type of :class:`SearchState`."""

    def preprocess_fields(self, fields: Any) -> Any:
        return tuple((name, types.unliteral(typ)) for name, typ in fields)


class SearchState(structref.StructRefProxy):  # type: ignore[misc]
    """What :func:`search` needs besides a start and a key, made once
    (:func:`new_search_state`): the tree, the goal table, the goal kernels, the bounds, the LM
    settings and the scratch (:class:`SearchWork`).  One object (numba's public
    ``numba.experimental.structref``) that numba types at once, where the structures given one
    by one are typed in Python on every call; the goal table's arrays are shared, so a new
    target written into its parameters is what the next call reads."""


structref.define_proxy(
    SearchState, SearchStateType, ["tree", "table", "kernels", "bounds", "cfg", "work"]
)


def new_search_state(
    t: TreeArrays, g: GoalTable, ks: GoalKernels, b: Bounds, cfg: LMSettings, pop_size: int
) -> Any:
    """A :class:`SearchState` for ``pop_size`` starts per generation."""
    return _search_state(t, g, ks, b, cfg, make_search_work(t, g, pop_size))


@numba.njit(cache=True)
def _search_state(
    t: TreeArrays, g: GoalTable, ks: GoalKernels, b: Bounds, cfg: LMSettings, sw: SearchWork
) -> Any:  # pragma: no cover - compiled
    """The :class:`SearchState` of its parts (compiled and cached: the proxy's own
    constructor would compile in every process)."""
    return SearchState(t, g, ks, b, cfg, sw)


def typed_settings(cfg: LMSettings) -> LMSettings:
    """``cfg`` with each field of the type the compiled kernels are typed for (a Python
    ``int`` given for a float setting would make numba compile another version)."""
    return LMSettings(
        int(cfg.max_iters), float(cfg.lam0), float(cfg.max_step), float(cfg.stall_rel),
        int(cfg.stall_iters), float(cfg.tol_margin),
    )  # fmt: skip
