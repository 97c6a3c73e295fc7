"""The worker of optimiser runs (``bench paper``): one :class:`~swarm_ik.bench.plans.RunSpec`
→ one CSV row and its convergence history.

CSV schema (:data:`RUN_FIELDS`), one row per run:

==================  ===========================================================================
``key``             unique run key (experiment, case, target, solver, settings, seed)
``experiment``      experiment id, e.g. ``000-table2``
``robot``           robot name; for the benchmark-function experiment the function key (``F1``)
``target_id``       target within the experiment (``printed``, ``pose3``, ``x*`` …)
``solver``          registry name
``seed``            the run's seed
``fitness_name``    ``paper-l1``, ``euler-zyz``, ``se3`` or ``function``
``pop_size``        population size passed to the solver (empty: solver default / none)
``iterations``      iterations passed to the solver (empty: solver default)
``max_evals``       evaluation budget passed (empty: the solver's own schedule ends the run)
``fitness``         best fitness found (the problem's fitness, or the function value)
``position_error``  ‖Δp‖ [m] by Pinocchio's FK (empty for benchmark functions)
``rotation_error``  geodesic rotation error [rad] (empty for benchmark functions)
``n_evals``         evaluations spent
``time_s``          wall-clock seconds of the solve (depends on machine load and ``--jobs``)
``success``         errors within ``tol_pos``/``tol_rot`` and within limits (IK); for functions
                    ``fitness − f_min ≤ 1e-8``
``within_limits``   answer within the joint limits (functions: always within the box)
==================  ===========================================================================

Everything except ``time_s`` is a deterministic function of the run's key: results do not
depend on ``jobs`` or on the order in which runs finish.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from swarm_ik.bench.common import cached_robot
from swarm_ik.bench.plans import RunSpec
from swarm_ik.bench.runner import Outcome, Schema
from swarm_ik.errors import InvalidArgumentError

RUN_FIELDS = (
    "key",
    "experiment",
    "robot",
    "target_id",
    "solver",
    "seed",
    "fitness_name",
    "pop_size",
    "iterations",
    "max_evals",
    "fitness",
    "position_error",
    "rotation_error",
    "n_evals",
    "time_s",
    "success",
    "within_limits",
)
"""Columns of every experiment CSV, in order."""

SCHEMA = Schema(
    RUN_FIELDS,
    ints=frozenset({"seed", "pop_size", "iterations", "max_evals", "n_evals"}),
    floats=frozenset({"fitness", "position_error", "rotation_error", "time_s"}),
    bools=frozenset({"success", "within_limits"}),
)
"""Typed schema of the run CSVs."""

HISTORY_POINTS = 120
"""Most points kept of a run's history (evenly spaced over the iterations, last included)."""

FUNCTION_SUCCESS_GAP = 1e-8
"""A benchmark-function run counts as a success when ``f − f_min`` is at most this."""


def run_one(spec: RunSpec) -> Outcome:
    """Run one spec (in a worker process or inline).

    Args:
        spec: The run.

    Returns:
        Its CSV row and compact history.
    """
    import swarm_ik

    # the same seed, budget and solver parameters for a test function and an IK target
    shared: dict[str, Any] = {"seed": spec.seed, "max_evals": spec.max_evals}
    shared.update(spec.solver_params())
    if spec.fitness_name == "function":
        from swarm_ik.testfunctions import get_function

        fn = get_function(spec.robot)
        lo, hi = fn.bounds
        res = swarm_ik.minimize(fn.function, lo, hi, spec.solver, **shared)
        fit, hist, n_evals, t = float(res.fun), res.history, res.n_evals, res.time_s
        pos = rot = math.nan
        success = fit - fn.f_min <= FUNCTION_SUCCESS_GAP
        within = bool(np.all(res.x >= lo) and np.all(res.x <= hi))
    else:
        if spec.target is None:
            raise InvalidArgumentError(f"run {spec.key!r}: an IK run needs a target")
        robot = cached_robot(spec.robot)
        target = np.asarray(spec.target, dtype=float).reshape(4, 4)
        problem = swarm_ik.IKProblem(robot, target, spec.fitness_name, orth_tol=spec.orth_tol)
        shared.update(tol_pos=spec.tol_pos, tol_rot=spec.tol_rot)
        r = swarm_ik.solve(problem, spec.solver, stop_on_success=spec.stop_on_success, **shared)
        fit, hist, n_evals, t = r.fitness, r.history, r.n_evals, r.time_s
        pos, rot, success, within = r.position_error, r.rotation_error, r.success, r.within_limits
    row = {
        "key": spec.key,
        "experiment": spec.experiment,
        "robot": spec.robot,
        "target_id": spec.target_id,
        "solver": spec.solver,
        "seed": spec.seed,
        "fitness_name": spec.fitness_name,
        "pop_size": spec.pop_size,
        "iterations": spec.iterations,
        "max_evals": spec.max_evals,
        "fitness": float(fit),
        "position_error": float(pos),
        "rotation_error": float(rot),
        "n_evals": int(n_evals),
        "time_s": float(t),
        "success": bool(success),
        "within_limits": bool(within),
    }
    history = compact_history(hist, int(n_evals)) if spec.keep_history else None
    return Outcome([row], history)


def warm_up() -> None:
    """Compile the numba kernels once (FK, the ``swarm`` polish) so that no run's ``time_s``
    includes compilation; called once per worker process.  Failures are ignored (the runs
    then simply pay the compilation themselves)."""
    try:
        import swarm_ik

        robot = cached_robot("yumi_left")
        problem = swarm_ik.IKProblem.from_q(robot, robot.mid_q())
        for solver in ("swarm", "dls"):
            if solver in swarm_ik.solvers.names():
                swarm_ik.solve(problem, solver, seed=0, max_evals=50)
    except Exception:  # noqa: BLE001 - warming up is an optimisation only
        pass


def compact_history(
    history: Sequence[float] | np.ndarray, n_evals: int, max_points: int = HISTORY_POINTS
) -> dict[str, Any]:
    """A run's best-fitness history, thinned for storage.

    Args:
        history: Best fitness after each iteration, shape ``(iterations,)``.
        n_evals: Evaluations the run spent (to place iterations on an evaluation axis).
        max_points: Most points kept (evenly spaced iterations, the last one always kept).

    Returns:
        ``{"n_iter": L, "n_evals": N, "it": [iteration indices], "f": [values]}``; values
        rounded to 5 significant digits, non-finite ones as ``None``.
    """
    h = np.asarray(history, dtype=float)
    n = int(h.shape[0])
    idx: list[int] = (
        np.unique(np.round(np.linspace(0, n - 1, min(n, max_points))).astype(int)).tolist()
        if n
        else []
    )
    vals = [float(f"{h[i]:.5g}") if np.isfinite(h[i]) else None for i in idx]
    return {"n_iter": n, "n_evals": int(n_evals), "it": [int(i) for i in idx], "f": vals}
