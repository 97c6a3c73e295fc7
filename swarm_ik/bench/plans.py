"""Experiment plans: which robots, solvers, budgets, sizes and seeds each benchmark runs.

Specs only: nothing here runs a solver or writes a file (the runner is
:mod:`swarm_ik.bench.runner`, the workers live with their benchmark).

* ``bench paper``: :class:`Config` (:data:`FULL`, :data:`QUICK`) and the ``specs_*`` functions
  turning it into :class:`RunSpec` lists, one per experiment;
* ``bench ik``: :class:`IKPlan` and :func:`ik_tasks` (one :class:`IKTask` per robot, target and
  budget; the solvers of a task run interleaved in a seeded random order);
* ``bench throughput``: :class:`ThroughputPlan`.
"""

from __future__ import annotations

import zlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from functools import lru_cache, partial
from typing import Any

import numpy as np

from swarm_ik import solvers as reg
from swarm_ik.bench import published
from swarm_ik.bench.common import cached_robot as _robot
from swarm_ik.errors import InvalidArgumentError


# --------------------------------------------------------------------------- paper: runs
@dataclass(frozen=True)
class RunSpec:
    """One independent run: everything needed to repeat it bit for bit.

    Attributes:
        experiment: Experiment id (e.g. ``"000-table2"``).
        robot: Robot name (bundled or example-robot-data), or a benchmark-function key of
            :data:`swarm_ik.testfunctions.FUNCTIONS` when ``fitness_name == "function"``.
        target_id: Name of the target within the experiment.
        solver: Solver registry name.
        seed: Seed of the run.
        fitness_name: IK fitness name, or ``"function"`` for a benchmark function.
        target: Target pose as 16 numbers (row-major 4x4, metres); ``None`` for functions.
        pop_size: ``pop_size`` passed to the solver (``None``: not passed).
        iterations: ``iterations`` passed to the solver (``None``: not passed).
        max_evals: Evaluation budget (``None``: the solver's own schedule).
        stop_on_success: Stop at the tolerance (``False``: run the whole budget, as the
            papers do).
        tol_pos: Position tolerance for ``success`` [m].
        tol_rot: Rotation tolerance for ``success`` [rad].
        orth_tol: Orthonormality tolerance of the target (the printed paper-000 target needs
            ``1e-4``).
        keep_history: Whether to store the history for convergence plots.
    """

    experiment: str
    robot: str
    target_id: str
    solver: str
    seed: int
    fitness_name: str
    target: tuple[float, ...] | None = None
    pop_size: int | None = None
    iterations: int | None = None
    max_evals: int | None = None
    stop_on_success: bool = False
    tol_pos: float = 1e-5
    tol_rot: float = 1e-5
    orth_tol: float = 1e-6
    keep_history: bool = True

    @property
    def key(self) -> str:
        """Unique key of the run within an output folder (settings included, so runs made
        with other settings are never mistaken for this one)."""
        parts = [
            self.experiment,
            self.robot,
            self.target_id,
            self.solver,
            self.fitness_name,
            f"pop={_blank(self.pop_size)}",
            f"it={_blank(self.iterations)}",
            f"budget={_blank(self.max_evals)}",
            f"stop={int(self.stop_on_success)}",
            f"seed={self.seed}",
        ]
        return "|".join(parts)

    def solver_params(self) -> dict[str, Any]:
        """Keyword arguments for the solver (only those given)."""
        params: dict[str, Any] = {}
        if self.pop_size is not None:
            params["pop_size"] = self.pop_size
        if self.iterations is not None:
            params["iterations"] = self.iterations
        return params


def _blank(v: Any) -> str:
    return "" if v is None else str(v)


# --------------------------------------------------------------------------- paper: sizes
POSE_SEED = 2021
"""Seed of the joint vectors whose FK are the arbitrary poses (000 Table 4, budget)."""

Q_EXACT = (
    -2.3633884105424747,
    -1.7359312886882694,
    0.24014480588594253,
    1.7082843808984993,
    -1.2356793043129546,
    3.2865382472506774,
    2.903761762991929,
)
"""Joint vector [rad] whose FK best fits [HLFOA]'s printed pose: bounded least squares on
the ``paper-l1`` residuals (position ×10 per metre, the 9 rotation entries) from
:data:`swarm_ik.bench.published.P000_Q_PRINTED_DEG`; within the YuMi limits.  Its FK is the
full-precision target of ``000-table2`` (b)."""

PAPER000_SOLVERS = ("foa", "hlfoa", "gwo", "mgwo", "pso", "dls", "swarm")
PAPER003_SOLVERS = ("gwo", "mgwo", "dls", "swarm")

TOL = 1e-5
"""Success tolerance, ‖Δp‖ [m] and θ [rad], both judged with Pinocchio's FK."""
IK_FLOOR = 1e-12
"""IK fitness values below this count as exact in the verdicts (round-off of an exact
solution is ~1e-16 to 1e-15)."""


@dataclass(frozen=True)
class Config:
    """Sizes of a benchmark invocation.

    Attributes:
        name: ``"full"`` (the papers' settings) or ``"quick"``.
        runs_000: Runs per target and solver in 000 Table 2 (paper: 10).
        iterations_000: Iterations in [HLFOA]'s experiments (paper: 1000).
        pop_000: Population in [HLFOA]'s experiments (paper: 100).
        poses_000: Poses of 000 Table 4 (paper: 10).
        runs_000_t4: Runs per pose and solver in 000 Table 4.
        runs_003: Runs per case and solver in [MGWO]'s experiments (paper: 50).
        pop_003: Wolves (paper: 30).
        iterations_003: Iterations (paper: 200).
        budget_poses: Poses per robot in the equal-budget experiment.
        budget_seeds: Runs per pose and solver there.
        budgets: The evaluation budgets there.
    """

    name: str
    runs_000: int = 10
    iterations_000: int = 1000
    pop_000: int = 100
    poses_000: int = 10
    runs_000_t4: int = 10
    runs_003: int = 50
    pop_003: int = 30
    iterations_003: int = 200
    budget_poses: int = 10
    budget_seeds: int = 3
    budgets: tuple[int, ...] = (1_000, 10_000, 100_000)

    def with_runs(self, runs: int) -> Config:
        """The same configuration with ``runs`` runs per case and solver everywhere."""
        if runs < 1:
            raise InvalidArgumentError(f"--runs must be >= 1, got {runs}")
        return replace(self, runs_000=runs, runs_000_t4=runs, runs_003=runs, budget_seeds=runs)


FULL = Config("full")
QUICK = Config(
    "quick",
    runs_000=3,
    iterations_000=150,
    poses_000=2,
    runs_000_t4=2,
    runs_003=5,
    budget_poses=2,
    budget_seeds=1,
    budgets=(1_000, 10_000),
)
"""Reduced sizes of ``bench paper --quick`` (about a minute on one core)."""


def _flat(m: np.ndarray) -> tuple[float, ...]:
    return tuple(float(v) for v in np.asarray(m, dtype=float).ravel())


def printed_target() -> np.ndarray:
    """[HLFOA]'s printed target in metres (the matrix as printed, not projected)."""
    t = published.P000_TARGET_MM.copy()
    t[:3, 3] /= 1000.0
    return t


def exact_target() -> np.ndarray:
    """FK of :data:`Q_EXACT` on the YuMi left arm: the full-precision target."""
    return np.asarray(_robot("yumi_left").fk(np.asarray(Q_EXACT)), dtype=float)


@lru_cache(maxsize=1)
def printed_floor() -> tuple[float, tuple[float, ...]]:
    """Lowest ``paper-l1`` fitness we find against the printed pose within the limits.

    Bounded least squares from :data:`Q_EXACT`, then Nelder–Mead on the (non-smooth) L1
    fitness itself, kept within the limits.

    Returns:
        ``(floor fitness, joint vector [rad])``.
    """
    from scipy.optimize import minimize

    import swarm_ik

    robot = _robot("yumi_left")
    problem = swarm_ik.IKProblem(robot, printed_target(), "paper-l1", orth_tol=1e-4)

    def f(q: np.ndarray) -> float:
        return float(problem.fitness(np.clip(q, robot.lower, robot.upper)[None])[0])

    q0 = np.asarray(Q_EXACT)
    res = minimize(
        f, q0, method="Nelder-Mead", options={"xatol": 1e-10, "fatol": 1e-12, "maxfev": 6000}
    )
    q = np.clip(res.x, robot.lower, robot.upper)
    best = min((f(q), tuple(q)), (f(q0), tuple(q0)))
    return best


def arbitrary_poses(robot_name: str, n: int) -> list[np.ndarray]:
    """FK of ``n`` joint vectors drawn uniformly within the limits (seed :data:`POSE_SEED`);
    the first ``k`` poses do not depend on ``n``."""
    robot = _robot(robot_name)
    rng = np.random.default_rng(POSE_SEED)
    qs = robot.random_q(rng, max(n, 1))
    return [np.asarray(robot.fk(q), dtype=float) for q in np.atleast_2d(qs)[:n]]


def x_star_target(robot_name: str) -> np.ndarray:
    """FK of [MGWO]'s ``x*`` on the given loading-manipulator variant (x* itself lies
    outside the limits of both; its FK is the target)."""
    return np.asarray(_robot(robot_name).fk(np.asarray(published.P003_X_STAR)), dtype=float)


# --------------------------------------------------------------------------- specs
def available(solvers: Sequence[str]) -> tuple[list[str], list[str]]:
    """``(registered, missing)`` among ``solvers``, order kept."""
    names = set(reg.names())
    return [s for s in solvers if s in names], [s for s in solvers if s not in names]


def _paper_settings(solver: str, pop: int, iterations: int, budget: int) -> dict[str, Any]:
    """Settings of one solver at a paper's population/iterations; a solver without a
    population schedule (registry: ``budget_only`` or ``evals_per_iteration``) gets the same
    evaluation budget instead."""
    spec = reg.get(solver)
    if spec.budget_only or spec.evals_per_iteration is not None:
        return spec.schedule(budget)
    return {"pop_size": pop, "iterations": iterations}


def _budget_settings(solver: str, budget: int) -> dict[str, Any]:
    """Settings for an evaluation budget (:meth:`swarm_ik.solvers.base.SolverSpec.schedule`:
    the solver's own population, enough iterations to spend the budget, ``max_evals``)."""
    return reg.get(solver).schedule(budget)


Case = tuple[str, str, np.ndarray, float]
"""An IK case of an experiment: ``(robot, target id, 4x4 target, orth_tol)``."""


def _ik_runs(
    experiment: str,
    cases: Sequence[Case],
    solvers: Sequence[str],
    runs: int,
    settings: Callable[[str], dict[str, Any]],
    fitness_name: str,
    **fixed: Any,
) -> list[RunSpec]:
    """The runs of an IK experiment: cases × solvers × seeds ``0 … runs-1``, in that order.

    Args:
        experiment: Experiment id.
        cases: The cases (:data:`Case`).
        solvers: Registry names.
        runs: Seeds per case and solver.
        settings: Solver -> its :class:`RunSpec` settings (``pop_size``, ``max_evals``, …).
        fitness_name: IK fitness.
        **fixed: Further :class:`RunSpec` fields shared by every run.
    """
    return [
        RunSpec(
            experiment,
            robot,
            tid,
            s,
            seed,
            fitness_name,
            _flat(target),
            orth_tol=orth,
            tol_pos=TOL,
            tol_rot=TOL,
            **fixed,
            **settings(s),
        )
        for robot, tid, target, orth in cases
        for s in solvers
        for seed in range(runs)
    ]


def _settings_000(cfg: Config) -> Callable[[str], dict[str, Any]]:
    budget = cfg.pop_000 * (cfg.iterations_000 + 1)
    return lambda s: _paper_settings(s, cfg.pop_000, cfg.iterations_000, budget)


def specs_000_table2(cfg: Config) -> list[RunSpec]:
    """Runs of 000 Table 2: both targets × solvers × runs."""
    cases = [
        ("yumi_left", "printed", printed_target(), 1e-4),
        ("yumi_left", "exact", exact_target(), 1e-6),
    ]
    solvers, _ = available(PAPER000_SOLVERS)
    return _ik_runs("000-table2", cases, solvers, cfg.runs_000, _settings_000(cfg), "paper-l1")


def specs_000_table4(cfg: Config) -> list[RunSpec]:
    """Runs of 000 Table 4: poses × solvers × runs."""
    poses = arbitrary_poses("yumi_left", cfg.poses_000)
    cases = [("yumi_left", f"pose{i}", t, 1e-6) for i, t in enumerate(poses)]
    solvers, _ = available(PAPER000_SOLVERS)
    return _ik_runs("000-table4", cases, solvers, cfg.runs_000_t4, _settings_000(cfg), "paper-l1")


def specs_003_table3(cfg: Config) -> list[RunSpec]:
    """Runs of 003 Table 3: F1–F4 × {GWO, MGWO} × runs."""
    solvers, _ = available(("gwo", "mgwo"))
    return [
        RunSpec("003-table3", f, "min", s, seed, "function", None, cfg.pop_003, cfg.iterations_003)
        for f in published.P003_TABLE3
        for s in solvers
        for seed in range(cfg.runs_003)
    ]


def specs_003_table4(cfg: Config) -> list[RunSpec]:
    """Runs of 003 Table 4: both robot variants × solvers × runs."""
    budget = cfg.pop_003 * cfg.iterations_003
    cases = [
        (robot, "x*", x_star_target(robot), 1e-6)
        for robot in ("loading_manipulator_long", "loading_manipulator")
    ]
    solvers, _ = available(PAPER003_SOLVERS)
    return _ik_runs(
        "003-table4",
        cases,
        solvers,
        cfg.runs_003,
        lambda s: _paper_settings(s, cfg.pop_003, cfg.iterations_003, budget),
        "euler-zyz",
    )


def budget_solvers() -> list[str]:
    """Every registered search solver (closed-form ones, which solve only particular chains,
    left out), DLS and ``swarm`` first."""
    names = reg.search_names()
    first = [s for s in ("dls", "swarm") if s in names]
    return first + [s for s in names if s not in first]


def budget_targets(cfg: Config) -> list[tuple[str, str, np.ndarray]]:
    """``(robot, target id, pose)`` of the equal-budget experiment: YuMi at the Table-4
    poses, the long loading manipulator at FK(x*) then arbitrary poses."""
    out = [
        ("yumi_left", f"pose{i}", t)
        for i, t in enumerate(arbitrary_poses("yumi_left", cfg.budget_poses))
    ]
    lm = "loading_manipulator_long"
    out.append((lm, "x*", x_star_target(lm)))
    out += [(lm, f"pose{i}", t) for i, t in enumerate(arbitrary_poses(lm, cfg.budget_poses - 1))]
    return out


def specs_budget(cfg: Config) -> list[RunSpec]:
    """Runs of the equal-budget experiment: targets × budgets × every solver × seeds."""
    return [
        spec
        for robot, tid, target in budget_targets(cfg)
        for b in cfg.budgets
        for spec in _ik_runs(
            "budget",
            [(robot, tid, target, 1e-6)],
            budget_solvers(),
            cfg.budget_seeds,
            partial(_budget_settings, budget=b),
            "se3",
            stop_on_success=True,
            keep_history=False,
        )
    ]


# --------------------------------------------------------------------------- bench ik
IK_ROBOTS = ("panda", "ur5", "ur10", "yumi_left", "loading_manipulator_long", "kinova", "xarm7")
"""Robots of the full ``bench ik`` (kinova: continuous joints; xarm7: a 7-joint arm)."""

IK_PEERS = (
    "swarm",
    "ik-solver",
    "dls",
    "tracik-1e-5",
    "tracik-1e-6",
    "rtb-lm",
    "rtb-gn",
    "rtb-nr",
    "pink",
    "ikpy",
)
"""Adapters of :mod:`swarm_ik.bench.peers` run by default (those not installed are skipped)."""

IK_QUICK_ROBOTS = ("panda", "ur5")
"""Robots of ``bench ik --quick`` (unless ``--robots`` is given)."""
IK_QUICK_N = 10
"""Targets per robot of ``bench ik --quick`` (unless ``--n`` is given)."""


@dataclass(frozen=True)
class IKPlan:
    """What one ``bench ik`` invocation runs.

    Attributes:
        robots: Robot names.
        peers: Adapter names (:data:`swarm_ik.bench.peers.PEERS`).
        budgets_ms: Time budgets [ms] (each peer's own time limit where it has one).
        n: Targets per robot (FK of joint vectors drawn uniformly within the limits).
        seed: Seed of the targets and of the interleaving order.
        tol: Strict tolerance [m and rad] (Euclidean norms).
        lenient_tol: Lenient tolerance [m and rad].
    """

    robots: tuple[str, ...]
    peers: tuple[str, ...]
    budgets_ms: tuple[float, ...] = (5.0,)
    n: int = 1000
    seed: int = 0
    tol: float = 1e-5
    lenient_tol: float = 2e-5

    def __post_init__(self) -> None:
        if self.n < 1:
            raise InvalidArgumentError(f"n must be >= 1, got {self.n}")
        if not self.robots or not self.peers or not self.budgets_ms:
            raise InvalidArgumentError("a plan needs robots, peers and budgets")
        if any(b <= 0 for b in self.budgets_ms):
            raise InvalidArgumentError(f"budgets must be > 0 ms, got {self.budgets_ms}")
        if not 0 < self.tol <= self.lenient_tol:
            raise InvalidArgumentError(
                f"need 0 < tol <= lenient_tol, got {self.tol:g} and {self.lenient_tol:g}"
            )


@dataclass(frozen=True)
class IKTask:
    """One target of one robot at one budget, solved by every peer in a seeded random order.

    Attributes:
        robot: Robot name.
        target_id: Index of the target (``0 … n-1``; the target does not depend on ``n``).
        budget_ms: Time budget [ms].
        peers: Adapter names, in plan order (the run order is drawn from :attr:`order_seed`).
        seed: Seed of the targets (and, with ``target_id``, of the order and of our solvers).
        tol: Strict tolerance [m and rad].
        lenient_tol: Lenient tolerance [m and rad].
        experiment: CSV name.
    """

    robot: str
    target_id: int
    budget_ms: float
    peers: tuple[str, ...]
    seed: int
    tol: float
    lenient_tol: float
    experiment: str = "peers"

    @property
    def key(self) -> str:
        """Unique key of the task (settings included)."""
        return (
            f"{self.experiment}|{self.robot}|t={self.target_id}|b={self.budget_ms:g}"
            f"|tol={self.tol:g}|seed={self.seed}|{','.join(self.peers)}"
        )

    def order(self) -> list[str]:
        """The peers in this task's run order: a permutation seeded by the task (the robot
        too), drawn again while two of our own peers that run the same search (``swarm``,
        ``ik-solver``) would run one right after the other (the second ran warm: its own
        time half the first's, review 117), where another peer can stand between them."""
        robot = zlib.crc32(self.robot.encode())  # (the whole name: stable across runs)
        rng = np.random.default_rng([self.seed, self.target_id, int(self.budget_ms * 1000), robot])
        twins = {"swarm", "ik-solver"}
        for _ in range(100):
            order = [self.peers[i] for i in rng.permutation(len(self.peers))]
            if len(self.peers) < 3 or not any(
                {a, b} == twins for a, b in zip(order, order[1:], strict=False)
            ):
                break
        return order


def ik_tasks(plan: IKPlan) -> list[IKTask]:
    """The tasks of a plan: robot-major, then budget, then target."""
    return [
        IKTask(r, i, float(b), plan.peers, plan.seed, plan.tol, plan.lenient_tol)
        for r in plan.robots
        for b in plan.budgets_ms
        for i in range(plan.n)
    ]


# --------------------------------------------------------------------------- bench throughput
THROUGHPUT_ROBOTS = ("panda", "yumi_left")
THROUGHPUT_SIZES = (100, 1000, 10_000, 100_000)
THROUGHPUT_QUICK_SIZES = (100, 1000)
