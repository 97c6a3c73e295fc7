"""Particle swarm optimisation [PSO] and the improved PSO of [PSO-IK].

Two registrations of the same :func:`run`:

* ``pso``: the standard global-best PSO of [PSO-IK], section 3.1 (eq. 6), with the paper's
  settings for its baseline: inertia ``w = 0.7``, ``c1 = c2 = 1.5``, 40 particles,
  100 iterations.
* ``pso-improved``: [PSO-IK]'s improved PSO (section 3.2): the same swarm with ``w = 0.9`` plus
  (1) a local search on the global best along the negative gradient and (2) an escape strategy
  that re-randomises half the swarm when the global best stagnates.
"""

from __future__ import annotations

import numpy as np

from swarm_ik.solvers.base import Evaluator, FloatArray, register

_MIN_STEP = 1e-12
"""Floor of the local-search step (fraction of the range); below it a step is a no-op."""


def fd_gradient(ev: Evaluator, x: FloatArray, fd_step: float) -> FloatArray | None:
    """Central finite-difference gradient of the objective at ``x``, through ``ev``.

    Costs ``2n`` evaluations (one batch).  Near a bound the difference becomes one-sided: the
    probe points are clipped into the bounds and the quotient uses the actual spacing.

    Args:
        ev: The evaluator (its evaluations count against the budget).
        x: Point, shape ``(n,)``, inside the bounds.
        fd_step: Probe offset as a fraction of each joint's range ``u_j - l_j``.

    Returns:
        Gradient, shape ``(n,)`` (0 for a dimension with zero range), or ``None`` when a probe
        was not evaluated or gave ``+inf``.
    """
    n = ev.dim
    h = fd_step * (ev.upper - ev.lower)
    eye = np.eye(n)
    plus = ev.clip(x + eye * h)
    minus = ev.clip(x - eye * h)
    f = ev(np.concatenate([plus, minus]))
    if not np.all(np.isfinite(f)):
        return None
    spacing = np.diagonal(plus) - np.diagonal(minus)
    diff = f[:n] - f[n:]
    return np.divide(diff, spacing, out=np.zeros(n), where=spacing > 0)


def run(
    ev: Evaluator,
    rng: np.random.Generator,
    *,
    pop_size: int = 40,
    iterations: int = 100,
    w: float = 0.7,
    c1: float = 1.5,
    c2: float = 1.5,
    v_max: float = 0.2,
    local_search: bool = False,
    ls_step: float = 0.2,
    ls_steps: int = 4,
    fd_step: float = 1e-6,
    escape: bool = False,
    escape_after: int = 5,
) -> None:
    """Global-best PSO ([PSO-IK], eq. 6) with [PSO-IK]'s optional improvements.

    Standard PSO (section 3.1): positions uniform within the bounds (row 0 = ``q0`` when
    given), velocities uniform in ``[-v_max, v_max]·(u - l)``; each iteration, per particle and
    component with fresh ``r1, r2 ~ U[0, 1]``::

        v = w·v + c1·r1·(pbest - x) + c2·r2·(gbest - x);   x = x + v        (eq. 6)

    then the whole swarm is evaluated in one batch and ``pbest``/``gbest`` replaced when
    strictly better.  [PSO-IK] clips out-of-bound positions to the bound; it says nothing of
    velocities: here each velocity component is clamped to ``±v_max·(u_j - l_j)`` (the usual
    clamp; paper silent) and set to zero where the position was clipped (absorbing wall; our
    choice, so a particle does not keep pushing against the bound).

    Improvement (1), local search (section 3.2.1, eq. 13), once per iteration on the global
    best, after the swarm's update: the gradient is estimated by central finite differences
    through ``ev`` (``2n`` evaluations per iteration, counted: [PSO-IK] differentiates its DH
    model analytically, eq. 11, which a black-box objective does not allow).  The direction is
    normalised in range-scaled coordinates ``z_j = (x_j - l_j)/(u_j - l_j)`` and the step is a
    fraction ``α`` of the range, so it is independent of the objective's units ([PSO-IK]
    steps ``λ·∇f`` with the raw gradient).  Up to ``ls_steps`` steps ``x ← clip(x + α·d)``
    are tried, one evaluation each; only improving steps are kept (the paper's "replace pbest
    when better"); after an improving step ``α`` doubles (capped at ``ls_step``), after a
    failed one it halves.  ``α`` starts at ``ls_step`` and carries over between iterations,
    so the search keeps working once the swarm is within ``ls_step`` of the optimum (a fixed
    ``α = 0.2`` of the range would almost never improve late in the run).  An improvement
    replaces the best particle's ``pbest`` and ``gbest``.

    Improvement (2), escape (section 3.2.2, eq. 14): when ``gbest`` has not improved for
    ``escape_after`` consecutive iterations, the next iteration places the worse half of the
    swarm (the ``pop_size // 2`` particles with the worst ``pbest``; the paper only says
    "half") uniformly within the bounds instead of moving it by eq. 6, with zero velocity;
    these are new particles, so their ``pbest`` becomes the new position whatever its
    fitness.  The better half is kept.  The escape costs no extra evaluation: the re-randomised
    particles are evaluated in the iteration's batch.  The counter then restarts.

    Evaluations: ``pop_size·(iterations + 1)``, plus ``2n + ls_steps`` per iteration with the
    local search.

    Args:
        ev: Budgeted objective (see :class:`swarm_ik.solvers.base.Evaluator`).
        rng: Source of all randomness.
        pop_size: Swarm size ``M`` ([PSO-IK]: 40).
        iterations: Iterations ([PSO-IK]: 100).
        w: Inertia weight ([PSO-IK]: 0.7 for the standard PSO, 0.9 for the improved one).
        c1: Cognitive coefficient ([PSO-IK]: 1.5).
        c2: Social coefficient ([PSO-IK]: 1.5).
        v_max: Velocity clamp as a fraction of each joint's range (not in [PSO-IK]; 0.2 is
            the common choice).
        local_search: Enable improvement (1).
        ls_step: Largest local-search step ``λ`` as a fraction of the range ([PSO-IK]:
            ``λ = 0.2``, applied there to the raw gradient).
        ls_steps: Most local-search steps per iteration ``MS`` ([PSO-IK]: 4).
        fd_step: Finite-difference probe offset as a fraction of the range (not in [PSO-IK];
            1e-6 is near the optimum for central differences in double precision).
        escape: Enable improvement (2).
        escape_after: Stagnation iterations ``G`` before an escape ([PSO-IK]: 5).

    Parameter values are checked by the registry (:data:`CONSTRAINTS`, ``pop_size`` and
        ``iterations`` by :meth:`swarm_ik.solvers.base.SolverSpec.resolve`).
    """
    m = int(pop_size)
    n = ev.dim
    lo, hi = ev.lower, ev.upper
    width = hi - lo
    vlim = v_max * width

    x = ev.initial_population(rng, m)
    v = rng.uniform(-vlim, vlim, size=(m, n))
    pf = ev(x)
    p = x.copy()
    ib = int(np.argmin(pf))
    g = p[ib].copy()
    gf = float(pf[ib])
    alpha = float(ls_step)
    stall = 0

    for _ in range(iterations):
        if ev.done:
            break
        gf_start = gf
        r1 = rng.random((m, n))
        r2 = rng.random((m, n))
        v = np.clip(w * v + c1 * r1 * (p - x) + c2 * r2 * (g - x), -vlim, vlim)  # eq. 6
        xn = x + v
        x = ev.clip(xn)
        v = np.where(x == xn, v, 0.0)
        escaped = np.zeros(0, dtype=np.int64)
        if escape and stall >= escape_after:  # eq. 14 for the worse half
            escaped = np.argsort(pf, kind="stable")[m - m // 2 :]
            x[escaped] = ev.uniform(rng, escaped.size)
            v[escaped] = 0.0
            stall = 0
        f = ev(x)
        p[escaped] = x[escaped]
        pf[escaped] = f[escaped]
        better = f < pf
        p[better] = x[better]
        pf[better] = f[better]
        ib = int(np.argmin(pf))
        if pf[ib] < gf:
            g = p[ib].copy()
            gf = float(pf[ib])

        if local_search and np.isfinite(gf) and ev.remaining > 2 * n and not ev.done:
            grad = fd_gradient(ev, g, fd_step)
            gz = None if grad is None else grad * width
            norm = 0.0 if gz is None else float(np.linalg.norm(gz))
            if gz is not None and np.isfinite(norm) and norm > 0.0:
                d = -(gz / norm) * width
                xl, fl = g, gf
                for _ in range(ls_steps):
                    y = ev.clip(xl + alpha * d)
                    fy = float(ev(y[None])[0])
                    if fy < fl:
                        xl, fl = y, fy
                        alpha = min(2.0 * alpha, ls_step)
                    else:
                        alpha = max(0.5 * alpha, _MIN_STEP)
                    if ev.done:
                        break
                if fl < gf:
                    g, gf = xl.copy(), fl
                    p[ib] = g
                    pf[ib] = gf

        if escape:
            stall = 0 if gf < gf_start else stall + 1
        ev.end_iteration()


CONSTRAINTS = {
    "w": "nonnegative",
    "c1": "nonnegative",
    "c2": "nonnegative",
    "v_max": "(0, 1e3]",
    "ls_step": "(0, 1e3]",
    "ls_steps": "int>=0",
    "fd_step": "(0, 1]",
    "escape_after": "int>=1",
}
"""What each parameter accepts (checked by the registry: ``solvers.base.Constraint``)."""

register(
    "pso",
    run,
    paper="PSO",
    constraints=CONSTRAINTS,
    description="standard global-best PSO ([PSO-IK] eq. 6; w=0.7, c1=c2=1.5, 40x100)",
)
register(
    "pso-improved",
    run,
    paper="PSO-IK",
    constraints=CONSTRAINTS,
    w=0.9,
    local_search=True,
    escape=True,
    description="[PSO-IK]'s improved PSO: w=0.9, gradient local search on gbest (finite "
    "differences), escape of half the swarm after 5 stagnant iterations",
)
