"""The contract between the solvers and the rest of swarm_ik.

A solver is a plain function ``run(ev, rng, *, <its parameters>) -> None``:

* ``ev`` is an :class:`Evaluator`: the only way a solver may evaluate the objective.  It knows
  the bounds, counts evaluations, enforces ``max_evals`` (exactly: it never evaluates more rows
  than the budget allows) and ``time_limit``, turns NaN/inf into ``+inf``, remembers the best
  point ever evaluated (telling ``on_improvement`` each time it improves) and records the
  history of the best fitness.
* ``rng`` is a :class:`numpy.random.Generator`; a solver takes all its randomness from it.
* The keyword-only parameters with their defaults are the solver's parameters; the registry
  refuses any other name.

A solver loops until ``ev.done`` (budget spent, time up, or the stop criterion met) or until its
own iteration count ends, calling ``ev.end_iteration()`` once per iteration so the history has one
entry per iteration.  Whatever it returns is ignored: the answer is ``ev.best_x``.
"""

from __future__ import annotations

import inspect
import re
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from swarm_ik._types import FloatArray
from swarm_ik._validate import INT_PARAM_MAX, plain_number
from swarm_ik.errors import InvalidArgumentError, unknown
from swarm_ik.kernels import raise_lost_ctrl_c

if TYPE_CHECKING:
    from swarm_ik.problem import IKProblem

_UNLIMITED = int(np.iinfo(np.int64).max)
MIN_POP_SIZE = 4
"""Smallest ``pop_size`` any population solver accepts (HLFOA needs 4 distinct members)."""
MAX_POP_SIZE = 1_000_000
"""Largest ``pop_size`` any solver accepts."""
MAX_ITERATIONS = 1_000_000
"""Largest ``iterations`` any solver accepts (a million generations of a population of 30 run
for minutes; a ``time_limit`` bounds a solve of any length)."""
MAX_POPULATION_VALUES = 10_000_000
"""Largest ``pop_size · dim`` (numbers in one population array: 80 MB of float64; a solver
keeps a few such arrays).  Checked by :meth:`SolverSpec.resolve` when it is given ``dim`` and
by :meth:`Evaluator.uniform` / :meth:`Evaluator.initial_population` before allocating."""

TIMED_CHUNK = 4096
"""Most rows an :class:`Evaluator` with a time limit evaluates between two reads of the clock
(a few milliseconds of FK for a 7-joint arm; without a time limit a population is one call)."""
BLOCK_SECONDS = 2e-3
"""[s] What one block of rows of an :class:`Evaluator` with a time limit should take: its
blocks start at one row and follow the cost per row measured on the earlier ones (a compiled
fitness of a microsecond a row: blocks of 2,000 rows; a Python goal of 50 ms a call: one row
a block), so that the clock is read about this often, or after every row of a slow
objective."""
Objective = Callable[[FloatArray], FloatArray]
"""A batched objective: ``(pop, n) -> (pop,)``; lower is better."""


class Evaluator:
    """Budgeted, counting, NaN-safe access to a batched objective.

    **One rule for the budget.**  There are two ways evaluations happen, and each has one rule:

    * *The evaluator evaluates* (:meth:`__call__`, :meth:`residual_jacobian`): once
      :attr:`done` nothing is evaluated; otherwise the first ``min(pop, remaining)`` rows are
      evaluated and charged, and the rows past the budget are not evaluated (fitness ``+inf``;
      error and Jacobian NaN).  The budget is never overdrawn.
    * *The solver evaluated itself* and charges it (:meth:`record`, :meth:`add_evals`): the
      solver checks :attr:`done` before starting and computes at most :attr:`remaining`
      evaluations; charging more raises :class:`InvalidArgumentError` (a solver bug, never
      clipped silently).  Work started in time is charged and its points offered even when
      the time limit passed meanwhile.

    Either way every evaluated point is offered for the best (NaN/inf fitness as ``+inf``),
    and no point is taken any more once the stop criterion was met: the answer is the first
    point that met it.  Each time the best improves, ``on_improvement(x, f)`` is called.

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
        on_improvement: Optional callback ``(x (n,), f)`` called each time the best point
            improves (``x`` is a copy), e.g. to record a convergence trace
            (:class:`swarm_ik.viz.TraceRecorder`).
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
        on_improvement: Callable[[FloatArray, float], Any] | None = None,
        key: Any = None,
    ) -> None:
        self.objective = objective
        self.key = key
        """The random-stream key of a compiled search when the solve's seed fixed it (an
        integer seed: :func:`swarm_ik.kernels.search.key_of_seed`), else None (a solver draws
        one from its Generator)."""
        self.on_improvement = on_improvement
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
        self._row_s: float | None = None  # (seconds per row measured: see _block)

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
    def _granted(self, pop: int) -> int:
        """Rows of a request of ``pop`` the evaluator evaluates: none once :attr:`done`,
        else at most :attr:`remaining`.  Every request of a solver passes here: where a
        Ctrl-C that the work lost on its way is raised again
        (:func:`swarm_ik.kernels.raise_lost_ctrl_c`; a paper solver's loop ran on to its
        budget after 1 of 25 Ctrl-Cs)."""
        raise_lost_ctrl_c()
        return 0 if self.done else min(pop, self.remaining)

    def __call__(self, x_batch: FloatArray) -> FloatArray:
        """Evaluate a population (the first rule of the class docstring).

        Args:
            x_batch: Points, shape ``(pop, n)``.

        Returns:
            Fitness, shape ``(pop,)``.  Rows beyond the remaining budget (or after the time
            limit) are not evaluated and get ``+inf``; NaN and ``-inf``/``+inf`` results
            become ``+inf``.
        """
        x_batch = np.asarray(x_batch, dtype=float)
        out = np.full(x_batch.shape[0], np.inf)
        k = self._granted(x_batch.shape[0])
        a = 0
        while a < k and not (a > 0 and self.time_up):  # (one block without a time limit)
            b = a + self._block(k - a)
            t = time.perf_counter()
            f = np.asarray(self.objective(x_batch[a:b]), dtype=float)
            self._measured(b - a, time.perf_counter() - t)
            if f.size != b - a:
                raise InvalidArgumentError(
                    f"the objective returned shape {f.shape} for {b - a} points; a batched "
                    "objective maps (pop, n) -> (pop,)"
                )
            out[a:b] = f.reshape(b - a)
            a = b
        out[:a] = self._charge(a, x_batch[:a], out[:a])
        return out

    def _block(self, left: int) -> int:
        """Rows of the next block of a request with ``left`` rows to go: all of them without
        a time limit; under one, as many as :data:`BLOCK_SECONDS` allows at the cost per row
        measured so far (one row before any was measured; at most :data:`TIMED_CHUNK`), so
        that the clock is read between blocks often enough for a slow objective (a Python
        goal of 50 ms a call) and seldom for a fast one.  The rows evaluated are offered for
        the best together at the end of the request, so the blocks change nothing but when
        the time limit is seen."""
        if self.time_limit is None:
            return left
        if self._row_s is None:
            return 1
        return max(1, min(left, TIMED_CHUNK, int(BLOCK_SECONDS / max(self._row_s, 1e-9))))

    def _measured(self, rows: int, seconds: float) -> None:
        """Note the seconds a block of ``rows`` rows took (the cost per row of :meth:`_block`:
        the latest block's, or half the earlier estimate when that is higher, so that one
        fast block does not size the next for a slow objective at once)."""
        if self.time_limit is None or rows <= 0:
            return
        per = seconds / rows
        self._row_s = per if self._row_s is None else max(per, 0.5 * self._row_s)

    def residual_jacobian(self, q_batch: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Fitness, pose error twist and Jacobian of an IK problem, counted as evaluations
        (the first rule of the class docstring).

        Args:
            q_batch: Joint vectors, shape ``(pop, n)``.

        Returns:
            ``(fitness (pop,), err (pop, rows), jac (pop, rows, n))`` as
            :meth:`swarm_ik.problem.IKProblem.residual_jacobian`; rows not evaluated (past
            the budget, or once :attr:`done`) have fitness ``+inf`` and NaN error and Jacobian.

        Raises:
            InvalidArgumentError: the evaluator has no IK problem.
        """
        if self.problem is None:
            raise InvalidArgumentError(
                "this solver needs the Jacobian of an IK problem; it cannot run on a plain "
                "objective"
            )
        q_batch = np.atleast_2d(np.asarray(q_batch, dtype=float))
        pop = q_batch.shape[0]
        k = self._granted(pop)
        parts = []
        a = 0
        while a < k and not (a > 0 and self.time_up):  # (blocks as in __call__)
            b = a + self._block(k - a)
            t = time.perf_counter()
            parts.append(self.problem.residual_jacobian(q_batch[a:b]))
            self._measured(b - a, time.perf_counter() - t)
            a = b
        if not parts:  # (nothing evaluated: the shapes only)
            parts.append(self.problem.residual_jacobian(q_batch[:0]))
        ek, jk = parts[0][1], parts[0][2]
        f = np.full(pop, np.inf)
        err = np.full((pop, *np.shape(ek)[1:]), np.nan)
        jac = np.full((pop, *np.shape(jk)[1:]), np.nan)
        if a:
            f[:a] = np.concatenate([np.asarray(p[0], dtype=float) for p in parts])
            err[:a] = np.concatenate([p[1] for p in parts])
            jac[:a] = np.concatenate([p[2] for p in parts])
            f[:a] = self._charge(a, q_batch[:a], f[:a])
        return f, err, jac

    def record(self, x_batch: FloatArray, f: FloatArray) -> FloatArray:
        """Charge evaluations that a solver computed itself (e.g. with Pinocchio calls) and
        offer their points (the second rule of the class docstring).

        The caller must compute ``f`` with the problem's own fitness.

        Args:
            x_batch: Points, shape ``(pop, n)``, ``pop <= remaining``.
            f: Their fitness, shape ``(pop,)``.

        Returns:
            The fitness with NaN/inf mapped to ``+inf``.

        Raises:
            InvalidArgumentError: ``pop`` exceeds the remaining budget.
        """
        x_batch = np.atleast_2d(np.asarray(x_batch, dtype=float))
        f = np.asarray(f, dtype=float).reshape(x_batch.shape[0])
        return self._charge(x_batch.shape[0], x_batch, f, who="record")

    def add_evals(self, n: int, x: FloatArray | None = None, f: float | None = None) -> None:
        """Charge ``n`` evaluations a solver made itself (e.g. in a compiled kernel), and
        offer the best point among them (the second rule of the class docstring).

        Args:
            n: Evaluations spent, ``0 <= n <= remaining``.
            x: Optional point, shape ``(dim,)``, inside the bounds.
            f: Its fitness under the problem's own fitness (required with ``x``).

        Raises:
            InvalidArgumentError: ``n`` is negative or exceeds the remaining budget, or ``x``
                comes without ``f``.
        """
        if x is not None and f is None:
            raise InvalidArgumentError("add_evals: a point x needs its fitness f")
        if x is None:
            self._charge(int(n), None, None, who="add_evals")
        else:
            xb = np.asarray(x, dtype=float).reshape(1, self.dim)
            self._charge(int(n), xb, np.array([f], dtype=float), who="add_evals")

    def _charge(
        self, n: int, x_batch: FloatArray | None, f: FloatArray | None, who: str = ""
    ) -> FloatArray:
        """The one place evaluations are charged: add ``n`` to the count (refusing an
        overdraft), map NaN/inf fitness to ``+inf`` and offer the points for the best.

        Returns:
            The cleaned fitness (empty without points).
        """
        if n < 0 or n > self.remaining:
            raise InvalidArgumentError(
                f"{who or 'evaluate'}: {n} evaluations charged but the remaining budget is "
                f"{self.remaining}; n must be in [0, {self.remaining}]"
            )
        self.n_evals += n
        if x_batch is None or f is None:
            return np.empty(0)
        f = np.where(np.isfinite(f), f, np.inf)
        if f.size and not self.stopped:
            self._update_best(x_batch, f)
        return f

    def _update_best(self, x_batch: FloatArray, f: FloatArray) -> None:
        i = int(np.argmin(f))
        if f[i] < self.best_f:
            self.best_f = float(f[i])
            self.best_x = x_batch[i].copy()
            if self.on_improvement is not None:
                self.on_improvement(self.best_x.copy(), self.best_f)
            if self.f_target is not None and self.best_f <= self.f_target:
                self.stopped = True
            elif self._stop is not None and self._stop(self.best_x):
                self.stopped = True

    def end_iteration(self) -> None:
        """Record the best fitness so far as one entry of the history."""
        self.history.append(self.best_f)

    # ---------------------------------------------------------------- helpers
    def uniform(self, rng: np.random.Generator, n: int) -> FloatArray:
        """``n`` points drawn uniformly within the bounds, shape ``(n, dim)``.

        Raises:
            InvalidArgumentError: ``n · dim`` exceeds :data:`MAX_POPULATION_VALUES`.
        """
        check_population(n, self.dim)
        return rng.uniform(self.lower, self.upper, size=(n, self.dim))

    def initial_population(self, rng: np.random.Generator, n: int) -> FloatArray:
        """Uniform initial population of ``n`` points; row 0 is ``q0`` when one was given."""
        x = self.uniform(rng, n)
        if self.q0 is not None and n > 0:
            x[0] = self.q0
        return x

    def wrapped(self, x: FloatArray) -> FloatArray:
        """Points with their continuous joints wrapped into ``[-π, π)`` (same shape; ``x``
        itself when there are none)."""
        if self.wrap_mask.any():
            x = np.array(x, dtype=float)
            m = self.wrap_mask
            x[..., m] = (x[..., m] + np.pi) % (2 * np.pi) - np.pi
        return x

    def clip(self, x: FloatArray) -> FloatArray:
        """Points clipped to the bounds (same shape); continuous joints are wrapped into
        ``[-π, π)`` first (:meth:`wrapped`), so a step across ±π comes out on the other side
        (a continuous joint's narrower bounds, if any, then clip it)."""
        return np.clip(self.wrapped(x), self.lower, self.upper)

    def resample_out_of_bounds(self, rng: np.random.Generator, x: FloatArray) -> FloatArray:
        """Replace each out-of-bound component by a uniform draw in its range ([HLFOA], eq. 12)."""
        bad = (x < self.lower) | (x > self.upper)
        if not bad.any():
            return x
        fresh = self.lower + (self.upper - self.lower) * rng.random(x.shape)
        return np.where(bad, fresh, x)


def check_population(pop_size: int, dim: int, solver: str | None = None) -> None:
    """Refuse a population too large to allocate: ``pop_size · dim`` above
    :data:`MAX_POPULATION_VALUES`.

    Raises:
        InvalidArgumentError: naming both numbers and the cap.
    """
    if int(pop_size) * max(int(dim), 1) > MAX_POPULATION_VALUES:
        who = f" for solver {solver!r}" if solver else ""
        raise InvalidArgumentError(
            f"pop_size {int(pop_size)} x {int(dim)} joints = {int(pop_size) * int(dim)} values "
            f"per population array{who} exceeds the cap of {MAX_POPULATION_VALUES} "
            f"(swarm_ik.solvers.base.MAX_POPULATION_VALUES); use a smaller pop_size"
        )


_INTERVAL = re.compile(
    r"^\s*([\[(])\s*([-+]?(?:inf|[0-9.]+(?:e[-+]?[0-9]+)?))\s*,\s*"
    r"([-+]?(?:inf|[0-9.]+(?:e[-+]?[0-9]+)?))\s*([\])])\s*$",
    re.IGNORECASE,
)
_NAMED = {
    "finite": "(-inf, inf)",
    "positive": "(0, inf)",
    "nonnegative": "[0, inf)",
    "unit": "[0, 1]",
}


@dataclass(frozen=True)
class Constraint:
    """What values a solver parameter accepts.

    Build one with :meth:`parse` from a short spec:

    * floats (always finite; ints are accepted and converted): ``"finite"``, ``"positive"``
      (``> 0``), ``"nonnegative"`` (``>= 0``), ``"unit"`` (``[0, 1]``) or an interval such as
      ``"(0, 1]"``, ``"(0, 2)"``, ``"[0, 1e3]"``;
    * integers (booleans refused): ``"int"`` or ``"int>=N"``;
    * ``"bool"``; ``"str"``; ``"choice:a|b"`` (one of the strings).

    Attributes:
        kind: ``"float"``, ``"int"``, ``"bool"``, ``"str"``.
        lo: Lower bound (floats and ints).
        hi: Upper bound (floats).
        lo_open: Whether ``lo`` itself is excluded.
        hi_open: Whether ``hi`` itself is excluded.
        choices: Accepted strings (empty: any).
    """

    kind: str
    lo: float = -np.inf
    hi: float = np.inf
    lo_open: bool = True
    hi_open: bool = True
    choices: tuple[str, ...] = ()

    @classmethod
    def parse(cls, spec: str | Constraint) -> Constraint:
        """The constraint of a spec string (see the class docstring).

        Raises:
            InvalidArgumentError: an unknown spec.
        """
        if isinstance(spec, Constraint):
            return spec
        text = _NAMED.get(spec, spec)
        m = _INTERVAL.match(text)
        if m:
            return cls(
                "float", float(m.group(2)), float(m.group(3)), m.group(1) == "(", m.group(4) == ")"
            )
        if text == "int":
            return cls("int")
        if text.startswith("int>="):
            return cls("int", lo=float(int(text[5:])), lo_open=False)
        if text in ("bool", "str"):
            return cls(text)
        if text.startswith("choice:"):
            return cls("str", choices=tuple(text[7:].split("|")))
        raise InvalidArgumentError(f"unknown parameter constraint {spec!r}")

    @classmethod
    def infer(cls, default: Any) -> Constraint | None:
        """The constraint implied by a default value's type (``None`` for other types)."""
        if isinstance(default, (bool, np.bool_)):
            return cls("bool")
        if isinstance(default, (int, np.integer)):
            return cls("int")
        if isinstance(default, (float, np.floating)):
            return cls("float")
        if isinstance(default, str):
            return cls("str")
        return None

    def describe(self) -> str:
        """Words for messages, e.g. ``"a finite number in (0, 1]"``."""
        if self.kind == "bool":
            return "true or false"
        if self.kind == "str":
            if self.choices:
                return "one of " + ", ".join(map(repr, self.choices))
            return "a string"
        if self.kind == "int":
            low = f"{int(self.lo)}" if np.isfinite(self.lo) else f"{-INT_PARAM_MAX - 1}"
            return f"an integer in [{low}, {INT_PARAM_MAX}]"
        lo_inf, hi_inf = not np.isfinite(self.lo), not np.isfinite(self.hi)
        if lo_inf and hi_inf:
            return "a finite number"
        if hi_inf:
            return f"a finite number {'>' if self.lo_open else '>='} {self.lo:g}"
        if lo_inf:
            return f"a finite number {'<' if self.hi_open else '<='} {self.hi:g}"
        return (
            f"a number in {'(' if self.lo_open else '['}{self.lo:g}, {self.hi:g}"
            f"{')' if self.hi_open else ']'}"
        )

    def convert(self, value: Any) -> tuple[bool, Any]:
        """``(ok, value)``: whether ``value`` is accepted, and its normalised form (floats as
        ``float``, integers as ``int``; a 0-d array is its number)."""
        value = plain_number(value)
        if self.kind == "bool":
            if isinstance(value, (bool, np.bool_)):
                return True, bool(value)
            return False, value
        if self.kind == "str":
            ok = isinstance(value, str) and (not self.choices or value in self.choices)
            return ok, value
        if isinstance(value, (bool, np.bool_)):
            return False, value
        if self.kind == "int":
            if not isinstance(value, (int, np.integer)):
                return False, value
            n = int(value)
            low = self.lo if np.isfinite(self.lo) else -INT_PARAM_MAX - 1
            return low <= n <= INT_PARAM_MAX, n
        if not isinstance(value, (int, float, np.integer, np.floating)):
            return False, value
        v = float(value)
        if not np.isfinite(v):
            return False, value
        ok_lo = v > self.lo if self.lo_open else v >= self.lo
        ok_hi = v < self.hi if self.hi_open else v <= self.hi
        return bool(ok_lo and ok_hi), v


SOLVER_CONSTRAINTS: dict[str, dict[str, str]] = {}
"""Constraints of solvers registered in modules that do not declare them themselves
(solver name -> parameter -> spec of :meth:`Constraint.parse`); merged with the
``constraints`` given to :func:`register`."""


_RESOLVED: dict[tuple[str, int, int | None], dict[str, Any]] = {}
"""Checked default parameters per (solver, defaults object, dim)."""


@dataclass(frozen=True)
class SolverSpec:
    """A registered solver.

    Attributes:
        name: Registry name, e.g. ``"pso-improved"``.
        run: The solver function ``run(ev, rng, **params)``.
        params: Default value of every parameter, registration overrides applied.
        description: One line for listings.
        needs_jacobian: True when the solver needs an IK problem (not a plain objective).
        constraints: What each parameter accepts (:class:`Constraint`): declared at
            registration, else inferred from the default's type (a float default: any
            finite number; an int: any integer; a bool; a string).
        closed_form: True for a closed-form solver of particular chains (``analytic``): not
            a search over any objective, so the contract of :func:`search_names` does not
            apply to it.
        paper: Short key of the solver's source in ``docs/references.md`` (e.g. ``"HLFOA"``;
            ``None``: our own).  The benchmarks set that paper's published numbers beside it.
        budget_only: True when the solver takes only an evaluation budget (``max_evals`` /
            ``time_limit``) and no population / iteration schedule worth setting; the
            benchmarks then give it the budget alone.
        evals_per_iteration: Evaluations one of its ``iterations`` costs when that is a fixed
            number independent of the parameters (``1`` for DLS: ``iterations = budget``);
            ``None``: a population schedule (``pop_size`` evaluations per iteration, or
            whatever its docstring says).
    """

    name: str
    run: Callable[..., Any]
    params: Mapping[str, Any] = field(default_factory=dict)
    description: str = ""
    needs_jacobian: bool = False
    constraints: Mapping[str, Constraint] = field(default_factory=dict)
    closed_form: bool = False
    paper: str | None = None
    budget_only: bool = False
    evals_per_iteration: int | None = None

    def schedule(self, budget: int) -> dict[str, Any]:
        """Settings that let this solver spend an evaluation budget: ``max_evals = budget``
        plus, for a solver with a fixed cost per iteration, ``iterations`` to match, or for a
        population solver, enough iterations of its own ``pop_size`` (``⌈budget / pop⌉``).

        Args:
            budget: Evaluations, ``>= 1``.

        Returns:
            Keyword arguments for :func:`swarm_ik.solve` (``max_evals``, maybe ``iterations``,
            at most :data:`MAX_ITERATIONS`).
        """
        if self.evals_per_iteration is not None:
            its = -(-budget // self.evals_per_iteration)
        elif self.budget_only or "pop_size" not in self.params or "iterations" not in self.params:
            return {"max_evals": budget}
        else:
            its = -(-budget // int(self.params["pop_size"]))
        return {"iterations": min(its, MAX_ITERATIONS), "max_evals": budget}

    def resolve(self, overrides: Mapping[str, Any], dim: int | None = None) -> dict[str, Any]:
        """Defaults updated with ``overrides``; unknown names are refused, listing valid ones.

        (Without overrides the checked defaults are cached per ``(solver, dim)``: this runs
        on every solve.)

        Every parameter is checked against its :attr:`constraints` (NaN, infinities,
        strings for numbers, booleans for integers, signs and ranges are refused), and the
        sizes shared by the population solvers for every solver that has them: ``pop_size``
        must be an integer in ``[MIN_POP_SIZE, MAX_POP_SIZE]`` (and ``pop_size · dim`` at
        most :data:`MAX_POPULATION_VALUES` when ``dim`` is given), ``iterations`` an integer
        in ``[1, MAX_ITERATIONS]``.

        Args:
            overrides: Parameter values given by the user.
            dim: Number of variables (joints), when known.

        Raises:
            InvalidArgumentError: an unknown parameter name, or a value its constraint
                refuses (the message names the parameter, the solver and what is accepted).
        """
        if not overrides:
            hit = _RESOLVED.get((self.name, id(self.params), dim))
            if hit is not None:
                return dict(hit)
            out = self._resolve({}, dim)
            _RESOLVED[(self.name, id(self.params), dim)] = dict(out)
            return out
        return self._resolve(overrides, dim)

    def _resolve(self, overrides: Mapping[str, Any], dim: int | None) -> dict[str, Any]:
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
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
                raise InvalidArgumentError(
                    f"{key} must be an integer for solver {self.name!r}, got {v!r} "
                    f"({type(v).__name__})"
                )
            if v < least:
                raise InvalidArgumentError(
                    f"{key} must be >= {least} (an integer) for solver {self.name!r}, got {v!r}"
                )
        if "iterations" in out and out["iterations"] > MAX_ITERATIONS:
            raise InvalidArgumentError(
                f"iterations must be <= {MAX_ITERATIONS} for solver {self.name!r} "
                f"(swarm_ik.solvers.base.MAX_ITERATIONS; time_limit bounds a longer solve), "
                f"got {out['iterations']!r}"
            )
        if "pop_size" in out:
            if out["pop_size"] > MAX_POP_SIZE:
                raise InvalidArgumentError(
                    f"pop_size must be <= {MAX_POP_SIZE} for solver {self.name!r}, got "
                    f"{out['pop_size']!r}"
                )
            if dim is not None:
                check_population(out["pop_size"], dim, self.name)
        for key, con in self.constraints.items():
            if key not in out:
                continue
            ok, v = con.convert(out[key])
            if not ok:
                raise InvalidArgumentError(
                    f"parameter {key} of solver {self.name!r} must be {con.describe()}, "
                    f"got {out[key]!r}"
                )
            out[key] = v
        return out


_REGISTRY: dict[str, SolverSpec] = {}


def register(
    name: str,
    run: Callable[..., Any],
    *,
    description: str = "",
    needs_jacobian: bool = False,
    constraints: Mapping[str, str | Constraint] | None = None,
    closed_form: bool = False,
    paper: str | None = None,
    budget_only: bool = False,
    evals_per_iteration: int | None = None,
    **overrides: Any,
) -> SolverSpec:
    """Register ``run`` under ``name``; keyword ``overrides`` change its parameter defaults.

    A variant is a registration of the same function with other overrides, never a copy.

    Args:
        name: Registry name.
        run: The solver function.
        description: One line for listings.
        needs_jacobian: True when the solver needs an IK problem.
        constraints: Parameter -> spec of :meth:`Constraint.parse` (e.g. ``{"lam0":
            "positive", "pa": "[0, 1]", "subpops": "int>=1"}``), merged over
            :data:`SOLVER_CONSTRAINTS` ``[name]``; parameters without one get the
            constraint inferred from their default (:meth:`Constraint.infer`).
        closed_form: True for a closed-form solver (see :class:`SolverSpec`).
        paper: Short key of the source in ``docs/references.md`` (see :class:`SolverSpec`).
        budget_only: The solver takes only a budget (see :class:`SolverSpec`).
        evals_per_iteration: Fixed evaluations per iteration (see :class:`SolverSpec`).
        **overrides: New defaults.

    Raises:
        InvalidArgumentError: ``name`` is already registered, an override or constraint is
            not a keyword-only parameter of ``run``, or a default breaks its constraint.
    """
    if name in _REGISTRY:
        raise InvalidArgumentError(f"solver {name!r} is already registered")
    sig = inspect.signature(run)
    defaults = {
        p.name: p.default
        for p in sig.parameters.values()
        if p.kind is inspect.Parameter.KEYWORD_ONLY
    }
    declared = {**SOLVER_CONSTRAINTS.get(name, {}), **(constraints or {})}
    stray = sorted(k for k in declared if k not in defaults)
    if stray:
        raise InvalidArgumentError(
            f"constraints for {stray} given, but solver {name!r} has no such parameter"
        )
    cons: dict[str, Constraint] = {}
    for key, default in defaults.items():
        con = Constraint.parse(declared[key]) if key in declared else Constraint.infer(default)
        if con is not None:
            cons[key] = con
    if evals_per_iteration is not None and (
        isinstance(evals_per_iteration, bool) or int(evals_per_iteration) < 1
    ):
        raise InvalidArgumentError(
            f"evals_per_iteration of solver {name!r} must be an integer >= 1 or None, "
            f"got {evals_per_iteration!r}"
        )
    spec = SolverSpec(
        name,
        run,
        defaults,
        description,
        needs_jacobian,
        cons,
        closed_form,
        paper,
        budget_only,
        evals_per_iteration,
    )
    spec = replace(spec, params=spec.resolve(overrides))
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
