"""Basic fruit fly optimisation algorithm [FOA], as described in [HLFOA], eqs. 4-9.

This is the *baseline* [HLFOA] improves on, implemented
faithfully, weaknesses included: the candidate solution ``S = 1/Dist`` is always positive, so
basic FOA cannot reach joint values below zero ([HLFOA], section 2.2.1).  On the YuMi target
the paper shows it stuck near fitness 5.2 (Table 2: mean 5.27143).  Do not "fix" it here; the
fixed algorithm is :mod:`swarm_ik.solvers.hlfoa`.
"""

from __future__ import annotations

import numpy as np

from swarm_ik.solvers.base import Evaluator, FloatArray, register


def _axis_unit(ev: Evaluator) -> FloatArray:
    """Per-dimension scale ``s_j = max(|l_j|, |u_j|)`` (1 where both bounds are 0), shape (n,)."""
    s = np.maximum(np.abs(ev.lower), np.abs(ev.upper))
    return np.where(s > 0.0, s, 1.0)


def smell_candidates(
    x_axis: FloatArray, y_axis: FloatArray, scale: FloatArray, ev: Evaluator
) -> FloatArray:
    """Candidate solutions ``S = 1/Dist`` of flies at axis positions ([HLFOA] eqs. 5-6).

    Args:
        x_axis: X axis coordinates of the flies, dimensionless, shape ``(pop, n)``.
        y_axis: Y axis coordinates, shape ``(pop, n)``.
        scale: Axis unit per dimension, ``s_j`` (see :func:`run`; 1 in [FOA]'s raw units),
            shape ``(n,)``.
        ev: The evaluator (for the bounds).

    Returns:
        ``min(max(s_j / sqrt(X² + Y²), l_j), u_j)``, shape ``(pop, n)``: always ``>= 0`` when
        the bounds allow it (``l_j < 0 <= u_j`` or ``0 <= l_j``), and ``+inf`` at ``Dist = 0``
        is clipped to the upper bound ``u_j``.  The clip is plain, with no wrapping of
        continuous joints (unlike :meth:`~swarm_ik.solvers.base.Evaluator.clip`, which would
        wrap ``S > π`` to a negative angle and ``+inf`` to NaN): a candidate is the paper's
        positive ``S`` held within the limits.
    """
    dist = np.sqrt(x_axis * x_axis + y_axis * y_axis)
    with np.errstate(divide="ignore"):
        s = scale / dist  # (scale > 0: Dist = 0 gives +inf, never NaN)
    return np.clip(s, ev.lower, ev.upper)


def run(
    ev: Evaluator,
    rng: np.random.Generator,
    *,
    pop_size: int = 100,
    iterations: int = 1000,
    init_range: float = 10.0,
    step: float = 1.0,
    axis_scale: bool = False,
) -> None:
    """Basic FOA [FOA] in the per-dimension form, [HLFOA] eqs. 4-9.

    D-dimensional form: every dimension ``j`` has its own pair of axes ``(X_j, Y_j)``; all the
    formulas act elementwise.  The swarm location ``(X_b, Y_b)`` (shape ``(n,)`` each) starts at
    ``U[0, init_range]`` per component ([FOA]'s ``10*rand()``) and is evaluated once.  Each
    iteration:

    * eq. 4: fly ``i`` at ``X_i = X_b + step*U[-1, 1]``, ``Y_i = Y_b + step*U[-1, 1]``
      (independent draws per component; [FOA]'s ``RandomValue = 2*rand() - 1``);
    * eq. 5: ``Dist_i = sqrt(X_i² + Y_i²)`` (elementwise);
    * eq. 6: ``S_ij = 1/Dist_ij``, clipped to the bounds (the joint vector in rad / m; the
      clip is ours: [HLFOA]'s eqs. 5–6 have none, and an ``S`` beyond a joint's limit would
      be no configuration of the arm).
      With ``axis_scale`` (registered as ``foa-scaled``, a variant not in [FOA] or [HLFOA])
      the axes are measured in units of ``1/s_j``, ``s_j = max(|l_j|, |u_j|)``: ``S_ij =
      s_j / Dist_ij``, so that ``Dist = 1`` lands on the largest bound magnitude.  That is an
      initial location in ``U[0, 10/s_j]`` and a step of ``U[-1, 1]/s_j`` in raw axis units:
      not [FOA]'s recommended values, and it changes the results (a held-out review, the
      YuMi target of [HLFOA] Table 2, 10 seeds: mean 6.18, std 0.743 scaled; 5.28, 0.041
      raw; the paper 5.27, 0.046), so the registered ``foa`` is the raw algorithm;
    * eqs. 7-8: ``Smell_i = f(S_i)`` for the whole swarm in one batch; best fly;
    * eq. 9 / step 7: the swarm location moves to the best fly only if its smell improves on
      the best so far (strictly), and the run goes on for all ``iterations``, as [FOA]'s code
      does.  Read literally, [HLFOA] §2.1's step 7 ("if the best smell improves on the previous
      generation's best and the iteration count is below the maximum, repeat step 6; otherwise
      output the result and end") would end the run at the first generation that does not
      improve; its own count of ``m·t_max + 1`` evaluations (§2.2.5) assumes the full run, which
      is our reading.

    ``S_ij > 0`` always: the algorithm never evaluates a negative joint value (unless a bound
    forces it) and so cannot reach optima with negative coordinates.  This is the weakness
    [HLFOA] reports, reproduced on purpose.  It holds on continuous joints too: ``S`` is
    clipped into the bounds without the wrap into ``[-π, π)`` the other solvers get, so an
    ``S > π`` on a continuous joint is held at its upper bound rather than turned into a
    negative angle (a wrap would let FOA reach negative values on those joints, which the
    algorithm as published cannot).

    Evaluations: ``pop_size * iterations + 1`` ([HLFOA], section 2.2.5): the initial location
    is evaluated once.  Pan's reference code instead evaluates a first population of flies
    around it and moves to their best unconditionally; we follow [HLFOA]'s count.  A starting point
    ``q0`` is ignored: a fly location cannot represent an arbitrary joint vector.

    Args:
        ev: Budgeted objective (see :class:`swarm_ik.solvers.base.Evaluator`).
        rng: Source of all randomness.
        pop_size: Flies per iteration ``m`` ([HLFOA]: 100).
        iterations: Iterations ``t_max`` ([HLFOA]: 1000).
        init_range: Initial swarm location drawn from ``U[0, init_range]`` per axis component,
            in axis units ([FOA]: 10; not given in [HLFOA]).
        step: Half-width of the random flight, ``RandomValue = step*U[-1, 1]``, axis units
            ([FOA]: 1; not given in [HLFOA]).
        axis_scale: Measure the axes in units of ``1/s_j`` (the ``foa-scaled`` variant, see
            eq. 6 above); False: [FOA]'s raw units.

    The paper's fitness is [HLFOA] eq. 3 (``IKProblem(..., fitness="paper-l1")``, as ``swarm-ik
    bench paper`` runs it); any other fitness of the problem is minimised as given.

    Parameter values are checked by the registry (:data:`CONSTRAINTS`, ``pop_size`` and
        ``iterations`` by :meth:`swarm_ik.solvers.base.SolverSpec.resolve`).
    """
    n = ev.dim
    scale = _axis_unit(ev) if axis_scale else np.ones(n)
    x_b = init_range * rng.random(n)
    y_b = init_range * rng.random(n)
    smell_best = float(ev(smell_candidates(x_b[None], y_b[None], scale, ev))[0])

    for _ in range(iterations):
        if ev.done:
            break
        x = x_b + step * rng.uniform(-1.0, 1.0, size=(pop_size, n))  # eq. 4
        y = y_b + step * rng.uniform(-1.0, 1.0, size=(pop_size, n))
        smell = ev(smell_candidates(x, y, scale, ev))  # eqs. 5-7
        i = int(np.argmin(smell))  # eq. 8
        if smell[i] < smell_best:  # step 7 -> eq. 9
            smell_best = float(smell[i])
            x_b = x[i].copy()
            y_b = y[i].copy()
        ev.end_iteration()


CONSTRAINTS = {"init_range": "(0, 1e6]", "step": "(0, 1e6]"}
"""What each parameter accepts (checked by the registry: ``solvers.base.Constraint``)."""

register(
    "foa",
    run,
    paper="FOA",
    constraints=CONSTRAINTS,
    description="basic fruit fly optimisation ([FOA]; [HLFOA] eqs. 4-9); cannot reach negative "
    "values, kept as the paper's baseline",
)
register(
    "foa-scaled",
    run,
    paper="FOA",
    constraints=CONSTRAINTS,
    description="variant of foa (not in [FOA]): the fly axes measured per joint in units of "
    "1/max(|lower|, |upper|)",
    axis_scale=True,
)
