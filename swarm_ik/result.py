"""The frozen outcome of an IK solve."""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from swarm_ik._types import FloatArray


@dataclass(frozen=True, eq=False, init=False)
class Result:
    """What :func:`swarm_ik.solve` returns.

    The errors are recomputed with Pinocchio's own forward kinematics (not the solver's
    batched kernel), so they can be trusted independently of the solver.

    The arrays ``q`` and ``history`` are read-only copies (float64) made at construction,
    whatever route builds the Result (its constructor, :func:`dataclasses.replace`,
    :mod:`copy`, :mod:`pickle`): a result cannot change after its errors were judged for its
    ``q``.  ``r.q[0] = 1.0`` raises ``ValueError``, and a later change to the array given to
    the constructor does not reach the result; ``r.q.copy()`` gives a writable copy.  Results
    compare and hash by identity (``==`` of the arrays field by field was ambiguous).

    Attributes:
        q: Best joint vector found (rad / m, one value per joint), shape ``(nq,)``.
        fitness: Its fitness under the problem's fitness function.
        position_error: ‖p − p_target‖ [m]: the largest position error over the primary
            goals (:func:`swarm_ik.problem.largest_errors`); 0.0 when no primary goal has a
            position error (e.g. only ``Orientation`` or ``Axis`` goals).
        rotation_error: Geodesic angle between reached and target orientation [rad]: the
            largest angular error over the primary goals; 0.0 when no primary goal has an
            angular error (a position-only problem, ``w_rot=0``, or only ``Position`` goals):
            then 0.0 means "nothing to measure", not a measured zero.  ``goal_errors`` tells
            the two apart (NaN where a goal has no such error), and the command line prints
            ``n/a`` (``null`` in ``--json``) with ``--position-only``.
        n_evals: Fitness evaluations spent (a Jacobian evaluation counts as one).
        time_s: Wall-clock seconds of the search, the solver's own time [s]: what the call
            adds around it (the judge with Pinocchio, tens of µs; a first call's kernel
            loading, charged to ``time_limit`` up to half of it) is not counted: time the
            call for those.
        success: Both errors within the tolerances given to ``solve`` (rotation ignored for
            position-only problems) and ``within_limits``.
        within_limits: ``q`` lies within the problem's bounds.
        history: Best fitness after each iteration of the solver, shape ``(iterations,)``.
        solver: Registry name of the solver.
        seed: The seed used (``None`` if a Generator was passed).
        goal_errors: Per primary goal, its errors [m, rad] computed with Pinocchio and
            whether it is met (:class:`swarm_ik.problem.GoalError`).
        reason: Why the solve ended: ``"converged"`` (success), ``"budget"`` (the
            evaluation budget ran out), ``"time_limit"``, ``"local_minima"`` (every start
            ended in a local minimum or at its iteration cap within the solver's own
            iteration count), ``"unreachable"`` (a goal point lies beyond the frame's
            reach or inside an obstacle, or a goal says it cannot be met, e.g. a
            ``CenterOfMass`` margin deeper than its support polygon allows: no joint vector
            can meet it; :func:`swarm_ik.api.unreachable_goal` says which and why),
            ``"conflicting_goals"`` (two goals of one frame at places no pose meets
            together, or primary goals pulling against each other at the answer:
            :meth:`swarm_ik.IKProblem.opposing_goals`), or
            ``"stopped"`` (the solver returned on its own before its budget without success).
    """

    q: FloatArray
    fitness: float
    position_error: float
    rotation_error: float
    n_evals: int
    time_s: float
    success: bool
    within_limits: bool
    history: FloatArray
    solver: str = ""
    seed: int | None = None
    goal_errors: tuple[Any, ...] = ()
    reason: str = ""

    def __init__(
        self,
        q: Any,
        fitness: float,
        position_error: float,
        rotation_error: float,
        n_evals: int,
        time_s: float,
        success: bool,
        within_limits: bool,
        history: Any,
        solver: str = "",
        seed: int | None = None,
        goal_errors: tuple[Any, ...] = (),
        reason: str = "",
    ) -> None:
        # the dataclass's own __init__ of a frozen class sets each field through
        # object.__setattr__ (2.5 µs, every solve); one update of the instance's dict is the
        # same assignment (the arrays frozen, whatever the caller keeps doing with its own)
        self.__dict__.update(
            q=_read_only(q), fitness=fitness, position_error=position_error,
            rotation_error=rotation_error, n_evals=n_evals, time_s=time_s, success=success,
            within_limits=within_limits, history=_read_only(history), solver=solver, seed=seed,
            goal_errors=goal_errors, reason=reason,
        )  # fmt: skip

    def __post_init__(self) -> None:
        # (the arrays frozen where __init__ is not this one: a dataclass subclass's own
        # __init__ calls this, as do pickle and copy through __setstate__)
        self.__dict__.update(q=_read_only(self.q), history=_read_only(self.history))

    def __setstate__(self, state: dict[str, Any]) -> None:
        # (pickle and copy restore the fields without __init__: read-only here too)
        self.__dict__.update(state)
        self.__post_init__()

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (arrays as lists)."""
        d = {f.name: getattr(self, f.name) for f in fields(self)}
        d["q"] = [float(v) for v in self.q]
        d["history"] = [float(v) for v in self.history]
        d["goal_errors"] = [g.to_dict() for g in self.goal_errors]
        return d

    def __repr__(self) -> str:
        return (
            f"Result(success={self.success}, position_error={self.position_error:.3g} m, "
            f"rotation_error={self.rotation_error:.3g} rad, fitness={self.fitness:.3g}, "
            f"n_evals={self.n_evals}, time_s={self.time_s:.4f}, solver={self.solver!r}, "
            f"reason={self.reason!r}, "
            f"q={np.round(self.q, 6).tolist()})"
        )


def _read_only(value: Any) -> FloatArray:
    """A read-only float64 copy of ``value`` (an array or a sequence of numbers); an array
    that is already one (``dataclasses.replace``, ``copy.copy``) is kept as it is."""
    if isinstance(value, np.ndarray) and value.dtype == np.float64 and not value.flags.writeable:
        return value
    arr = np.array(value, dtype=float)
    arr.setflags(write=False)
    return arr


def freeze_arrays(obj: Any) -> None:
    """Mark every numpy array field of the dataclass ``obj`` read-only, in place (results
    built from arrays of their own: :class:`swarm_ik.batch.BatchResult`,
    :class:`swarm_ik.path.PathResult`), so that a frozen result's rows cannot change after
    they were checked; ``arr.copy()`` gives a writable copy."""
    for f in fields(obj):
        value = getattr(obj, f.name)
        if isinstance(value, np.ndarray):
            value.flags.writeable = False


class FrozenArrays:
    """A dataclass base whose numpy array fields are read-only once made, unpickled or
    deep-copied (:func:`freeze_arrays`): :class:`swarm_ik.batch.BatchResult`,
    :class:`swarm_ik.path.PathResult`."""

    def __post_init__(self) -> None:
        freeze_arrays(self)

    def __setstate__(self, state: dict[str, Any]) -> None:
        # (pickle and copy.deepcopy restore the fields without __post_init__)
        self.__dict__.update(state)
        freeze_arrays(self)


class Solutions(list[Result]):
    """What :func:`swarm_ik.solve_many` returns: its solutions, a list of :class:`Result`
    (nearest to the reference first, each judged with Pinocchio), with why the search ended
    and what the whole call spent, in :func:`swarm_ik.solve`'s words.

    Attributes:
        reason: ``"converged"`` (``n`` solutions, or fewer when the search found no new
            branch in its patience: every branch it could find), ``"budget"`` or
            ``"time_limit"`` (the budget ran out before ``n``; the solutions found are
            kept), or for an empty list :attr:`Result.reason`'s words for a failed solve:
            ``"unreachable"`` or ``"conflicting_goals"`` where proven before the search (no
            evaluation spent), ``"conflicting_goals"`` where the start that ended nearest to
            the goals shows them pulling against each other
            (:meth:`~swarm_ik.problem.IKProblem.opposing_goals`), else ``"local_minima"``
            or the budget's reason.
        n_evals: Evaluations the whole call spent.
        time_s: Wall-clock seconds of the whole call [s].
    """

    reason: str
    n_evals: int
    time_s: float

    def __init__(
        self, results: Any = (), reason: str = "", n_evals: int = 0, time_s: float = 0.0
    ) -> None:
        super().__init__(results)
        self.reason, self.n_evals, self.time_s = str(reason), int(n_evals), float(time_s)
