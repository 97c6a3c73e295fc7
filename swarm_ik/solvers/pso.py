"""Particle swarm optimisation [PSO] and the improved PSO of [PSO-IK].

Three registrations of the same :func:`run`:

* ``pso``: the standard global-best PSO of [PSO-IK], section 3.1 (eq. 6), with the paper's
  settings for its baseline: inertia ``w = 0.7``, ``c1 = c2 = 1.5``, 40 particles,
  100 iterations.
* ``pso-improved``: [PSO-IK]'s improved PSO (section 3.2) as written: the same swarm with
  ``w = 0.9`` plus (1) a local search from the generation's best particle, ``MS = 4`` steps
  ``θ ← θ − λ·∇f(θ)`` with the fixed ``λ = 0.2`` (eq. 13), and (2) an escape strategy that
  re-randomises half the swarm when the global best stagnates for ``G = 5`` generations
  (eq. 14).
* ``pso-adaptive``: a variant of ``pso-improved`` (not in [PSO-IK]): the same swarm and
  escape, with a local search from ``gbest`` along one normalised, range-scaled descent
  direction per iteration and a step that doubles on success and halves on failure
  (``ls_rule="adaptive"``).

[PSO-IK]'s stopping rule (step ⑥ of section 3.1: stop when ``gbest`` meets the accuracy, the
"minimum error" 0.02 of section 4) is the opt-in ``paper_stop``; by default the library's own
success test ends a run (see :func:`run`).
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
    ls_rule: str = "paper",
    ls_step: float = 0.2,
    ls_steps: int = 4,
    fd_step: float = 1e-6,
    escape: bool = False,
    escape_after: int = 5,
    paper_stop: bool = False,
    min_error: float = 0.02,
) -> None:
    """Global-best PSO ([PSO-IK], eq. 6) with [PSO-IK]'s optional improvements.

    Standard PSO (section 3.1): positions uniform within the bounds (row 0 = ``q0`` when
    given), velocities uniform in ``[-v_max, v_max]·(u - l)``; each iteration, per particle and
    component with fresh ``r1, r2 ~ U[0, 1]``::

        v = w·v + c1·r1·(pbest - x) + c2·r2·(gbest - x);   x = x + v        (eq. 6)

    then the whole swarm is evaluated in one batch and ``pbest``/``gbest`` replaced when
    strictly better.  [PSO-IK] clips out-of-bound positions to the bound (here a continuous
    joint, without bounds, is wrapped to ``[-π, π)`` instead: our choice); it says nothing of
    velocities: here each velocity component is clamped to ``±v_max·(u_j - l_j)`` (the usual
    clamp; paper silent) and set to zero where the position was clipped (absorbing wall; our
    choice, so a particle does not keep pushing against the bound).

    Improvement (1), local search (section 3.2.1, eqs. 9-13), with ``ls_rule="paper"``
    (registered as ``pso-improved``), as written: after the swarm's update, the particle ``i``
    with the best fitness *of this generation* (``argmin f(θ_i)`` over the positions just
    evaluated, not ``gbest``) is searched from its position ``θ_i`` by ``MS = ls_steps`` steps
    of eq. 13::

        θ ← clip(θ − λ·∇f(θ))                                             (eq. 13)

    with the fixed step ``λ = ls_step`` ([PSO-IK]: 0.2) on the raw gradient, recomputed at each
    step (eq. 13 is plain gradient descent).  After each step, if ``f(θ) < f(pbest_i)`` then
    ``pbest_i ← θ`` ("倘若其适应度优于pbest_i则将其值赋给pbest_i"); the steps go on from ``θ``
    either way (the paper keeps only the *record* of improving steps, not a rejection of the
    others).  Such a point also becomes the particle's position ``θ_i``: section 3.2.1 opens
    with "若存在更优的位置,则用更优的位置代替当前的位置" (a better position found replaces the
    current one); the particle's velocity is kept (paper silent).  After the ``MS`` steps
    ``pbest_i`` is stored in ``gbest``, read as "when better than ``gbest``" so that ``gbest``
    stays the best position found, its definition in section 3.1 (the literal "store" would
    make ``gbest`` worse whenever particle ``i``'s ``pbest`` is not the global best).  What
    [PSO-IK] leaves open, and our choices:

    * *gradient*: [PSO-IK] differentiates its DH model analytically (eqs. 9-12, eq. 11 for
      ``∂f/∂θ_i``), which a black-box objective does not allow; here ``∇f`` is the central
      finite difference :func:`fd_gradient` through ``ev`` (``2n`` evaluations, counted), with
      the probe offset ``fd_step`` of each joint's range (not in [PSO-IK]);
    * *units of λ*: eq. 9 (``∂A_i/∂θ_i = R_i·A_i``) holds for ``θ`` in radians, so [PSO-IK]'s
      gradient is per radian, while its ranges are printed in degrees (``θ_i ∈ [−180, 180]``)
      and its positions in the unnamed length unit of its Table 1 (not in the text); eq. 13
      does not say in which units it is applied.  Here ``θ`` is in the robot's units (rad,
      m for prismatic joints) and ``∇f`` the gradient of whatever objective is minimised in
      those units, so ``λ = 0.2`` means ``0.2·(joint unit)²`` per fitness unit and the step's
      length scales with the objective.  With a squared fitness such as [PSO-IK]'s own
      (``fitness="paper-pso"``) the gradient vanishes at the optimum and the steps shrink;
      with a norm such as ``"se3"`` it does not, and a fixed ``λ`` oversteps near the optimum
      (the steps are then not recorded, but neither do they converge);
    * *bounds*: a step leaving the bounds is clipped to them, the rule of section 3.1 for
      positions ("若超出范围,则将边界值赋给θ_j"); continuous joints wrap, as everywhere in
      the swarm (:meth:`~swarm_ik.solvers.base.Evaluator.clip`);
    * the search stops early when the budget cannot pay for a gradient and a step
      (``2n + 1`` evaluations) or a probe's fitness is not finite.

    With ``ls_rule="adaptive"`` (registered as ``pso-adaptive``; not in [PSO-IK])
    the local search runs once per iteration on ``gbest`` instead: one finite-difference
    gradient at ``gbest``; the direction ``d`` is normalised in range-scaled coordinates
    ``z_j = (x_j - l_j)/(u_j - l_j)`` and the step is a fraction ``α`` of the range, so it is
    independent of the objective's units.  Up to ``ls_steps`` steps ``x ← clip(x + α·d)``
    along that one direction are tried, one evaluation each; only improving steps are kept;
    after an improving step ``α`` doubles (capped at ``ls_step``), after a failed one it
    halves.  ``α`` starts at ``ls_step`` and carries over between iterations, so the search
    keeps working once the swarm is within ``ls_step`` of the optimum.  An improvement
    replaces the best particle's ``pbest`` and ``gbest``.  It differs from eq. 13 in four
    ways: the start (``gbest``, not the generation's best particle), the gradient (once per
    iteration, not per step), the normalised range-scaled direction, and the adaptive step.

    Improvement (2), escape (section 3.2.2, eq. 14): when ``gbest`` has not improved for
    ``escape_after`` consecutive iterations, the next iteration places the worse half of the
    swarm (the ``pop_size // 2`` particles with the worst ``pbest``; the paper only says
    "half") uniformly within the bounds instead of moving it by eq. 6, with zero velocity;
    these are new particles, so their ``pbest`` becomes the new position whatever its
    fitness.  The better half is kept.  The escape costs no extra evaluation: the re-randomised
    particles are evaluated in the iteration's batch.  The counter then restarts.

    Stopping, step ⑥ of section 3.1 ("若gbest满足精度要求或达到最大迭代次数,算法结束"):
    [PSO-IK] ends the run when ``gbest`` meets the accuracy, its "minimum error" set to 0.02
    in section 4 ("最小误差设为0.02"), or after the last iteration.  The 0.02 is a value of the
    paper's fitness, eqs. 3-5: ``|P − P*|²`` in the squared length unit of its robot (Table 1,
    not in the text) plus the dimensionless orientation term, i.e. about ``‖Δp‖ ≤ 0.14`` length
    units with the orientation exact.  With ``paper_stop=True`` the run ends at the end of the
    first iteration whose ``gbest`` fitness is ``<= min_error`` (in the units of the objective
    actually minimised: [PSO-IK]'s 0.02 means what it meant there only with
    ``fitness="paper-pso"`` and lengths in the paper's unit).  By default (``paper_stop=False``)
    the library's route applies instead: the run ends when the budget is spent, after the
    last iteration, or at the library's own success test (``swarm_ik.solve``'s ``tol_pos`` /
    ``tol_rot``, 1e-5 m and 1e-5 rad by default, seen by the evaluator as soon as a point
    meets it), a far stricter accuracy than the paper's.

    Evaluations: ``pop_size·(iterations + 1)``, plus with the local search per iteration
    ``ls_steps·(2n + 1)`` (``"paper"``: a gradient and a step each) or ``2n + ls_steps``
    (``"adaptive"``).

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
        ls_rule: ``"paper"``: eq. 13 as written (fixed ``λ``, from the generation's best
            particle, a gradient per step); ``"adaptive"``: our variant from ``gbest`` (see
            above; not in [PSO-IK]).
        ls_step: ``"paper"``: the step ``λ`` of eq. 13 on the raw gradient ([PSO-IK]:
            ``λ = 0.2``; units above); ``"adaptive"``: largest step ``α`` as a fraction of
            each joint's range.
        ls_steps: Local-search steps per iteration ``MS`` ([PSO-IK]: 4).
        fd_step: Finite-difference probe offset as a fraction of the range (not in [PSO-IK];
            1e-6 is near the optimum for central differences in double precision).
        escape: Enable improvement (2).
        escape_after: Stagnation iterations ``G`` before an escape ([PSO-IK]: 5).
        paper_stop: End the run when ``gbest``'s fitness is ``<= min_error`` (step ⑥ of
            section 3.1); off by default: the library's own success test ends the run.
        min_error: The accuracy of ``paper_stop``, a fitness value ([PSO-IK]: 0.02 in the
            units of its eqs. 3-5).

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
        v = np.where(x == ev.wrapped(xn), v, 0.0)  # (stopped at a wall; a continuous joint
        # wrapped across ±π meets none there and keeps its velocity)
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

        if local_search:
            if ls_rule == "paper":
                g, gf = _local_search_paper(ev, x, f, p, pf, g, gf, ls_step, ls_steps, fd_step)
            else:
                g, gf, alpha = _local_search_adaptive(
                    ev, p, pf, g, gf, ib, alpha, ls_step, ls_steps, fd_step
                )

        if escape:
            stall = 0 if gf < gf_start else stall + 1
        ev.end_iteration()
        if paper_stop and gf <= min_error:  # step 6 of [PSO-IK] 3.1
            break


def _local_search_paper(
    ev: Evaluator,
    x: FloatArray,
    f: FloatArray,
    p: FloatArray,
    pf: FloatArray,
    g: FloatArray,
    gf: float,
    lam: float,
    steps: int,
    fd_step: float,
) -> tuple[FloatArray, float]:
    """[PSO-IK]'s local search, eq. 13, as written (see :func:`run`).

    Starts at the position of the generation's best particle ``i = argmin f``; each of the
    ``steps`` steps is ``θ ← clip(θ − λ·∇f(θ))`` with a fresh finite-difference gradient; a
    step better than ``pbest_i`` becomes ``pbest_i`` and the particle's position (``p``,
    ``pf``, ``x`` updated in place); then ``pbest_i`` replaces ``gbest`` when better.

    Returns:
        The new ``(gbest, gbest fitness)``.
    """
    i = int(np.argmin(f))
    if not np.isfinite(f[i]):
        return g, gf
    th = x[i].copy()
    for _ in range(steps):
        if ev.done or ev.remaining < 2 * ev.dim + 1:
            break
        grad = fd_gradient(ev, th, fd_step)
        if grad is None:
            break
        th = ev.clip(th - lam * grad)  # eq. 13, out-of-range components to the bound
        fth = float(ev(th[None])[0])
        if fth < pf[i]:  # "better than pbest_i: assign it to pbest_i"
            p[i] = th
            pf[i] = fth
            x[i] = th  # "the better position replaces the current position"
    if pf[i] < gf:  # "store pbest_i in gbest" (gbest: the best position found)
        return p[i].copy(), float(pf[i])
    return g, gf


def _local_search_adaptive(
    ev: Evaluator,
    p: FloatArray,
    pf: FloatArray,
    g: FloatArray,
    gf: float,
    ib: int,
    alpha: float,
    ls_step: float,
    steps: int,
    fd_step: float,
) -> tuple[FloatArray, float, float]:
    """The ``pso-adaptive`` local search (not in [PSO-IK]; see :func:`run`): from
    ``gbest`` (``g``, the ``pbest`` of particle ``ib``) along one normalised, range-scaled
    descent direction, with a step ``α`` that doubles on success and halves on failure.

    Returns:
        The new ``(gbest, gbest fitness, α)``.
    """
    n = ev.dim
    width = ev.upper - ev.lower
    if not (np.isfinite(gf) and ev.remaining > 2 * n and not ev.done):
        return g, gf, alpha
    grad = fd_gradient(ev, g, fd_step)
    gz = None if grad is None else grad * width
    norm = 0.0 if gz is None else float(np.linalg.norm(gz))
    if gz is None or not np.isfinite(norm) or norm <= 0.0:
        return g, gf, alpha
    d = -(gz / norm) * width
    xl, fl = g, gf
    for _ in range(steps):
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
    return g, gf, alpha


CONSTRAINTS = {
    "w": "nonnegative",
    "c1": "nonnegative",
    "c2": "nonnegative",
    "v_max": "(0, 1e3]",
    "ls_step": "(0, 1e3]",
    "ls_steps": "int>=0",
    "fd_step": "(0, 1]",
    "escape_after": "int>=1",
    "ls_rule": "choice:paper|adaptive",
    "min_error": "finite",
}
"""What each parameter accepts (checked by the registry: ``solvers.base.Constraint``)."""

register(
    "pso",
    run,
    paper="PSO-IK",
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
    description="[PSO-IK]'s improved PSO as written: w=0.9, local search of MS=4 steps "
    "theta - 0.2*grad f from the generation's best particle (eq. 13; finite-difference "
    "gradient), escape of half the swarm after 5 stagnant iterations (eq. 14)",
)
register(
    "pso-adaptive",
    run,
    paper="PSO-IK",
    constraints=CONSTRAINTS,
    w=0.9,
    local_search=True,
    ls_rule="adaptive",
    escape=True,
    description="pso-improved variant (not in [PSO-IK]): local search from gbest along a "
    "normalised range-scaled direction, step doubled on success and halved on failure",
)
