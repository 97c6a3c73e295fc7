"""Hybrid learning fruit fly optimisation of [HLFOA], section 2.2.

Two registrations of the same :func:`run`:

* ``hlfoa``: the paper's algorithm, with the real-time visual update (eqs. 13-14): every
  individual is evaluated on its own and updates ``P_i`` and ``G_b`` at once, so the flies after
  it in the same iteration already learn from it.  This is inherently sequential: one objective
  call per individual.
* ``hlfoa-batch``: a named variant that is *not* the paper's algorithm.  The whole population is
  generated from the iteration-start ``P`` and ``G_b``, evaluated in one batch, and only then
  are ``P`` and ``G_b`` updated (synchronous update).  Much faster per evaluation on a batched
  objective, but it learns one iteration late.

The paper's fitness is its eq. 3 (``IKProblem(..., fitness="paper-l1")``, as ``swarm-ik bench
paper`` runs it); on any other fitness of the problem the algorithm minimises that one.
"""

from __future__ import annotations

import numpy as np

from swarm_ik._types import IntArray
from swarm_ik.solvers.base import Evaluator, register
from swarm_ik.solvers.gwo import schedule_length


def distinct_indices(rng: np.random.Generator, m: int) -> IntArray:
    """For each ``i < m``, three distinct indices ``r1, r2, r3``, all different from ``i``.

    Uniform over ordered triples of distinct elements of ``{0..m-1} \\ {i}``, drawn for all
    ``i`` at once (each index drawn from a shrunken range, then shifted past the excluded ones).

    Args:
        rng: Random generator.
        m: Population size, ``>= 4``.

    Returns:
        Integer array, shape ``(m, 3)``: columns ``r1, r2, r3``.
    """
    excl = np.arange(m, dtype=np.int64)[:, None]  # sorted excluded indices per row
    out = np.empty((m, 3), dtype=np.int64)
    for k in range(3):
        r = rng.integers(0, m - 1 - k, size=m)
        # Shift r past each excluded value <= it, in increasing order of the excluded values.
        for j in range(excl.shape[1]):
            r = r + (r >= excl[:, j])
        out[:, k] = r
        excl = np.sort(np.concatenate([excl, r[:, None]], axis=1), axis=1)
    return out


def run(
    ev: Evaluator,
    rng: np.random.Generator,
    *,
    pop_size: int = 100,
    iterations: int = 1000,
    realtime: bool = True,
) -> None:
    """HLFOA, [HLFOA] section 2.2 (eqs. 10-14), minimising ``ev``.

    * Linear candidates (2.2.1): the fly position ``X_i`` *is* the candidate (``S_i = X_i``).
    * Initialisation (2.2.6 step 1): ``m`` flies uniform within the bounds (row 0 = ``q0`` when
      given), evaluated; ``P_i = X_i``, ``G_b`` = best of them.
    * Olfactory search (eqs. 10-11), for ``t = 1..t_max`` and each fly ``i``, with
      ``ω = exp(-(t/t_max)²)``, ``r, r' ~ U[0, 1]`` and distinct ``r1 ≠ r2 ≠ r3 ≠ i``::

          r <  ω:  X_i(t+1) = (P_r2 - P_r3)·exp(-r') + P_r1
          r >= ω:  X_i(t+1) = (P_r2 - P_r3)·ω + (G_b + X_i(t))/2

      ``X_i(t)`` is the fly's current position (its last candidate, accepted or not).  ``r``
      and ``r'`` are drawn once per fly and iteration, shared by its joints (the paper writes
      them as scalars; our reading).
    * Bounds (eq. 12): each out-of-bound component becomes ``l_j + (u_j - l_j)·k``,
      ``k ~ U[0, 1]``.
    * Visual search (eqs. 13-14), greedy with ``<=``: ``P_i`` and ``G_b`` take ``X_i(t+1)``
      when it is at least as good.  With ``realtime=True`` (the paper) this happens right after
      fly ``i`` is evaluated, before fly ``i+1`` is generated.

    Evaluations: ``m·t_max + m`` (section 2.2.5).  With ``realtime=True`` each fly is
    evaluated by its own ``ev`` call; the random numbers of an iteration (``r``, ``r'``, the
    index triples and the eq. 12 draws ``k``) are drawn in batch at the start of the iteration,
    which changes the order of the random stream, not the distribution, so the algorithm is
    exactly the paper's.  No candidate is evaluated speculatively: the evaluation count is the
    paper's.

    Args:
        ev: Budgeted objective (see :class:`swarm_ik.solvers.base.Evaluator`).
        rng: Source of all randomness.
        pop_size: Population size ``m`` ([HLFOA]: 100); at least 4 (three distinct partners
            besides the fly itself).
        iterations: ``t_max`` ([HLFOA]: 1000); also sets the schedule ``ω``, shortened to the
            iterations an evaluation budget smaller than ``m·t_max`` allows (so that ``ω``
            still reaches its end within the budget, as GWO's ``a``:
            :func:`swarm_ik.solvers.gwo.schedule_length`; a choice, the paper runs whole).
        realtime: True: real-time update of eqs. 13-14, one evaluation per call (the paper).
            False: synchronous update, one batch per iteration (the ``hlfoa-batch`` variant,
            not in the paper).

    ``pop_size >= 4`` (:data:`swarm_ik.solvers.base.MIN_POP_SIZE`) and ``iterations >= 1``
    are checked by the registry (:meth:`swarm_ik.solvers.base.SolverSpec.resolve`).
    """
    m = int(pop_size)
    n = ev.dim
    lo, hi = ev.lower, ev.upper
    width = hi - lo

    x = ev.initial_population(rng, m)
    pf = ev(x)
    p = x.copy()
    ib = int(np.argmin(pf))
    g = p[ib].copy()
    gf = float(pf[ib])

    t_max = schedule_length(ev, m, iterations)
    for t in range(1, int(iterations) + 1):
        if ev.done:
            break
        w = float(np.exp(-((t / t_max) ** 2)))  # eq. 11
        first = rng.random(m) < w  # r < ω
        decay = np.exp(-rng.random(m))  # exp(-r')
        idx = distinct_indices(rng, m)
        k = rng.random((m, n))  # eq. 12 draws, used only where a component is out of bounds

        if not realtime:
            diff = p[idx[:, 1]] - p[idx[:, 2]]
            xn = np.where(
                first[:, None],
                diff * decay[:, None] + p[idx[:, 0]],
                diff * w + 0.5 * (g + x),
            )
            bad = (xn < lo) | (xn > hi)
            x = np.where(bad, lo + width * k, xn)
            f = ev(x)
            better = f <= pf  # eq. 13
            p[better] = x[better]
            pf[better] = f[better]
            i = int(np.argmin(f))
            if f[i] <= gf:  # eq. 14
                g = x[i].copy()
                gf = float(f[i])
            ev.end_iteration()
            continue

        # Real-time update: fly i sees P and G_b as updated by flies 0..i-1 of this iteration.
        r1s, r2s, r3s = idx[:, 0].tolist(), idx[:, 1].tolist(), idx[:, 2].tolist()
        firsts = first.tolist()
        decays = decay.tolist()
        for i in range(m):
            if firsts[i]:
                xi = (p[r2s[i]] - p[r3s[i]]) * decays[i] + p[r1s[i]]
            else:
                xi = (p[r2s[i]] - p[r3s[i]]) * w + 0.5 * (g + x[i])
            bad = (xi < lo) | (xi > hi)
            if bad.any():
                xi = np.where(bad, lo + width * k[i], xi)
            n_before = ev.n_evals
            fi = float(ev(xi[None])[0])
            if ev.n_evals == n_before:  # not evaluated: budget spent, time up or stopped
                break
            x[i] = xi
            if fi <= pf[i]:  # eq. 13
                p[i] = xi
                pf[i] = fi
            if fi <= gf:  # eq. 14
                g = xi
                gf = fi
        ev.end_iteration()


register(
    "hlfoa",
    run,
    paper="HLFOA",
    description="hybrid learning fruit fly optimisation [HLFOA] with the paper's real-time "
    "update; one evaluation per call",
)
register(
    "hlfoa-batch",
    run,
    paper="HLFOA",
    realtime=False,
    description="HLFOA variant (not in [HLFOA]): synchronous update, whole population per batch",
)
