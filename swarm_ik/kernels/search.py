"""The whole ``swarm`` search in one compiled call: starts, grey-wolf proposals, LM polish,
stop test, clipping and the time check.

:func:`swarm_search` is the compiled twin of the Python loop of
:func:`swarm_ik.solvers.hybrid.run` (``prefer="best"``, stopping at success, one primary goal
and no secondary goal): generation 0 polishes the seed and then ``pop_size − 1`` uniform
starts, one after the other, until one converges; the polished points that did not converge
form an archive of local minima (best first, ``pop_size`` kept); each later generation
polishes ``n_swarm`` grey-wolf moves of the archive ([GWO] eqs. 3.3–3.7, :func:`gwo_move_into`,
the twin of :func:`swarm_ik.solvers.gwo.gwo_move`) and uniform starts for the rest.  The polish
is :func:`swarm_ik.kernels.lm.lm_run` (on a workspace made once per search, or once per
:class:`swarm_ik.IKSolver`: :class:`SearchWork`).

Randomness is a counter-based stream: uniform number ``c`` of a run is
``splitmix64(key + c) >> 11 · 2⁻⁵³`` (SplitMix64: Steele, Lea & Flood, OOPSLA 2014), with
``key`` one ``uint64`` drawn from the caller's ``numpy`` Generator (:func:`stream_key`), so the
same seed gives the same result.

The clock: numba has none.  :func:`now` calls ``clock_gettime(CLOCK_MONOTONIC)`` of the C
library (the clock behind ``time.perf_counter`` on Linux) as a numba ``ExternalFunction``,
which caches (``cache=True``) and costs ≈ 0.03–0.1 µs; the ``objmode`` fallback (used off
Linux) costs ≈ 2 µs.  The search reads it once per polish call (about once per generation).

Argument passing: numba types a ``NamedTuple`` argument in Python on every call (≈ 4–8 µs for
the tree, goal table, bounds and settings on the project machine), a flat run of arrays and
scalars in C (≈ 1–2 µs).  :func:`flat_args` flattens the structures once and
:func:`swarm_search_flat` rebuilds them inside the compiled code; the structures stay opaque
(their field counts are read off the classes).  :class:`swarm_ik.IKSolver`, called many times
with the same structures, goes further: they live in a :class:`PoseSolver` (a numba
``StructRef``, made once), and :func:`solve_pose` takes it, the target, the start and an
output buffer, and returns no new array — with cold caches, between other libraries' calls,
that entry costs ≈ 10 µs where the fifty flat arguments and a returned history cost ≈ 27 µs.
"""

from __future__ import annotations

import math
import sys
import time
from typing import Any, NamedTuple

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.core.imputils import impl_ret_borrowed
from numba.experimental import structref
from numba.extending import intrinsic

from swarm_ik._types import BoolArray, FloatArray, IntArray
from swarm_ik.kernels import hot, leaf, lm
from swarm_ik.kernels.fk import TreeArrays
from swarm_ik.kernels.lm import BUDGET, CONVERGED, Bounds, GoalTable, LMSettings
from swarm_ik.pose import clearly_pose

__all__ = [
    "POSE_SOLVER_FIELDS",
    "PoseSolver",
    "SearchWork",
    "entry_point",
    "flat_args",
    "pose_solver",
    "gwo_move_into",
    "grown",
    "make_search_work",
    "packed",
    "run_search",
    "now",
    "pose_errors_one",
    "pose_ok",
    "seed_key",
    "solve_pose",
    "splitmix64",
    "start_inside",
    "stream_key",
    "swarm_search",
    "swarm_search_flat",
    "typed_settings",
    "uniforms",
    "warm_up",
]

N_TREE = len(TreeArrays._fields)
N_TABLE = len(GoalTable._fields)
N_BOUNDS = len(Bounds._fields)
N_CFG = len(LMSettings._fields)
_E_TREE = N_TREE
_E_TABLE = _E_TREE + N_TABLE
_E_BOUNDS = _E_TABLE + N_BOUNDS
_E_CFG = _E_BOUNDS + N_CFG
N_STATIC = _E_CFG
"""Number of flat arguments that carry the tree, goal table, bounds and settings."""

NO_LIMIT = -1.0
"""``time_limit`` value meaning "no time limit"."""


# --------------------------------------------------------------------------- clock
_CLOCK_MONOTONIC = 1  # Linux


@intrinsic
def _clock_monotonic(typingctx: Any) -> Any:  # pragma: no cover - compiled
    """``clock_gettime(CLOCK_MONOTONIC)`` of libc in seconds, its ``struct timespec`` on the
    stack (no allocation: callable from the kernels compiled without numba's runtime)."""

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        i32, i64 = ir.IntType(32), ir.IntType(64)
        ts = cgutils.alloca_once(builder, ir.ArrayType(i64, 2))  # {tv_sec, tv_nsec}
        fnty = ir.FunctionType(i32, [i32, ir.IntType(8).as_pointer()])
        fn = cgutils.get_or_insert_function(builder.module, fnty, "clock_gettime")
        builder.call(fn, [ir.Constant(i32, _CLOCK_MONOTONIC), builder.bitcast(ts, fnty.args[1])])
        sec = builder.load(builder.gep(ts, [ir.Constant(i32, 0), ir.Constant(i32, 0)]))
        nsec = builder.load(builder.gep(ts, [ir.Constant(i32, 0), ir.Constant(i32, 1)]))
        f64 = ir.DoubleType()
        return builder.fadd(
            builder.sitofp(sec, f64),
            builder.fmul(builder.sitofp(nsec, f64), ir.Constant(f64, 1e-9)),
        )

    return types.float64(), codegen


@leaf
def _now_libc() -> float:  # pragma: no cover - compiled
    return _clock_monotonic()  # type: ignore[call-arg,no-any-return]


@numba.njit(cache=True)
def _now_objmode() -> float:  # pragma: no cover - compiled
    with numba.objmode(t="float64"):
        t = time.perf_counter()
    return t


_LINUX = sys.platform.startswith("linux")
now = _now_libc if _LINUX else _now_objmode
"""Seconds of the clock of ``time.perf_counter`` (compiled; usable inside ``njit`` code; on
Linux also inside the kernels compiled without numba's runtime)."""

_search_kernel: Any = hot if _LINUX else numba.njit(cache=True)
"""The decorator of :func:`swarm_search`: a :data:`~swarm_ik.kernels.hot` leaf (no reference
counting, inlined into its callers) where :func:`now` allocates nothing (Linux); elsewhere
the clock goes through object mode, which needs numba's runtime."""

_pose_kernel: Any = leaf if _LINUX else numba.njit(cache=True)
"""The decorator of :func:`pose_search`: a leaf where :func:`swarm_search` compiles without
numba's runtime (Linux)."""


# --------------------------------------------------------------------------- randomness
@leaf
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
def _uniform(key: np.uint64, c: np.uint64) -> float:  # pragma: no cover - compiled
    return float(splitmix64(key + c) >> np.uint64(11)) * (2.0**-53)


@numba.njit(cache=True)
def uniforms(key: np.uint64, first: int, n: int) -> FloatArray:  # pragma: no cover
    """Uniforms ``first + 1 … first + n`` of the stream ``key`` in ``[0, 1)`` (tests, tools)."""
    out = np.empty(n)
    for c in range(n):
        out[c] = _uniform(key, np.uint64(first + c + 1))
    return out


def stream_key(rng: np.random.Generator) -> np.uint64:
    """The ``uint64`` key of a search's random stream, one draw from ``rng``."""
    return np.uint64(rng.integers(0, 2**64, dtype=np.uint64))


_M32 = np.uint64(0xFFFFFFFF)


@leaf
def _mul128(ah: Any, al: Any, bh: Any, bl: Any) -> tuple[Any, Any]:  # pragma: no cover
    """``(ah·2⁶⁴ + al)·(bh·2⁶⁴ + bl) mod 2¹²⁸`` as ``(high, low)`` words (uint64 each)."""
    s32 = np.uint64(32)
    a0, a1 = al & _M32, al >> s32
    b0, b1 = bl & _M32, bl >> s32
    p00 = a0 * b0
    p01 = a0 * b1
    p10 = a1 * b0
    mid = (p00 >> s32) + (p01 & _M32) + (p10 & _M32)
    hi = a1 * b1 + (p01 >> s32) + (p10 >> s32) + (mid >> s32)  # high word of al·bl
    return hi + ah * bl + al * bh, al * bl


@leaf
def _add128(ah: Any, al: Any, bh: Any, bl: Any) -> tuple[Any, Any]:  # pragma: no cover
    """``(ah·2⁶⁴ + al) + (bh·2⁶⁴ + bl) mod 2¹²⁸`` as ``(high, low)`` words (uint64 each)."""
    lo = al + bl
    return ah + bh + (np.uint64(1) if lo < al else np.uint64(0)), lo


@leaf
def _hashmix(
    value: np.uint64, h: np.uint64, mult: np.uint64
) -> tuple[Any, Any]:  # pragma: no cover
    """numpy ``SeedSequence``'s ``hashmix`` of ``value`` with the hash constant ``h``:
    ``(mixed, next h)``."""
    v = value ^ h
    h = (h * mult) & _M32
    v = (v * h) & _M32
    return v ^ (v >> np.uint64(16)), h


@leaf
def _mix(x: np.uint64, y: np.uint64) -> np.uint64:  # pragma: no cover - compiled
    """numpy ``SeedSequence``'s ``mix``."""
    r = (np.uint64(0xCA01F9DD) * x - np.uint64(0x4973F715) * y) & _M32
    return r ^ (r >> np.uint64(16))


@leaf
def seed_key(seed: int) -> np.uint64:  # pragma: no cover - compiled
    """``stream_key(numpy.random.default_rng(seed))`` for an integer ``0 <= seed < 2**63``,
    without making the Generator (≈ 10–16 µs in numpy; ≈ 0.1 µs here), in scalars (a leaf:
    :func:`swarm_search` computes it once its first polish has not ended the run, so a solve
    that converges from its first start never does).

    numpy's algorithms, step by step: ``SeedSequence(seed)`` (the integer as 32-bit words,
    ``mix_entropy`` into a pool of 4 with ``hashmix``/``mix``, ``generate_state(4, uint64)``),
    ``PCG64`` seeded with those words (``pcg_setseq_128_srandom_r``: state 0, increment
    ``2·seq + 1``, step, add the initial state, step), and one ``next64`` (step, XSL-RR
    output), which ``Generator.integers(0, 2**64, dtype=uint64)`` returns unchanged.  Equal to
    numpy on every seed tested (``tests/test_search.py``)."""
    u = np.uint64(seed)
    s32 = np.uint64(32)
    h, ma = np.uint64(0x43B0D7E5), np.uint64(0x931E8875)  # INIT_A, MULT_A
    zero = np.uint64(0)
    # mix_entropy: the seed's two 32-bit words (a high word of 0 is as no word), into 4
    p0, h = _hashmix(u & _M32, h, ma)
    p1, h = _hashmix(u >> s32, h, ma)
    p2, h = _hashmix(zero, h, ma)
    p3, h = _hashmix(zero, h, ma)
    # every source into every other entry of the pool, in numpy's order (src, then dst)
    v, h = _hashmix(p0, h, ma)
    p1 = _mix(p1, v)
    v, h = _hashmix(p0, h, ma)
    p2 = _mix(p2, v)
    v, h = _hashmix(p0, h, ma)
    p3 = _mix(p3, v)
    v, h = _hashmix(p1, h, ma)
    p0 = _mix(p0, v)
    v, h = _hashmix(p1, h, ma)
    p2 = _mix(p2, v)
    v, h = _hashmix(p1, h, ma)
    p3 = _mix(p3, v)
    v, h = _hashmix(p2, h, ma)
    p0 = _mix(p0, v)
    v, h = _hashmix(p2, h, ma)
    p1 = _mix(p1, v)
    v, h = _hashmix(p2, h, ma)
    p3 = _mix(p3, v)
    v, h = _hashmix(p3, h, ma)
    p0 = _mix(p0, v)
    v, h = _hashmix(p3, h, ma)
    p1 = _mix(p1, v)
    v, h = _hashmix(p3, h, ma)
    p2 = _mix(p2, v)
    # generate_state(4, uint64): eight 32-bit words from the pool, in turn
    hb, mb = np.uint64(0x8B51F9DD), np.uint64(0x58F38DED)  # INIT_B, MULT_B
    s0, hb = _hashmix(p0, hb, mb)
    s1, hb = _hashmix(p1, hb, mb)
    s2, hb = _hashmix(p2, hb, mb)
    s3, hb = _hashmix(p3, hb, mb)
    s4, hb = _hashmix(p0, hb, mb)
    s5, hb = _hashmix(p1, hb, mb)
    s6, hb = _hashmix(p2, hb, mb)
    s7, hb = _hashmix(p3, hb, mb)
    init_h, init_l = s0 | (s1 << s32), s2 | (s3 << s32)
    seq_h, seq_l = s4 | (s5 << s32), s6 | (s7 << s32)
    inc_h = (seq_h << np.uint64(1)) | (seq_l >> np.uint64(63))
    inc_l = (seq_l << np.uint64(1)) | np.uint64(1)
    mul_h, mul_l = np.uint64(0x2360ED051FC65DA4), np.uint64(0x4385DF649FCCF645)
    sh, sl = inc_h, inc_l  # state 0, one step: 0·mul + inc
    sh, sl = _add128(sh, sl, init_h, init_l)
    sh, sl = _mul128(sh, sl, mul_h, mul_l)
    sh, sl = _add128(sh, sl, inc_h, inc_l)
    sh, sl = _mul128(sh, sl, mul_h, mul_l)  # next64: one more step…
    sh, sl = _add128(sh, sl, inc_h, inc_l)
    x = sh ^ sl  # …and the XSL-RR output
    rot = sh >> np.uint64(58)
    return (x >> rot) | (x << ((np.uint64(64) - rot) & np.uint64(63)))


# --------------------------------------------------------------------------- grey wolf
@leaf
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


@leaf
def _clip_row(q: FloatArray, b: Bounds) -> None:  # pragma: no cover - compiled
    """Continuous joints wrapped into ``[-π, π)``, then clipped to the bounds (in place; the
    twin of :meth:`swarm_ik.solvers.base.Evaluator.clip`)."""
    for j in range(q.shape[0]):
        q[j] = lm.into_bounds(q[j], j, b)


# --------------------------------------------------------------------------- the search
@leaf
def _offer(
    q: FloatArray, f: float, dp: float, dr: float, ev_q: FloatArray
) -> tuple[float, float, float]:  # pragma: no cover - compiled
    """Offer the best point ``q`` (fitness, errors) to the evaluator's best ``ev_q`` (copied
    in); returns the evaluator's new fitness and errors."""
    for j in range(q.shape[0]):
        ev_q[j] = q[j]
    return f, dp, dr


@numba.njit(cache=True)
def grown(hist: FloatArray, n: int) -> FloatArray:  # pragma: no cover - compiled
    """A copy of ``hist``'s first ``n`` entries in a buffer twice as long."""
    bigger = np.empty(max(2 * hist.shape[0], n + 1, 1))
    bigger[:n] = hist[:n]
    return bigger


SEARCH_DONE = 0
"""Code of :func:`swarm_search`: the run ended."""
SEARCH_PAUSED = 1
"""Code of :func:`swarm_search`: the history buffer is full (call again with a longer one and
``resume=True``)."""


@numba.njit(cache=True, inline="always")
def run_search(
    t: TreeArrays,
    g: GoalTable,
    b: Bounds,
    cfg: LMSettings,
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
    sw: SearchWork,
) -> tuple[int, float, float, float, bool, FloatArray, int]:  # pragma: no cover - compiled
    """:func:`swarm_search` run to its end, the history grown whenever it fills (inlined
    into its callers, so the structures are not passed through one more call).

    Returns:
        ``(evaluations, fitness, dp, dr, stopped, history, n_history)``: as
        :func:`swarm_search`, with the best fitness after each generation in
        ``history[:n_history]`` (``sw.hist``, or a longer array it grew into).
    """
    hist = sw.hist
    resume = False
    while True:
        code, used, fit, dp, dr, stopped, n_hist, last = swarm_search(
            t, g, b, cfg, seed_q, kernel_tol_pos, kernel_tol_rot, tol_pos, tol_rot, w_rot,
            pop_size, n_swarm, iterations, unlimited, max_evals, budget_total, evals_before,
            time_limit, t0, key, -1, out_q, sw, hist, resume,
        )  # fmt: skip
        if code == SEARCH_DONE:
            break
        hist = grown(hist, n_hist)
        resume = True
    if last:
        if n_hist == hist.shape[0]:
            hist = grown(hist, n_hist)
        hist[n_hist] = fit
        n_hist += 1
    return used, fit, dp, dr, stopped, hist, n_hist


@leaf
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
    :func:`make_search_work` (per call by :func:`swarm_search_flat`; once per
    :class:`swarm_ik.IKSolver`, in its :class:`PoseSolver`, so that a call allocates nothing:
    about 40 allocations, ≈ 6 µs of a call with cold caches).  Each call sets what it reads
    before reading it, so a reused scratch gives the results of a new one."""

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
    hist: FloatArray
    """The history (64 entries; a longer history grows into a new array)."""
    par: FloatArray
    """The goal parameters of a :func:`solve_pose` call, ``g.par``'s shape."""
    state_i: IntArray
    """The integer state of a paused :func:`swarm_search` (9 entries); ``state_f``: its
    float state (7)."""
    state_f: FloatArray
    lm_work: lm.Work
    """The scratch of :func:`swarm_ik.kernels.lm.lm_run`."""


@numba.njit(cache=True)
def make_search_work(
    t: TreeArrays, g: GoalTable, pop_size: int
) -> SearchWork:  # pragma: no cover - compiled
    """The :class:`SearchWork` of :func:`swarm_search` for ``pop_size`` starts per
    generation."""
    n = t.nq
    rows = max(pop_size, 1)
    pq, pdp, pdr, pst, pev = lm.polish_outputs(rows, n)
    return SearchWork(
        np.empty((rows, n)), pq, pdp, pdr, pst, pev, np.empty((2 * rows, n)),
        np.empty(2 * rows), np.empty((3, n)), np.empty((3, rows, n)), np.empty((3, rows, n)),
        np.empty((rows, n)), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n),
        np.empty(64), np.empty_like(g.par), np.zeros(9, dtype=np.int64), np.zeros(7),
        lm.make_work(t, g, g.rows_primary),
    )  # fmt: skip


@_search_kernel
def swarm_search(
    t: TreeArrays,
    g: GoalTable,
    b: Bounds,
    cfg: LMSettings,
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
    seed: int,
    out_q: FloatArray,
    sw: SearchWork,
    hist: FloatArray,
    resume: bool,
) -> tuple[int, int, float, float, float, bool, int, bool]:  # pragma: no cover - compiled
    """The memetic search of the ``swarm`` solver (see the module docstring).

    Args:
        t, g, b, cfg: Tree, goal table (one primary goal, no secondary), bounds, LM settings.
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
        time_limit: Seconds since ``t0`` after which no polish starts (``NO_LIMIT``: none).
        t0: Start of the solve on the clock of :func:`now` [s].
        key: Random stream key (:func:`stream_key`); with ``seed >= 0`` not read.
        seed: ``-1``, or an integer seed whose key (:func:`seed_key`) this computes once its
            first polish has not ended the run (a solve that converges from its first start
            never computes it).
        out_q: The answer (lowest fitness seen), ``(nq,)``.
        sw: Scratch (:func:`make_search_work` for ``pop_size``).
        hist: The history's buffer (``sw.hist`` from :func:`run_search`; the tail of the
            output buffer from :func:`solve_pose`).
        resume: Continue the run that returned :data:`SEARCH_PAUSED` (its state is in
            ``sw``; ``hist``: a longer copy of the full buffer, :func:`grown`).

    Compiled without reference counting (a leaf: its callers own every array), so it cannot
    allocate: when a generation ends with ``hist`` full it saves its state in ``sw`` and
    returns :data:`SEARCH_PAUSED`; the caller calls again with a longer copy of ``hist`` and
    ``resume=True`` (:func:`run_search` is that loop for the callers with a
    :class:`SearchWork` history; :func:`solve_pose` has its own, over its output buffer).

    Returns:
        ``(code, evaluations, fitness, dp, dr, stopped, n_history, last_pending)``:
        :data:`SEARCH_DONE` or :data:`SEARCH_PAUSED`; evaluations used, the answer's fitness,
        its position [m] and angular [rad] errors, whether the stop test ended the run, the
        entries of ``hist`` written (the best fitness after each generation) and whether the
        caller appends the fitness as the last entry (an open generation, or none ended).
    """
    n = seed_q.shape[0]
    m = pop_size
    rows = max(m, 1)
    queue, pq, pdp, pdr, pst, pev = sw.queue, sw.pq, sw.pdp, sw.pdr, sw.pst, sw.pev
    arch_x, arch_f, tmp_x, lead, r1, r2 = sw.arch_x, sw.arch_f, sw.tmp_x, sw.lead, sw.r1, sw.r2
    moved, work, si, sf = sw.moved, sw.lm_work, sw.state_i, sw.state_f
    if queue.shape[0] < rows or queue.shape[1] != n:
        raise ValueError("swarm_search: scratch made for fewer starts or another robot")
    best_q = sw.best_q  # lowest fitness seen (not yet offered to the stop test)
    ev_q = sw.ev_q  # the evaluator's best (what the stop test has seen)
    lo, hi = sw.lo, sw.hi  # random starts: uniform in the sampling window
    has_time = time_limit >= 0.0
    stream = np.uint64(key)  # (one type whether the key came typed uint64 or int64)
    if resume:  # the state saved when the history filled (below)
        n_hist, n_arch, n_queue, used, gen = si[0], si[1], si[2], si[3], si[4]
        counter = np.uint64(si[5])
        stopped, gen0_rest, open_gen = si[6] != 0, si[7] != 0, si[8] != 0
        best_f, best_dp, best_dr, ev_f, ev_dp, ev_dr = sf[0], sf[1], sf[2], sf[3], sf[4], sf[5]
        sec_per_eval = sf[6]
    else:
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
        counter = np.uint64(0)
        sampling_window(b.lower, b.upper, seed_q, lo, hi)
    while True:
        if resume:  # straight to the end of the generation that filled the history
            resume = False
        else:
            if stopped or used >= max_evals:
                break
            t_call = now()
            if has_time and t_call - t0 >= time_limit:
                break
            if unlimited and gen >= iterations:
                break
            cap = max_evals - used
            if has_time:
                left = time_limit - (t_call - t0)
                cap = min(cap, max(8, int(0.8 * left / sec_per_eval)))
            u = lm.lm_run(
                queue[:n_queue], t, g, b, cfg, kernel_tol_pos, kernel_tol_rot, cap, True,
                pq[:n_queue], pdp[:n_queue], pdr[:n_queue], pst[:n_queue], pev[:n_queue], work,
            )  # fmt: skip
            if u > 0 and has_time:
                sec_per_eval = 0.5 * sec_per_eval + 0.5 * (now() - t_call) / u
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
                if seed >= 0:  # the key, at the first draw
                    stream, seed = seed_key(seed), -1
                for s in range(m - 1):
                    for j in range(n):
                        counter += np.uint64(1)
                        queue[s, j] = min(
                            lo[j] + (hi[j] - lo[j]) * _uniform(stream, counter), hi[j]
                        )
                n_queue = m - 1
                continue
            if n_queue != 0:
                continue
            if best_f < np.inf and best_f < ev_f:
                ev_f, ev_dp, ev_dr = _offer(best_q, best_f, best_dp, best_dr, ev_q)
                stopped = ev_dp <= tol_pos and ev_dr <= tol_rot
            if n_hist == hist.shape[0]:  # full: saved, grown by the caller, resumed here
                si[0], si[1], si[2], si[3], si[4] = n_hist, n_arch, n_queue, used, gen
                si[5] = np.int64(counter)
                si[6], si[7], si[8] = stopped, gen0_rest, open_gen
                sf[0], sf[1], sf[2], sf[3] = best_f, best_dp, best_dr, ev_f
                sf[4], sf[5], sf[6] = ev_dp, ev_dr, sec_per_eval
                return SEARCH_PAUSED, used, ev_f, ev_dp, ev_dr, stopped, n_hist, False
        hist[n_hist] = ev_f
        n_hist += 1
        open_gen = False
        gen += 1
        frac = gen / max(iterations, 1)
        if budget_total > 0:
            frac = max(frac, (evals_before + used) / budget_total)
        a = 2.0 * max(0.0, 1.0 - frac)
        n_sw = min(n_swarm, m) if n_arch > 0 else 0
        if seed >= 0:
            stream, seed = seed_key(seed), -1
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
                            rr[L, s, j] = _uniform(stream, counter)
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
                queue[s, j] = min(lo[j] + (hi[j] - lo[j]) * _uniform(stream, counter), hi[j])
        n_queue = m
    if best_f < np.inf and best_f < ev_f and not stopped:
        ev_f, ev_dp, ev_dr = _offer(best_q, best_f, best_dp, best_dr, ev_q)
        stopped = ev_dp <= tol_pos and ev_dr <= tol_rot
    for j in range(n):
        out_q[j] = ev_q[j]
    return SEARCH_DONE, used, ev_f, ev_dp, ev_dr, stopped, n_hist, open_gen or n_hist == 0


@numba.njit(cache=True)
def swarm_search_flat(*a: Any) -> tuple[int, float, float, float, bool, FloatArray]:  # type: ignore[no-untyped-def]  # pragma: no cover
    """:func:`swarm_search` with the tree, goal table, bounds and settings given field by
    field (:func:`flat_args`): the cheap way to call it from Python."""
    t = TreeArrays(*a[0:_E_TREE])
    g = GoalTable(*a[_E_TREE:_E_TABLE])
    b = Bounds(*a[_E_TABLE:_E_BOUNDS])
    cfg = LMSettings(*a[_E_BOUNDS:_E_CFG])
    rest = a[_E_CFG:]
    used, fit, dp, dr, stopped, hist, n_hist = run_search(  # (inlined: no *args)
        t, g, b, cfg, rest[0], rest[1], rest[2], rest[3], rest[4], rest[5], rest[6], rest[7],
        rest[8], rest[9], rest[10], rest[11], rest[12], rest[13], rest[14], rest[15], rest[16],
        make_search_work(t, g, rest[6]),
    )  # fmt: skip
    return used, fit, dp, dr, stopped, hist[:n_hist].copy()


RAN = 0
"""Status of :func:`solve_pose`: the search ran."""
CHECK_TARGET = 1
"""Status of :func:`solve_pose`: the target needs :func:`swarm_ik.pose.as_pose`'s check."""
CHECK_START = 2
"""Status of :func:`solve_pose`: the start needs :func:`swarm_ik.api.prepare_q0`."""


@structref.register
class PoseSolverType(types.StructRef):
    """The numba type of a :class:`PoseSolver` (one per set of field types)."""

    def preprocess_fields(self, fields: Any) -> Any:
        return tuple((name, types.unliteral(typ)) for name, typ in fields)


class PoseSolver(structref.StructRefProxy):  # type: ignore[misc]
    """The compiled state of one :class:`swarm_ik.IKSolver`, made by :func:`pose_solver` and
    read by :func:`solve_pose`: the tree, the goal table (its one pose row the template that
    each call fills with its target), the bounds, the LM settings and the search settings
    (the arguments of :func:`swarm_search` from ``kernel_tol_pos`` to ``time_limit``),
    ``position_only``, the search's scratch ``work`` and the conversion of the answer to
    Pinocchio's configuration (``pin_index``, ``pin_affine``, ``nq_pin``: no rows and 0 where
    that configuration is ``q`` itself).

    One object where the flat arguments were about fifty: the compiled entry unboxes a pointer
    instead of some forty arrays (≈ 10 µs of a call with cold caches)."""


POSE_SOLVER_FIELDS = (
    "tree", "table", "bounds", "cfg", "kernel_tol_pos", "kernel_tol_rot", "tol_pos", "tol_rot",
    "w_rot", "pop_size", "n_swarm", "iterations", "unlimited", "max_evals", "budget_total",
    "evals_before", "time_limit", "position_only", "work", "pin_index", "pin_affine", "nq_pin",
)  # fmt: skip
"""The fields of :class:`PoseSolver`, in the order of its constructor."""

structref.define_proxy(PoseSolver, PoseSolverType, list(POSE_SOLVER_FIELDS))


@numba.njit(cache=True)
def _new_pose_solver(*a: Any) -> Any:  # type: ignore[no-untyped-def]  # pragma: no cover
    return PoseSolver(*a)


def pose_solver(
    t: TreeArrays,
    g: GoalTable,
    b: Bounds,
    cfg: LMSettings,
    search_args: tuple[Any, ...],
    position_only: bool,
    pin_plan: tuple[IntArray, FloatArray, int],
) -> PoseSolver:
    """A :class:`PoseSolver` (compiled constructor, loaded from numba's cache).

    Args:
        t, g, b, cfg: The structures (``g``: one pose row, its parameters the template's).
        search_args: The arguments of :func:`swarm_search` from ``kernel_tol_pos`` to
            ``time_limit`` (13 values).
        position_only: The pose row is a position row (its rotation is not set per call).
        pin_plan: The conversion of the answer to Pinocchio's configuration
            (:meth:`swarm_ik.robot.RobotModel.pinocchio_plan_arrays`; no rows where that
            configuration is ``q`` itself): :func:`solve_pose` writes it after ``q``.
    """
    kinds = (float, float, float, float, float, int, int, int, bool, int, int, int, float)
    if len(search_args) != len(kinds):
        raise ValueError(f"pose_solver: {len(kinds)} search arguments, got {len(search_args)}")
    typed = tuple(k(v) for k, v in zip(kinds, search_args, strict=True))
    t, g, b = packed((t, g, b))
    work = packed(make_search_work(t, g, typed[5]))  # (its scratch contiguous too)
    index, affine, nq_pin = pin_plan
    return _new_pose_solver(  # type: ignore[no-any-return]
        t, g, b, typed_settings(cfg), *typed, bool(position_only), work,
        np.ascontiguousarray(index, dtype=np.int64), np.ascontiguousarray(affine, dtype=float),
        int(nq_pin),
    )  # fmt: skip


def packed(structures: Any) -> Any:
    """``structures`` (tuples and named tuples of arrays, nested) with every array replaced by
    an equal copy that is a view of one buffer per dtype, in order: the data a compiled call
    reads lies in a few contiguous blocks instead of dozens of separate allocations (with
    cold caches, ≈ 1–2 µs less per :func:`solve_pose` call for the tree, goal table and
    bounds, 0.5–3 µs for the search's scratch; in-process A/Bs on Panda and UR10).  Each
    copy keeps its array's shape, dtype, C layout and writeability, so the compiled code's
    types do not change."""
    arrays: list[np.ndarray] = []

    def collect(x: Any) -> None:
        if isinstance(x, np.ndarray):
            arrays.append(x)
        elif isinstance(x, tuple):
            for y in x:
                collect(y)

    collect(structures)
    step = 8  # elements: each array starts on a 64-byte line for 8-byte dtypes
    sizes: dict[np.dtype[Any], int] = {}
    for a in arrays:
        sizes[a.dtype] = sizes.get(a.dtype, 0) + -(-a.size // step) * step
    base = {dt: np.empty(n, dtype=dt) for dt, n in sizes.items()}
    offset = dict.fromkeys(sizes, 0)

    def rebuild(x: Any) -> Any:
        if isinstance(x, np.ndarray):
            o = offset[x.dtype]
            view = base[x.dtype][o : o + x.size].reshape(x.shape)
            view[...] = x
            view.flags.writeable = x.flags.writeable
            offset[x.dtype] = o + -(-x.size // step) * step
            return view
        if isinstance(x, tuple):
            parts = [rebuild(y) for y in x]
            return type(x)(*parts) if hasattr(x, "_fields") else tuple(parts)
        return x

    return rebuild(structures)


_WORD_BITS = 64 if sys.maxsize > 2**32 else 32
_MEMINFO = ir.LiteralStructType(
    [ir.IntType(_WORD_BITS), ir.IntType(8).as_pointer(), ir.IntType(8).as_pointer(),
     ir.IntType(8).as_pointer(), ir.IntType(_WORD_BITS)]
)  # fmt: skip
"""Layout of numba's ``NRT_MemInfo`` (``refct``, ``dtor``, ``dtor_info``, ``data``, ``size``;
``numba.core.runtime.nrtdynmod``)."""


def _borrowed(typingctx: Any, struct: Any, name: Any) -> Any:  # pragma: no cover - compiled
    """``struct.name`` of a numba ``StructRef`` (``name`` a string constant), readable where
    numba's runtime is off: what a :data:`~swarm_ik.kernels.leaf` reads its fields with
    (numba's own attribute access asks the runtime for the payload and increments each
    array's reference count, which a leaf cannot do; its caller holds the structure, so the
    fields stay alive).  Compiled with the runtime on (``pose_search`` off Linux), the value
    is returned with a reference, as numba's own access returns it."""
    if not isinstance(struct, types.StructRef) or not isinstance(name, types.StringLiteral):
        return None
    attr = name.literal_value
    if attr not in struct.field_dict:
        return None

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        # numba's getattr of a StructRef, without asking the runtime for the payload: its
        # pointer read off the MemInfo (field 3, as NRT_MemInfo_data_fast does)
        meminfo = cgutils.create_struct_proxy(struct)(context, builder, value=args[0]).meminfo
        info = builder.bitcast(meminfo, _MEMINFO.as_pointer())
        data_type = struct.get_data_type()
        data = builder.bitcast(
            builder.load(cgutils.gep(builder, info, 0, 3)),
            context.data_model_manager[data_type].get_value_type().as_pointer(),
        )
        payload = cgutils.create_struct_proxy(data_type)(context, builder, ref=data)
        # a reference for the caller where it counts them (numba's runtime on: it releases
        # what a call returns); nothing in a leaf
        return impl_ret_borrowed(context, builder, signature.return_type, getattr(payload, attr))

    return struct.field_dict[attr](struct, name), codegen


borrowed: Any = intrinsic(prefer_literal=True)(_borrowed)
"""``borrowed(struct, "name")`` in compiled code (:func:`_borrowed`)."""


@leaf
def pinocchio_config(
    q: FloatArray, index: IntArray, affine: FloatArray, out: FloatArray
) -> None:  # pragma: no cover - compiled
    """Pinocchio's configuration of ``q`` into ``out`` by the plan of
    :meth:`swarm_ik.robot.RobotModel.pinocchio_plan_arrays` (``index`` ``(k, 3)``, ``affine``
    ``(k, 2)``): each joint's value ``multiplier · q[i] + offset``, a continuous joint's as
    (cos, sin); the compiled twin of :meth:`~swarm_ik.robot.RobotModel.to_pinocchio`."""
    for k in range(index.shape[0]):
        v = affine[k, 0] * q[index[k, 0]] + affine[k, 1]
        at = index[k, 1]
        if index[k, 2] != 0:
            out[at] = math.cos(v)
            out[at + 1] = math.sin(v)
        else:
            out[at] = v


@_pose_kernel
def pose_search(
    s: Any,
    target: FloatArray,
    q_start: FloatArray,
    target_checked: bool,
    start_checked: bool,
    t0: float,
    seed: int,
    out_q: FloatArray,
    q_pin: FloatArray,
    hist: FloatArray,
    resume: bool,
) -> tuple[int, int, int, float, int, bool]:  # pragma: no cover - compiled
    """The body of :func:`solve_pose`: the checks, the goal row of the target and
    :func:`swarm_search` (one run, or its resumption with a longer ``hist``).

    A leaf: it reads the :class:`PoseSolver`'s fields without numba's reference counting.
    In :func:`solve_pose` itself every array field read off the structure and passed on was
    an atomic increment and decrement of that array's count (about 90 of each per call,
    on some sixty separate counters: cache misses when the caches are cold).

    Returns:
        ``(status, code, evaluations, fitness, n_history, last_pending)``: ``status`` as
        :func:`solve_pose`'s; the rest as :func:`swarm_search`'s (``code``: :data:`SEARCH_DONE`
        or :data:`SEARCH_PAUSED`).
    """
    b = borrowed(s, "bounds")
    work = borrowed(s, "work")
    table = borrowed(s, "table")
    par = work.par
    if not resume:
        if not target_checked and not pose_ok(target, 1e-6):
            return CHECK_TARGET, SEARCH_DONE, 0, np.inf, 0, False
        if not start_checked and not start_inside(q_start, b.lower, b.upper, b.wrap):
            return CHECK_START, SEARCH_DONE, 0, np.inf, 0, False
        p0 = table.par
        for r in range(par.shape[0]):
            for c in range(par.shape[1]):
                par[r, c] = p0[r, c]
        if not borrowed(s, "position_only"):
            for r in range(3):
                for c in range(3):
                    par[0, 3 * r + c] = target[r, c]
        for r in range(3):
            par[0, 9 + r] = target[r, 3]
    g0 = table
    g = GoalTable(  # (every field of GoalTable, in order: a test checks the list)
        g0.code, g0.frame, g0.weight, g0.primary, par, g0.jref, g0.jw, g0.row0, g0.nrows,
        g0.rows_primary, g0.rows_secondary, g0.col,
    )  # fmt: skip
    code, used, fit, _dp, _dr, _stopped, n, last = swarm_search(
        borrowed(s, "tree"), g, b, borrowed(s, "cfg"), q_start,
        borrowed(s, "kernel_tol_pos"), borrowed(s, "kernel_tol_rot"),
        borrowed(s, "tol_pos"), borrowed(s, "tol_rot"), borrowed(s, "w_rot"),
        borrowed(s, "pop_size"), borrowed(s, "n_swarm"), borrowed(s, "iterations"),
        borrowed(s, "unlimited"), borrowed(s, "max_evals"), borrowed(s, "budget_total"),
        borrowed(s, "evals_before"), borrowed(s, "time_limit"), t0, np.uint64(0), seed, out_q,
        work, hist, resume,
    )  # fmt: skip
    if code == SEARCH_DONE:  # the answer's Pinocchio configuration, where it is not q
        pinocchio_config(out_q, borrowed(s, "pin_index"), borrowed(s, "pin_affine"), q_pin)
    return RAN, code, used, fit, n, last


@numba.njit(cache=True)
def solve_pose(
    s: Any,
    target: FloatArray,
    q_start: FloatArray,
    target_checked: bool,
    start_checked: bool,
    t0: float,
    seed: int,
    out: FloatArray,
) -> tuple[int, int, float, int, FloatArray | None]:  # pragma: no cover - compiled
    """One :class:`swarm_ik.IKSolver` call of a 4×4 target in one compiled call: the checks of
    the target (:func:`pose_ok`) and of the start (:func:`start_inside`), the goal row of the
    target and :func:`swarm_search` (its random key made from the integer seed when it first
    draws), in the leaf :func:`pose_search`.

    Args:
        s: The :class:`PoseSolver`.
        target: The pose, ``(4, 4)``.
        q_start: The first start, ``(nq,)``.
        target_checked, start_checked: Already checked in Python (else checked here).
        t0: Start of the solve, ``time.perf_counter()`` [s].
        seed: The integer seed.
        out: ``(nq + nq_pin + cap,)``: receives the answer ``q`` in its first ``nq``
            entries, its Pinocchio configuration in the next ``nq_pin`` (the
            :class:`PoseSolver`'s; 0 where that configuration is ``q`` itself) and the
            history after them when it fits in ``cap`` entries.

    Compiled without ``nogil``: the call holds the GIL, so threads sharing one
    :class:`PoseSolver` take turns with its scratch (``s.work``).

    Returns:
        ``(status, evaluations, fitness, n_history, history)``: ``history`` is None when it
        was written to ``out`` (a returned array costs ≈ 8 µs to box with cold caches), else
        the whole history.  ``status`` is :data:`RAN`, or :data:`CHECK_TARGET` /
        :data:`CHECK_START` when an unchecked target or start did not pass (nothing ran: the
        caller checks it in Python, which raises or fixes it, and calls again with it marked
        checked).
    """
    nq = q_start.shape[0]
    nq_pin = borrowed(s, "nq_pin")
    out_q = out[:nq]
    q_pin = out[nq : nq + nq_pin]
    hist = out[nq + nq_pin :]  # the history is written into out until it fills
    grew = False
    resume = False  # (one call site, its flags variables: one compiled pose_search)
    while True:
        status, code, used, fit, n, last = pose_search(
            s, target, q_start, target_checked or resume, start_checked or resume, t0, seed,
            out_q, q_pin, hist, resume,
        )  # fmt: skip
        if status != RAN:
            return status, 0, np.inf, 0, None
        if code != SEARCH_PAUSED:
            break
        hist = grown(hist, n)  # full: a longer copy, and the run resumed
        grew = resume = True
    if last:
        if n == hist.shape[0]:
            hist = grown(hist, n)
            grew = True
        hist[n] = fit
        n += 1
    if grew:
        return RAN, used, fit, n, hist[:n]
    return RAN, used, fit, n, None


def entry_point(kernel: Any, args: tuple[Any, ...]) -> Any:
    """A callable ``f(*args)`` running the compiled ``kernel`` (:func:`solve_pose`,
    :func:`pose_errors_one`) on arguments of the types of ``args`` without the dispatcher's
    typing of each argument: numba's compiled entry point for exactly those types (compiled
    or loaded first if needed; ≈ 2 µs less per call with cold caches, 8 µs for a
    :class:`PoseSolver`).  Callers must pass arguments of those same types (arrays of the
    same dtype, dimensions and layout), as :class:`swarm_ik.IKSolver` does.  Without one
    (another numba's internals), the dispatcher itself."""
    kernel(*args)  # compiled (or loaded) for these types
    try:
        sig = tuple(numba.typeof(a) for a in args)
        return kernel.overloads[sig].entry_point
    except (AttributeError, KeyError, TypeError):  # pragma: no cover - numba internals moved
        return kernel


def typed_settings(cfg: LMSettings) -> LMSettings:
    """``cfg`` with each field of the type the compiled kernels are typed for (a Python
    ``int`` given for a float setting would make numba compile another version)."""
    return LMSettings(
        int(cfg.max_iters), float(cfg.lam0), float(cfg.max_step), float(cfg.stall_rel),
        int(cfg.stall_iters), float(cfg.tol_margin),
    )  # fmt: skip


def flat_args(t: TreeArrays, g: GoalTable, b: Bounds, cfg: LMSettings) -> list[Any]:
    """The structures as the flat argument list of :func:`swarm_search_flat` (its first
    :data:`N_STATIC` entries)."""
    return [*t, *g, *b, *typed_settings(cfg)]


def warm_up(t: TreeArrays, g: GoalTable, b: Bounds) -> None:
    """Compile (or load from numba's cache) :func:`swarm_search_flat` for these types, outside
    any timed solve (called by :func:`swarm_ik.kernels.lm.warm_up`), :func:`pose_errors_one`
    (the check of the answer) and :func:`seed_key` (called from Python by
    :func:`swarm_ik.solvers.hybrid.search_key`).  Each cached kernel costs ≈ 10–70 ms to
    load, so the rest load where they are used: :func:`solve_pose` (with
    :func:`pose_ok` and :func:`start_inside` compiled into it) when an
    :class:`swarm_ik.IKSolver` is made, the test helpers (:func:`gwo_move_into` on its own,
    :func:`uniforms`) on first use."""
    nq = t.nq
    seed = np.ascontiguousarray(0.5 * (b.lower + b.upper))
    static = flat_args(t, g, b, lm.DEFAULT_LM)
    out = np.empty(nq)
    swarm_search_flat(
        *static, seed, 1e-5, 1e-5, 1e-5, 1e-5, 1.0, 2, 1, 1, False, 3, 3, 0, 1.0, now(),
        np.uint64(1), out,
    )  # fmt: skip
    eye = np.eye(4)
    pose_errors_one(eye, eye, seed, b.lower, b.upper)  # the check of solve's answer
    seed_key(0)  # the random key of an integer seed


# --------------------------------------------------------------------------- per-call checks
@leaf
def start_inside(
    q: FloatArray, lower: FloatArray, upper: FloatArray, wrap: BoolArray
) -> bool:  # pragma: no cover - compiled
    """Whether the start ``q`` ``(nq,)`` is finite, inside ``[lower, upper]`` and, on the
    continuous joints (``wrap``), a fixed point of the wrap into ``[-π, π)``: then
    :func:`swarm_ik.api.prepare_q0` would return it unchanged, and it is used as it is."""
    for j in range(q.shape[0]):
        v = q[j]
        if not (lower[j] <= v <= upper[j]):  # False for NaN
            return False
        if wrap[j] and (v + math.pi) % (2.0 * math.pi) - math.pi != v:
            return False  # RobotModel.wrap would move it (by round-off at least)
    return True


_clearly_pose = leaf(clearly_pose)


@leaf
def pose_ok(m: FloatArray, orth_tol: float) -> bool:  # pragma: no cover - compiled
    """Whether the ``(4, 4)`` matrix ``m`` passes :func:`swarm_ik.pose.as_pose`'s checks
    with a margin: :func:`swarm_ik.pose.clearly_pose` compiled.  False means "let
    ``as_pose`` judge" (it raises the error, naming the fault, or accepts a borderline
    matrix)."""
    return _clearly_pose(
        orth_tol, m[0, 0], m[0, 1], m[0, 2], m[0, 3], m[1, 0], m[1, 1], m[1, 2], m[1, 3],
        m[2, 0], m[2, 1], m[2, 2], m[2, 3], m[3, 0], m[3, 1], m[3, 2], m[3, 3],
    )  # fmt: skip


@hot
def _rtr(target: FloatArray, reached: FloatArray, a: int, c: int) -> float:  # pragma: no cover
    """Entry ``(a, c)`` of ``R*ᵀR`` of two poses ``(4, 4)``."""
    return (
        target[0, a] * reached[0, c] + target[1, a] * reached[1, c] + (target[2, a] * reached[2, c])
    )


@numba.njit(cache=True)
def pose_errors_one(
    reached: FloatArray, target: FloatArray, q: FloatArray, lower: FloatArray, upper: FloatArray
) -> tuple[float, float, bool]:  # pragma: no cover - compiled
    """``‖p − p*‖`` [m], the angle of ``R*ᵀR`` [rad] (the formula of
    :func:`swarm_ik.kernels.lie.angle`) of a reached pose ``(4, 4)`` (Pinocchio's) against the
    target ``(4, 4)``, and whether ``q`` lies within ``[lower, upper]`` (± 1e-12)."""
    dx = reached[0, 3] - target[0, 3]
    dy = reached[1, 3] - target[1, 3]
    dz = reached[2, 3] - target[2, 3]
    dp = math.sqrt(dx * dx + dy * dy + dz * dz)
    # the entries of R*ᵀR that the angle needs, as scalars (an array here was an allocation
    # per call, ≈ 1 µs with cold caches)
    s0 = _rtr(target, reached, 2, 1) - _rtr(target, reached, 1, 2)
    s1 = _rtr(target, reached, 0, 2) - _rtr(target, reached, 2, 0)
    s2 = _rtr(target, reached, 1, 0) - _rtr(target, reached, 0, 1)
    c0 = (
        _rtr(target, reached, 0, 0) + _rtr(target, reached, 1, 1) + _rtr(target, reached, 2, 2)
    ) - 1.0
    dr = math.atan2(math.sqrt(s0 * s0 + s1 * s1 + s2 * s2), c0)
    within = True
    for j in range(q.shape[0]):
        if q[j] < lower[j] - 1e-12 or q[j] > upper[j] + 1e-12:
            within = False
    return dp, dr, within
