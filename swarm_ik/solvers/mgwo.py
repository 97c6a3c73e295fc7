"""Multi-population grey wolf optimiser of [MGWO], section 3.1.

One registration, ``mgwo``: the pack is split into sub-packs that run the GWO update of
:mod:`swarm_ik.solvers.gwo` with their own leaders; the best of their alphas is the wolf
king; the worst wolf of each sub-pack follows the king and its own alpha PSO-style; a
stagnating king triggers the re-initialisation of the worst sub-pack (details in
:func:`run`).  The paper gives no values for m, γ, ω, c1, c2; they were chosen from this
sweep (30 wolves, 200 iterations; F1–F4 of :mod:`swarm_ik.testfunctions`, mean of 20 runs,
seeds 0–19; IK: ``loading_manipulator_long`` with the ``"euler-zyz"`` fitness, target the
FK of [MGWO]'s ``x* = [π/4, π/6, π/4, 0.8, 1, 1, π/6, −π/4]`` (reachable in that variant),
full budget, 50 runs, seeds 0–49):

======  ===  ====  ===  =======  =======  =====  ========  =======  =========  ========
solver  m    γ     ω    F1       F2       F3     F4        IK mean  IK median  IK worst
======  ===  ====  ===  =======  =======  =====  ========  =======  =========  ========
gwo     --   --    --   8.6e-9   6.0e-6   13.6   -3.86070  0.172    0.068      0.93
mgwo    1    0.1   0.7  7.9e-9   7.1e-6   15.2   -3.86169  0.158    0.056      0.87
mgwo    2    0.1   0.7  8.7e-6   3.0e-4   17.0   -3.86205  0.083    0.064      0.44
mgwo    3    0.05  0.7  5.1e-4   3.0e-3   20.8   -3.86236  0.078    0.064      0.22
mgwo    3    0.1   0.4  2.1e-4   2.4e-3   18.4   -3.86252  0.062    0.048      0.15
mgwo    3    0.2   0.4  2.1e-4   2.4e-3   18.3   -3.86262  0.061    0.056      0.22
mgwo    3    0.1   0.7  5.1e-4   3.0e-3   23.2   -3.86220  0.075    0.057      0.42
mgwo    3    0.2   0.7  5.1e-4   3.0e-3   21.4   -3.86257  0.061    0.055      0.18
mgwo    3    0.1   0.9  5.7e-4   3.5e-3   21.4   -3.86247  0.080    0.069      0.37
mgwo    5    0.1   0.4  5.2e-3   1.5e-2   25.4   -3.86262  0.065    0.057      0.21
mgwo    5    0.1   0.7  6.0e-2   4.7e-2   30.3   -3.86259  0.081    0.082      0.20
mgwo    10   0.1   0.7  6.3      0.87     56.3   -3.86267  0.083    0.078      0.25
======  ===  ====  ===  =======  =======  =====  ========  =======  =========  ========

(c1 = c2 = 1.5 throughout; on F1 and F2 γ never acts, the king improves every iteration.)
[MGWO], Table 3 (50 runs): GWO 9.38e-9, 6.76e-6, 14.75, −3.8609; MGWO 5.89e-14, 5.16e-9,
1.30, −3.8628; Table 4 (IK, its own robot limits): GWO 0.4292, MGWO 0.0122.

What this reproduces and what it does not: MGWO's gains on the multimodal IK problem (the mean
falls 2.8-fold and the worst run is six times better than GWO's) and on F4 (closer to −3.86278, as
in the paper).  It does **not** reproduce the paper's gains on F1–F3: with the 30 wolves
split into sub-packs of 10, each sub-pack behaves like a GWO of 10 wolves (GWO with 10
wolves: F1 4.5e-4), and the king-guided worst wolves do not make up for it.  The paper's
text gives nothing else that would explain its F1–F3 figures.
"""

from __future__ import annotations

import numpy as np

from swarm_ik.errors import InvalidArgumentError
from swarm_ik.solvers.base import Evaluator, register
from swarm_ik.solvers.gwo import gwo_move, init_leaders, schedule_length, update_leaders


def run(
    ev: Evaluator,
    rng: np.random.Generator,
    *,
    pop_size: int = 30,
    iterations: int = 200,
    subpops: int = 3,
    gamma: float = 0.1,
    omega: float = 0.4,
    c1: float = 1.5,
    c2: float = 1.5,
    v_max: float = 0.2,
    demote_leaders: bool = False,
) -> None:
    """Multi-population GWO ([MGWO], section 3.1, steps 1–9 of section 3.2).

    The pack of ``pop_size`` wolves (row 0 = ``q0`` when given) is split into ``subpops``
    contiguous sub-packs (step 3; sizes differ by at most one).  Each iteration
    ``t = 0, …, T−1``:

    1. the whole pack is evaluated in one batch; each sub-pack updates its own α, β, δ with
       the GWO leader rule (step 4; :func:`swarm_ik.solvers.gwo.update_leaders`);
    2. the wolf king ``I_α`` is the best of the sub-packs' alphas (step 5, eq. 16); a counter
       counts the iterations in which the king's fitness did not improve;
    3. every wolf except the worst of each sub-pack moves by the standard GWO update towards
       its own sub-pack's α, β, δ (step 7), with the global schedule ``a = 2 − 2t/T`` (the
       same ``t/T`` for all sub-packs);
    4. the worst wolf of sub-pack ``k`` (worst fitness in this iteration's evaluation)
       instead moves PSO-style (step 6, eqs. 21–22)::

           v = ω·v + c1·r1·(I_α − x) + c2·r2·(I_k − x),   x = x + v

       with ``I_k`` the sub-pack's α and fresh ``r1, r2 ~ U[0, 1]`` per coordinate;
    5. positions are clipped to the bounds; a clipped velocity component is set to zero;
    6. when the counter exceeds ``r = γ·G_t`` (eq. 23, ``G_t = T``), the worst sub-pack (the
       one with the worst α; never the king's) is re-initialised uniformly within the bounds
       (our reading of the paper's "随机重组", random regrouping, which it does not detail),
       with zero velocities and empty leader slots, and the counter is reset (step 6).  The new
       wolves are evaluated in the next iteration's batch: no extra evaluations.

    Like :func:`swarm_ik.solvers.gwo.run` a run costs exactly ``pop_size·iterations``
    evaluations (the move after the last evaluation is skipped) and ``T`` is shortened to what
    ``max_evals`` allows.

    Choices where [MGWO] is silent or ambiguous (all exposed as parameters):

    * Steps 6 and 7 are read as alternatives: the worst wolves move by eqs. 21–22 *instead of*
      the GWO update (applying the GWO update after the PSO move would nearly erase it, since
      the GWO move depends on the old position only through ``|C·X_l − X|``; measured on
      F1–F4, the two readings give the same results within noise).
    * ``I_α`` and ``I_k`` in eq. 21 are positions (the text calls them fitness values).
    * Velocities start at zero; each wolf keeps its own velocity, updated only while it is
      the worst of its sub-pack; components are clamped to ``±v_max·(u − l)`` (PSO's usual
      clamp; without it the first moves of a far-away worst wolf overshoot the box).
    * "Worst sub-population" = the one whose α is worst.  It is re-initialised (Step 6) after
      the iteration's moves, not before them, so its new wolves are evaluated where they were
      drawn; its α, β, δ are emptied with it (the paper does not say what its leaders become).
    * "Population 30" is read as 30 wolves in all (the paper's 30, split into the sub-packs).
      The text ("拓展了灰狼种群数量", the pack enlarged at initialisation) also reads as 30
      wolves *per* sub-pack: ``pop_size=90`` with 3 sub-packs, three times the evaluations
      (a review measured F1 2e-9 and F3 7.7 that way, 8 seeds, against 2.3e-4 and 17 with
      30 in all; the paper's 5.9e-14 and 1.30 are reached by neither).
    * m = 3, γ = 0.1, ω = 0.4, c1 = c2 = 1.5 from the sweep in the module docstring: m = 3
      gives the best IK results of the values tried; γ hardly matters; ω = 0.4 is slightly
      better than 0.7 on every column.

    Args:
        ev: Budgeted objective (see :class:`swarm_ik.solvers.base.Evaluator`).
        rng: Source of all randomness.
        pop_size: Total number of wolves ``n`` ([MGWO]: 30).
        iterations: Iterations ``G_t`` ([MGWO]: 200).
        subpops: Number of sub-packs ``m``, ``1 <= m <= pop_size`` ([MGWO]: ``1 < m < n``,
            value not given; ``m = 1`` is plain GWO with a PSO-guided worst wolf and no
            re-initialisation).
        gamma: ``γ ∈ (0, 1)`` of the re-initialisation threshold ``r = γ·G_t`` (eq. 23; value
            not given in the paper).
        omega: Inertia ``ω`` of eq. 21 (not given).
        c1: Coefficient of the pull towards the wolf king (eq. 21; not given).
        c2: Coefficient of the pull towards the sub-pack's α (eq. 21; not given).
        v_max: Velocity clamp of the worst wolves as a fraction of each joint's range (not in
            the paper).
        demote_leaders: Use the true three best as α, β, δ (see
            :func:`swarm_ik.solvers.gwo.update_leaders`; default: the reference rule, as GWO).

    Parameter values are checked by the registry (:data:`CONSTRAINTS`, ``pop_size`` and
        ``iterations`` by :meth:`swarm_ik.solvers.base.SolverSpec.resolve`).

    Raises:
        InvalidArgumentError: ``subpops > pop_size``.
    """
    m = int(pop_size)
    k = int(subpops)
    if m < k:
        raise InvalidArgumentError(
            f"mgwo needs subpops <= pop_size; got pop_size={pop_size}, subpops={subpops}"
        )
    n = ev.dim
    t_max = schedule_length(ev, m, iterations)
    threshold = gamma * t_max  # eq. 23: r = γ·G_t
    vlim = v_max * (ev.upper - ev.lower)
    groups = np.array_split(np.arange(m), k)  # contiguous sub-populations, sizes differ by <= 1
    group_of = np.concatenate([np.full(g.size, j) for j, g in enumerate(groups)])

    x = ev.initial_population(rng, m)
    v = np.zeros((m, n))
    lx = np.empty((k, 3, n))
    lf = np.empty((k, 3))
    for j, g in enumerate(groups):
        lx[j], lf[j] = init_leaders(x[g[0]])
    king_prev = np.inf
    stall = 0

    for t in range(iterations):
        if ev.done:
            break
        f = ev(x)
        for j, g in enumerate(groups):  # step 4: each sub-population's α, β, δ
            lx[j], lf[j] = update_leaders(lx[j], lf[j], x[g], f[g], demote=demote_leaders)
        king = int(np.argmin(lf[:, 0]))  # step 5, eq. 16: the wolf king I_α
        king_f = float(lf[king, 0])
        stall = 0 if king_f < king_prev else stall + 1
        king_prev = king_f
        ev.end_iteration()
        if t + 1 >= iterations or ev.done:  # (a move no evaluation would see)
            break
        a = max(0.0, 2.0 - 2.0 * t / t_max)

        # step 6, eqs. 21-22: the worst wolf of each sub-population follows I_α and its I_k.
        worst = np.array([g[int(np.argmax(f[g]))] for g in groups])
        r1 = rng.random((k, n))
        r2 = rng.random((k, n))
        i_alpha = lx[king, 0]
        i_k = lx[:, 0]
        v[worst] = np.clip(
            omega * v[worst] + c1 * r1 * (i_alpha - x[worst]) + c2 * r2 * (i_k - x[worst]),
            -vlim,
            vlim,
        )
        xn = gwo_move(x, lx[group_of], a, rng)  # step 7 (eqs. of GWO) for the other wolves
        xn[worst] = x[worst] + v[worst]
        x_new = ev.clip(xn)
        kept = x_new[worst] == ev.wrapped(xn[worst])  # absorbing walls (a continuous
        v[worst] = np.where(kept, v[worst], 0.0)  # joint wrapped across ±π meets none there)
        x = x_new

        # step 6, eq. 23: re-initialise the worst sub-population after a long stagnation.
        if stall > threshold and k >= 2:
            order = np.argsort(-lf[:, 0], kind="stable")
            j = int(order[0]) if int(order[0]) != king else int(order[1])
            g = groups[j]
            x[g] = ev.uniform(rng, g.size)
            v[g] = 0.0
            lx[j], lf[j] = init_leaders(x[g[0]])
            stall = 0


CONSTRAINTS = {
    "subpops": "int>=1",
    "gamma": "(0, 1)",
    "omega": "nonnegative",
    "c1": "nonnegative",
    "c2": "nonnegative",
    "v_max": "(0, 1e3]",
}
"""What each parameter accepts (checked by the registry: ``solvers.base.Constraint``)."""

register(
    "mgwo",
    run,
    paper="MGWO",
    constraints=CONSTRAINTS,
    description="multi-population GWO of [MGWO]: sub-packs, wolf king, PSO-guided worst "
    "wolves, re-initialisation of the worst sub-pack on stagnation (30 wolves x 200)",
)
