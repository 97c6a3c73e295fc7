"""The contract between the solvers and the rest of swarm_ik.

A solver is a plain function ``run(ev, rng, *, <its parameters>) -> None``:

* ``ev`` is an :class:`Evaluator`: the only way a solver may evaluate the objective.  It knows
  the bounds, counts evaluations, enforces ``max_evals`` (exactly: it never evaluates more rows
  than the budget allows) and ``time_limit``, turns NaN/inf into ``+inf``, remembers the best
  point ever evaluated and records the history of the best fitness.
* ``rng`` is a :class:`numpy.random.Generator`; a solver takes all its randomness from it.
* The keyword-only parameters with their defaults are the solver's parameters; the registry
  refuses any other name.

A solver loops until ``ev.done`` (budget spent, time up, or the stop criterion met) or until its
own iteration count ends, calling ``ev.end_iteration()`` once per iteration so the history has one
entry per iteration.  Whatever it returns is ignored: the answer is ``ev.best_x``.
"""

from __future__ import annotations

import inspect
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from swarm_ik.errors import InvalidArgumentError, unknown

if TYPE_CHECKING:
    from swarm_ik.problem import IKProblem

FloatArray = NDArray[np.float64]
_UNLIMITED = int(np.iinfo(np.int64).max)
MIN_POP_SIZE = 4
"""Smallest ``pop_size`` any population solver accepts (HLFOA needs 4 distinct members)."""
Objective = Callable[[FloatArray], FloatArray]
"""A batched objective: ``(pop, n) -> (pop,)``; lower is better."""


class Evaluator:
    """Budgeted, counting, NaN-safe access to a batched objective.

    Args:
        objective: Batched objective ``(pop, n) -> (pop,)``.
        lower: Lower bounds, shape ``(n,)``.
        upper: Upper bounds, shape ``(n,)``.
        max_evals: Most evaluations allowed (``None``: unlimited, the solver's own iteration
            count ends the run).
        time_limit: Wall-clock limit in seconds (``None``: none).
        problem: The IK problem behind the objective, if any; Jacobian-based solvers need it.
        q0: Optional starting point, shape ``(n,)``, inside the bounds.
        stop: Optional predicate on the best point; when it returns True the run is done
            (e.g. "position and rotation errors within tolerance").
        f_target: Optional fitness value; reaching it (``<=``) ends the run.
        tolerance: Optional ``(tol_pos [m], tol_rot [rad])`` of the success test behind
            ``stop``, for solvers that stop their own compiled loops at it (``None``: unknown).
    """

    def __init__(
        self,
        objective: Objective,
        lower: FloatArray,
        upper: FloatArray,
        *,
        max_evals: int | None = None,
        time_limit: float | None = None,
        problem: IKProblem | None = None,
        q0: FloatArray | None = None,
        stop: Callable[[FloatArray], bool] | None = None,
        f_target: float | None = None,
        tolerance: tuple[float, float] | None = None,
    ) -> None:
        self.objective = objective
        self.tolerance = tolerance
        self.lower = np.asarray(lower, dtype=float)
        self.upper = np.asarray(upper, dtype=float)
        self.dim = int(self.lower.shape[0])
        self.max_evals = max_evals
        self.time_limit = time_limit
        self.problem = problem
        self.wrap_mask = (
            problem.robot.continuous_mask if problem is not None else np.zeros(self.dim, bool)
        )
        self.q0 = None if q0 is None else np.asarray(q0, dtype=float)
        self._stop = stop
        self.f_target = f_target
        self.n_evals = 0
        self.best_x: FloatArray = (
            self.q0.copy() if self.q0 is not None else 0.5 * (self.lower + self.upper)
        )
        self.best_f = np.inf
        self.history: list[float] = []
        self.stopped = False  # the stop criterion was met
        self.t0 = time.perf_counter()

    # ----------------------------------------------------------------- budget
    @property
    def elapsed(self) -> float:
        """Seconds since the evaluator was created."""
        return time.perf_counter() - self.t0

    @property
    def remaining(self) -> int:
        """Evaluations left in the budget (a large number when unlimited)."""
        if self.max_evals is None:
            return _UNLIMITED
        return max(0, self.max_evals - self.n_evals)

    @property
    def stops_on_success(self) -> bool:
        """Whether the run ends at the success criterion (False: the whole budget runs)."""
        return self._stop is not None or self.f_target is not None

    @property
    def time_up(self) -> bool:
        """Whether the time limit has passed."""
        return self.time_limit is not None and self.elapsed >= self.time_limit

    @property
    def done(self) -> bool:
        """True when the budget is spent, the time is up, or the stop criterion was met."""
        return self.stopped or self.remaining <= 0 or self.time_up

    # ------------------------------------------------------------- evaluation
    def __call__(self, x_batch: FloatArray) -> FloatArray:
        """Evaluate a population.

        Args:
            x_batch: Points, shape ``(pop, n)``.

        Returns:
            Fitness, shape ``(pop,)``.  Rows beyond the remaining budget (or after the time
            limit) are not evaluated and get ``+inf``; NaN and ``-inf``/``+inf`` results
            become ``+inf``.
        """
        x_batch = np.asarray(x_batch, dtype=float)
        pop = x_batch.shape[0]
        out = np.full(pop, np.inf)
        k = 0 if self.time_up or self.stopped else min(pop, self.remaining)
        if k <= 0:
            return out
        f = np.asarray(self.objective(x_batch[:k]), dtype=float)
        if f.size != k:
            raise InvalidArgumentError(
                f"the objective returned shape {f.shape} for {k} points; a batched objective "
                "maps (pop, n) -> (pop,)"
            )
        f = f.reshape(k)
        self.n_evals += k
        f = np.where(np.isfinite(f), f, np.inf)
        out[:k] = f
        self._update_best(x_batch[:k], f)
        return out

    def residual_jacobian(self, q_batch: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Fitness, pose error twist and Jacobian of an IK problem, counted as evaluations.

        Args:
            q_batch: Joint vectors, shape ``(pop, n)``; ``pop`` must fit in the budget.

        Returns:
            ``(fitness (pop,), err (pop, 6), jac (pop, 6, n))`` as
            :meth:`swarm_ik.problem.IKProblem.residual_jacobian`.
        """
        if self.problem is None:
            raise InvalidArgumentError(
                "this solver needs the Jacobian of an IK problem; it cannot run on a plain "
                "objective"
            )
        q_batch = np.atleast_2d(np.asarray(q_batch, dtype=float))
        k = min(q_batch.shape[0], self.remaining)
        if k < q_batch.shape[0]:
            raise InvalidArgumentError(
                f"residual_jacobian asked for {q_batch.shape[0]} evaluations but only {k} remain"
            )
        f, err, jac = self.problem.residual_jacobian(q_batch)
        self.n_evals += k
        f = np.where(np.isfinite(f), f, np.inf)
        self._update_best(q_batch, f)
        return f, err, jac

    def record(self, x_batch: FloatArray, f: FloatArray) -> FloatArray:
        """Count evaluations that a solver computed itself (e.g. with Pinocchio calls).

        Only rows within the remaining budget are counted and considered for the best; the
        caller must compute ``f`` with the problem's own fitness.

        Args:
            x_batch: Points, shape ``(pop, n)``.
            f: Their fitness, shape ``(pop,)``.

        Returns:
            The fitness with NaN/inf and rows past the budget mapped to ``+inf``.
        """
        x_batch = np.atleast_2d(np.asarray(x_batch, dtype=float))
        f = np.asarray(f, dtype=float).reshape(x_batch.shape[0])
        out = np.full(f.shape, np.inf)
        k = 0 if self.time_up or self.stopped else min(f.shape[0], self.remaining)
        if k <= 0:
            return out
        self.n_evals += k
        out[:k] = np.where(np.isfinite(f[:k]), f[:k], np.inf)
        self._update_best(x_batch[:k], out[:k])
        return out

    def add_evals(self, n: int, x: FloatArray | None = None, f: float | None = None) -> None:
        """Count ``n`` evaluations a solver made itself (e.g. in a compiled kernel), and
        offer the best point among them.

        The caller must check :attr:`done` before starting the work and must not compute more
        than :attr:`remaining` evaluations; work started before the time limit is counted and
        its point considered even if the limit passed meanwhile.

        Args:
            n: Evaluations spent, ``0 <= n <= remaining``.
            x: Optional point, shape ``(dim,)``, inside the bounds.
            f: Its fitness under the problem's own fitness (required with ``x``).

        Raises:
            InvalidArgumentError: ``n`` is negative or exceeds the remaining budget, or ``x``
                comes without ``f``.
        """
        n = int(n)
        if n < 0 or n > self.remaining:
            raise InvalidArgumentError(
                f"add_evals: n must be in [0, {self.remaining}] (the remaining budget), got {n}"
            )
        self.n_evals += n
        if x is None:
            return
        if f is None:
            raise InvalidArgumentError("add_evals: a point x needs its fitness f")
        if self.stopped:
            return
        fx = float(f) if np.isfinite(f) else np.inf
        self._update_best(np.asarray(x, dtype=float).reshape(1, self.dim), np.array([fx]))

    def _update_best(self, x_batch: FloatArray, f: FloatArray) -> None:
        i = int(np.argmin(f))
        if f[i] < self.best_f:
            self.best_f = float(f[i])
            self.best_x = x_batch[i].copy()
            if self.f_target is not None and self.best_f <= self.f_target:
                self.stopped = True
            elif self._stop is not None and self._stop(self.best_x):
                self.stopped = True

    def end_iteration(self) -> None:
        """Record the best fitness so far as one entry of the history."""
        self.history.append(self.best_f)

    # ---------------------------------------------------------------- helpers
    def uniform(self, rng: np.random.Generator, n: int) -> FloatArray:
        """``n`` points drawn uniformly within the bounds, shape ``(n, dim)``."""
        return rng.uniform(self.lower, self.upper, size=(n, self.dim))

    def initial_population(self, rng: np.random.Generator, n: int) -> FloatArray:
        """Uniform initial population of ``n`` points; row 0 is ``q0`` when one was given."""
        x = self.uniform(rng, n)
        if self.q0 is not None and n > 0:
            x[0] = self.q0
        return x

    def clip(self, x: FloatArray) -> FloatArray:
        """Points clipped to the bounds (same shape); continuous joints are wrapped into
        ``[-π, π)`` first, so a step across ±π comes out on the other side."""
        if self.wrap_mask.any():
            x = np.array(x, dtype=float)
            m = self.wrap_mask
            x[..., m] = (x[..., m] + np.pi) % (2 * np.pi) - np.pi
        return np.clip(x, self.lower, self.upper)

    def resample_out_of_bounds(self, rng: np.random.Generator, x: FloatArray) -> FloatArray:
        """Replace each out-of-bound component by a uniform draw in its range (eq. 12, 000)."""
        bad = (x < self.lower) | (x > self.upper)
        if not bad.any():
            return x
        fresh = self.lower + (self.upper - self.lower) * rng.random(x.shape)
        return np.where(bad, fresh, x)


@dataclass(frozen=True)
class SolverSpec:
    """A registered solver.

    Attributes:
        name: Registry name, e.g. ``"pso-improved"``.
        run: The solver function ``run(ev, rng, **params)``.
        params: Default value of every parameter, registration overrides applied.
        description: One line for listings.
        needs_jacobian: True when the solver needs an IK problem (not a plain objective).
        closed_form: True for a closed-form solver of particular chains (``analytic``): not
            a search over any objective, so the contract of :func:`search_names` does not
            apply to it.
    """

    name: str
    run: Callable[..., Any]
    params: Mapping[str, Any] = field(default_factory=dict)
    description: str = ""
    needs_jacobian: bool = False
    closed_form: bool = False

    def resolve(self, overrides: Mapping[str, Any]) -> dict[str, Any]:
        """Defaults updated with ``overrides``; unknown names are refused, listing valid ones.

        The sizes shared by the population solvers are checked here, for every solver that
        has them: ``pop_size`` must be an integer ``>= MIN_POP_SIZE`` and ``iterations`` an
        integer ``>= 1``.

        Raises:
            InvalidArgumentError: an unknown parameter name, or a bad ``pop_size`` /
                ``iterations``.
        """
        bad = [k for k in overrides if k not in self.params]
        if bad:
            valid = ", ".join(sorted(self.params)) or "(none)"
            raise InvalidArgumentError(
                f"unknown parameter(s) {', '.join(map(repr, bad))} for solver {self.name!r}; "
                f"its parameters: {valid}"
            )
        out = {**self.params, **overrides}
        for key, least in (("pop_size", MIN_POP_SIZE), ("iterations", 1)):
            if key not in out:
                continue
            v = out[key]
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < least:
                raise InvalidArgumentError(
                    f"{key} must be >= {least} (an integer) for solver {self.name!r}, got {v!r}"
                )
        return out


_REGISTRY: dict[str, SolverSpec] = {}


def register(
    name: str,
    run: Callable[..., Any],
    *,
    description: str = "",
    needs_jacobian: bool = False,
    closed_form: bool = False,
    **overrides: Any,
) -> SolverSpec:
    """Register ``run`` under ``name``; keyword ``overrides`` change its parameter defaults.

    A variant is a registration of the same function with other overrides, never a copy.

    Raises:
        InvalidArgumentError: ``name`` is already registered, or an override is not a
            keyword-only parameter of ``run``.
    """
    if name in _REGISTRY:
        raise InvalidArgumentError(f"solver {name!r} is already registered")
    sig = inspect.signature(run)
    defaults = {
        p.name: p.default
        for p in sig.parameters.values()
        if p.kind is inspect.Parameter.KEYWORD_ONLY
    }
    spec = SolverSpec(name, run, defaults, description, needs_jacobian, closed_form)
    spec = SolverSpec(
        name, run, spec.resolve(overrides), description, needs_jacobian, closed_form
    )
    _REGISTRY[name] = spec
    return spec


def names() -> list[str]:
    """Names of all registered solvers, sorted."""
    return sorted(_REGISTRY)


def search_names() -> list[str]:
    """Names of the registered search solvers (every solver but the closed-form ones),
    sorted: those that minimise any problem's cost within a budget."""
    return sorted(n for n, s in _REGISTRY.items() if not s.closed_form)


def get(name: str) -> SolverSpec:
    """The solver registered under ``name``.

    Raises:
        UnknownNameError: no such solver; the message lists the registered ones.
    """
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):  # TypeError: an unhashable name such as a list
        raise unknown("solver", name, _REGISTRY) from None
