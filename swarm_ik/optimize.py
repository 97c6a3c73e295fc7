"""Run any registered solver on a plain objective with box bounds (no robot needed)."""

from __future__ import annotations

import reprlib
import time
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from swarm_ik._validate import check_seed, plain_number, user_stacklevel
from swarm_ik.errors import InvalidArgumentError
from swarm_ik.pose import is_finite_nonneg
from swarm_ik.solvers import base
from swarm_ik.solvers.base import Evaluator, FloatArray, Objective


@dataclass(frozen=True)
class OptimizeResult:
    """Outcome of :func:`minimize`.

    Attributes:
        x: Best point found, shape ``(n,)``.
        fun: Its objective value.
        n_evals: Objective evaluations spent (rows evaluated).
        time_s: Wall-clock seconds.
        history: Best value after each iteration, shape ``(iterations,)``.
    """

    x: FloatArray
    fun: float
    n_evals: int
    time_s: float
    history: FloatArray


def make_rng(seed: int | np.random.Generator | None) -> np.random.Generator:
    """A Generator from a seed (non-negative int), an existing Generator, or None (seed 0).

    Raises:
        InvalidArgumentError: the seed is negative, too large, or not an integer.
    """
    s = check_seed(seed)
    return s if isinstance(s, np.random.Generator) else np.random.default_rng(s)


MAX_EVALS_LIMIT = 2**62
"""The largest ``max_evals`` (the compiled kernels count evaluations in 64-bit integers)."""


def rising_estimate(previous: float, measured: float) -> float:
    """A running estimate of what a step of a timed call costs [s], kept out of later calls'
    time limits: the new measurement when it is larger (rising at once, so that an overrun
    is not repeated), else 0.9 × the previous estimate (falling by a tenth per call, so that
    one slow call does not shorten every later search for good)."""
    return max(measured, 0.9 * previous)


def check_budget(max_evals: int | None, time_limit: float | None) -> None:
    """Refuse a zero/negative evaluation budget or time limit, or one beyond
    :data:`MAX_EVALS_LIMIT` evaluations (a 0-d array is its number)."""
    max_evals, time_limit = plain_number(max_evals), plain_number(time_limit)
    if max_evals is not None and (
        isinstance(max_evals, bool) or not isinstance(max_evals, (int, np.integer)) or max_evals < 1
    ):
        raise InvalidArgumentError(
            f"max_evals must be a positive integer, got {reprlib.repr(max_evals)}"
        )
    if max_evals is not None and max_evals > MAX_EVALS_LIMIT:
        raise InvalidArgumentError(
            f"max_evals must be at most 2**62 (swarm_ik.optimize.MAX_EVALS_LIMIT), got "
            f"{reprlib.repr(max_evals)}"
        )
    if time_limit is not None and not (is_finite_nonneg(time_limit) and float(time_limit) > 0):
        raise InvalidArgumentError(
            f"time_limit must be a positive number of seconds, got {reprlib.repr(time_limit)}"
        )


def _check_x0(x0: Any, lo: FloatArray, hi: FloatArray) -> FloatArray:
    """``x0`` of :func:`minimize`: refused when not ``(n,)`` finite numbers, clipped into
    ``[lo, hi]`` with a warning when outside (the same rule as ``q0`` of ``solve``)."""
    try:
        x = np.array(x0, dtype=float)
    except (TypeError, ValueError):
        raise InvalidArgumentError(f"x0 must be {lo.size} numbers, got {x0!r:.80}") from None
    if x.shape != lo.shape or not np.all(np.isfinite(x)):
        raise InvalidArgumentError(
            f"x0 must hold {lo.size} finite numbers (one per bound), got {x.tolist()!r}"
        )
    fixed = np.clip(x, lo, hi)
    outside = np.flatnonzero(fixed != x)
    if outside.size:
        warnings.warn(
            f"x0 lies outside the bounds at indices {outside.tolist()}; clipped into them",
            stacklevel=user_stacklevel(),
        )
    return fixed


def minimize(
    objective: Objective,
    lower: Any,
    upper: Any,
    solver: str = "gwo",
    *,
    seed: int | np.random.Generator | None = 0,
    max_evals: int | None = None,
    time_limit: float | None = None,
    f_target: float | None = None,
    x0: Any = None,
    **params: Any,
) -> OptimizeResult:
    """Minimise a batched objective within box bounds with a registered solver.

    Args:
        objective: Batched objective ``(pop, n) -> (pop,)``.
        lower: Lower bounds, shape ``(n,)``.
        upper: Upper bounds, shape ``(n,)``.
        solver: Registry name (see :func:`swarm_ik.solvers.names`).
        seed: Seed or Generator; the same seed gives the same result.
        max_evals: Most objective evaluations (rows) allowed.
        time_limit: Most wall-clock seconds.
        f_target: Stop as soon as a value ``<= f_target`` is found.
        x0: Optional starting point, shape ``(n,)``.
        **params: The solver's parameters (unknown names are refused).

    Returns:
        The best point found and the run's bookkeeping.
    """
    if not callable(objective):
        raise InvalidArgumentError(
            f"objective must be a callable (pop, n) -> (pop,), got {type(objective).__name__}"
        )
    spec = base.get(solver)
    if spec.needs_jacobian:
        raise InvalidArgumentError(
            f"solver {solver!r} needs an IK problem (it uses the Jacobian); use swarm_ik.solve"
        )
    kwargs = spec.resolve(params)
    check_budget(max_evals, time_limit)
    try:
        lo = np.array(lower, dtype=float).ravel()
        hi = np.array(upper, dtype=float).ravel()
    except (TypeError, ValueError):
        raise InvalidArgumentError("lower and upper must be arrays of numbers") from None
    if (
        lo.size == 0
        or lo.shape != hi.shape
        or not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)))
    ):
        raise InvalidArgumentError(
            "lower and upper must be non-empty finite arrays of the same shape, got shapes "
            f"{lo.shape} and {hi.shape}"
        )
    if np.any(lo > hi):
        raise InvalidArgumentError(f"lower > upper at indices {np.flatnonzero(lo > hi).tolist()}")
    with np.errstate(over="ignore"):
        wide = ~np.isfinite(hi - lo)
    if wide.any():  # (the uniform draws of every solver span hi - lo)
        raise InvalidArgumentError(
            f"upper - lower overflows a float at indices {np.flatnonzero(wide).tolist()}: "
            "bounds must span less than 1.7e308"
        )
    if f_target is not None and not (
        isinstance(f_target, (int, float, np.integer, np.floating)) and np.isfinite(f_target)
    ):
        raise InvalidArgumentError(f"f_target must be a finite number, got {f_target!r}")
    start = None if x0 is None else _check_x0(x0, lo, hi)
    rng = make_rng(seed)
    ev = Evaluator(
        objective,
        lo,
        hi,
        max_evals=max_evals,
        time_limit=time_limit,
        f_target=f_target,
        q0=start,
    )
    t0 = time.perf_counter()
    spec.run(ev, rng, **kwargs)
    return OptimizeResult(
        x=ev.best_x.copy(),
        fun=float(ev.best_f),
        n_evals=ev.n_evals,
        time_s=time.perf_counter() - t0,
        history=np.asarray(ev.history, dtype=float),
    )
