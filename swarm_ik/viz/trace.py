"""Convergence traces: the best-so-far configuration after each iteration of a solve.

A :class:`TraceRecorder` is an ``on_improvement(q, f)`` callback of
:class:`swarm_ik.solvers.base.Evaluator`: it keeps every point that improved on the best so
far, whichever way the solver evaluated it (``ev(x)``, ``ev.residual_jacobian``,
``ev.record`` or, for the compiled ``swarm`` solver, ``ev.add_evals(n, x, f)``).
:func:`solve_traced` hands it to :func:`swarm_ik.solve` as ``on_improvement=``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from swarm_ik._types import FloatArray
from swarm_ik.errors import InvalidArgumentError
from swarm_ik.problem import IKProblem
from swarm_ik.result import Result


@dataclass(frozen=True)
class Trace:
    """The optimiser's best-so-far configuration after each iteration of one solve.

    Attributes:
        q: Best-so-far joint vector per iteration (rad / m), shape ``(iterations, nq)``.
        fitness: Its fitness (the solve's ``Result.history``), shape ``(iterations,)``.
        improvements: Number of times the best point improved during the solve.
    """

    q: FloatArray
    fitness: FloatArray
    improvements: int

    def __len__(self) -> int:
        return int(self.q.shape[0])

    def subsample(self, max_frames: int) -> Trace:
        """At most ``max_frames`` iterations, evenly spaced, the first and last kept."""
        if max_frames < 2:
            raise InvalidArgumentError(f"max_frames must be at least 2, got {max_frames}")
        n = len(self)
        if n <= max_frames:
            return self
        idx = np.unique(np.round(np.linspace(0, n - 1, max_frames)).astype(int))
        return Trace(self.q[idx], self.fitness[idx], self.improvements)


class TraceRecorder:
    """``on_improvement(q, f)`` callback keeping each point that beats the best so far.

    Attributes:
        q: The improving points (rad / m), each of shape ``(nq,)``, in order.
        fitness: Their fitness, decreasing.
    """

    def __init__(self) -> None:
        self.q: list[FloatArray] = []
        self.fitness: list[float] = []

    def __call__(self, q: Any, f: float) -> None:
        f = float(f)
        if np.isfinite(f) and (not self.fitness or f < self.fitness[-1]):
            self.q.append(np.array(q, dtype=float, copy=True))
            self.fitness.append(f)

    def offer(self, q_batch: Any, f_batch: Any) -> None:
        """Offer a batch of evaluated points ``(pop, nq)`` with their fitness ``(pop,)``."""
        f = np.asarray(f_batch, dtype=float).reshape(-1)
        if f.size:
            f = np.where(np.isfinite(f), f, np.inf)
            i = int(np.argmin(f))
            self(np.atleast_2d(q_batch)[i], f[i])


def solve_traced(
    problem: IKProblem, solver: str | None = None, **solve_kwargs: Any
) -> tuple[Result, Trace]:
    """:func:`swarm_ik.solve`, also returning the best-so-far configuration per iteration.

    Only for watching a solve: the recording adds a copy of ``q`` per improvement.

    Args:
        problem: The problem.
        solver: Registry name (default: :data:`swarm_ik.api.DEFAULT_SOLVER`).
        **solve_kwargs: Passed to :func:`swarm_ik.solve` (``seed``, ``max_evals``, ``q0``, …).

    Returns:
        The result and its :class:`Trace` (one row per entry of ``result.history``, plus the
        final ``q`` when the history did not record it; at least one row).
    """
    from swarm_ik.api import DEFAULT_SOLVER, solve

    rec = TraceRecorder()
    name = solver or DEFAULT_SOLVER
    result = solve(problem, name, on_improvement=rec, **solve_kwargs)
    trail = np.array(rec.q, dtype=float).reshape(-1, problem.nq)
    history = np.asarray(result.history, dtype=float)
    if trail.shape[0] == 0 or history.size == 0:
        return result, Trace(result.q[None].copy(), np.array([result.fitness]), len(rec.q))
    f_trail = np.asarray(rec.fitness)
    # the best point after iteration i is the first recorded one whose fitness reached
    # history[i] (the solver's own arithmetic may differ from the problem's in the last bits)
    rows = np.empty(history.size, dtype=int)
    for i, h in enumerate(history):
        tol = 1e-9 * (1.0 + abs(h)) if np.isfinite(h) else 0.0
        above = np.count_nonzero(f_trail > h + tol) if np.isfinite(h) else 0
        rows[i] = min(above, trail.shape[0] - 1)
    q_frames = trail[rows]
    if not np.allclose(q_frames[-1], result.q):  # a final step the history did not record
        q_frames = np.vstack([q_frames, result.q])
        history = np.append(history, result.fitness)
    return result, Trace(q_frames, history, len(rec.q))
