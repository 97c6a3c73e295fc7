"""The source papers' published numbers, as data (transcribed from ``SEEDS.md``).

Nothing here is computed: these are the values printed in the papers, set beside our own
numbers by :mod:`swarm_ik.bench.report`.  Each :class:`PublishedRow` names the algorithm as the
paper prints it and, when we implement it, the registry name of our solver.

* Paper 000 — Shi et al., 2021, HLFOA on the ABB YuMi IRB 14000 left arm: Table 2 (the given
  pose, 10 runs, population 100, 1000 iterations) and Table 4 (10 arbitrary reachable poses).
  Fitness: eq. 3, ``λ·(|Δpx|+|Δpy|+|Δpz|) + Σ|ΔR_ij|``, millimetres with ``λ = 1e-2`` (the
  same values as metres with ``λ = 10``, our ``"paper-l1"``).
* Paper 003 — Hu et al., 2025, MGWO on a mobile loading manipulator: Table 3 (benchmark
  functions F1–F4, 30 wolves, 200 iterations, 50 runs, means only) and Table 4 (IK of the
  target FK(x*), 50 runs; its last column is the **variance**).  Fitness: eq. 15, ZYZ Euler
  angles, ``μ = 1`` (our ``"euler-zyz"``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

STATS = ("best", "mean", "worst", "std", "var")
"""Statistic names a published row may carry (``var`` = variance, as paper 003 prints)."""


@dataclass(frozen=True)
class PublishedRow:
    """One algorithm's row of a published table.

    Attributes:
        algorithm: Name as printed in the paper, e.g. ``"HLFOA"``.
        solver: Our registry name for it (``None``: not implemented here; listed as published).
        stats: Published values by statistic name (a subset of :data:`STATS`), fitness units.
    """

    algorithm: str
    solver: str | None
    stats: Mapping[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class PublishedTable:
    """A published table (or the part of it for one case).

    Attributes:
        paper: ``"000"`` or ``"003"`` (the numbering of ``SEEDS.md``).
        table: Table label as in the paper, e.g. ``"Table 2"``.
        caption: What was measured, in one line.
        rows: The rows, in the paper's order.
        resolution: Half a unit of the last printed digit where that matters for comparing
            (``0`` otherwise), in fitness units.
    """

    paper: str
    table: str
    caption: str
    rows: tuple[PublishedRow, ...]
    resolution: float = 0.0

    def row_for(self, solver: str) -> PublishedRow | None:
        """The row of our solver ``solver``, or ``None`` if the paper has none."""
        for row in self.rows:
            if row.solver == solver:
                return row
        return None


# --------------------------------------------------------------------------- paper 000
P000_TARGET_MM = np.array(
    [
        [-0.53812, -0.17516, 0.82447, 21.84134],
        [0.77431, 0.28371, 0.56565, 72.69408],
        [-0.33299, 0.94278, -0.01704, 234.75475],
        [0.0, 0.0, 0.0, 1.0],
    ]
)
"""Paper 000's given target pose (Table 2 experiment) as printed: rotation rounded to five
decimals (not exactly orthonormal), translation in **millimetres**."""

P000_Q_PRINTED_DEG = (-135.4, -99.5, 13.8, 97.9, -70.8, 188.3, 166.4)
"""Joint vector [deg] near which the printed pose is reached best (``SEEDS.md``)."""

P000_TABLE2 = PublishedTable(
    "000",
    "Table 2",
    "YuMi left arm, the given pose; population 100, 1000 iterations, 10 runs",
    (
        PublishedRow(
            "FOA", "foa", {"best": 5.21425, "mean": 5.27143, "worst": 5.35291, "std": 4.57e-2}
        ),
        PublishedRow(
            "LGMS-FOA", None, {"best": 0.207373, "mean": 0.540788, "worst": 1.20566, "std": 0.265}
        ),
        PublishedRow(
            "AE-LGMS-FOA", None, {"best": 3.42e-2, "mean": 0.3495, "worst": 0.7838, "std": 0.2151}
        ),
        PublishedRow("IFOA", None, {"best": 5.426, "mean": 5.515, "worst": 5.585, "std": 5.85e-2}),
        PublishedRow("SFOA", None, {"best": 6.149, "mean": 6.935, "worst": 7.772, "std": 0.583}),
        PublishedRow(
            "HLFOA",
            "hlfoa",
            {"best": 2.22e-16, "mean": 4.04e-16, "worst": 5.07e-16, "std": 8.02e-17},
        ),
    ),
)
"""Paper 000, Table 2: best / mean / worst / std of the fitness over 10 runs."""

P000_TABLE4 = PublishedTable(
    "000",
    "Table 4",
    "YuMi left arm, 10 arbitrary reachable poses",
    (
        PublishedRow("FOA", "foa", {"mean": 7.107}),
        PublishedRow("LGMS-FOA", None, {"mean": 0.684}),
        PublishedRow("AE-LGMS-FOA", None, {"mean": 0.296}),
        PublishedRow("HLFOA", "hlfoa", {"best": 1.73e-16, "mean": 3.88e-16, "worst": 6.80e-16}),
    ),
)
"""Paper 000, Table 4: fitness over the 10 poses (HLFOA: best / mean / worst; others: mean)."""

# --------------------------------------------------------------------------- paper 003
P003_X_STAR = (np.pi / 4, np.pi / 6, np.pi / 4, 0.8, 1.0, 1.0, np.pi / 6, -np.pi / 4)
"""Paper 003's target joint vector ``x*`` (rad, rad, rad, m, m, m, rad, rad); it violates the
paper's own limits (θ3 = 45° > 35.45°, d4..d6 > 0.5 m)."""

HARTMANN3_MIN = -3.86278214782076
"""Global minimum of Hartmann-3 (F4) to full precision (Dixon & Szegő's test set)."""

P003_TABLE3: dict[str, PublishedTable] = {
    "F1": PublishedTable(
        "003",
        "Table 3",
        "F1 sphere (30-D)",
        (
            PublishedRow("GWO", "gwo", {"mean": 9.38e-9}),
            PublishedRow("MGWO", "mgwo", {"mean": 5.89e-14}),
        ),
    ),
    "F2": PublishedTable(
        "003",
        "Table 3",
        "F2 Schwefel 2.22 (30-D)",
        (
            PublishedRow("GWO", "gwo", {"mean": 6.76e-6}),
            PublishedRow("MGWO", "mgwo", {"mean": 5.16e-9}),
        ),
    ),
    "F3": PublishedTable(
        "003",
        "Table 3",
        "F3 Rastrigin (30-D)",
        (
            PublishedRow("GWO", "gwo", {"mean": 14.75}),
            PublishedRow("MGWO", "mgwo", {"mean": 1.30}),
        ),
    ),
    "F4": PublishedTable(
        "003",
        "Table 3",
        "F4 Hartmann-3 (3-D)",
        (
            PublishedRow("GWO", "gwo", {"mean": -3.8609}),
            PublishedRow("MGWO", "mgwo", {"mean": -3.8628}),
        ),
        resolution=5e-5,
    ),
}
"""Paper 003, Table 3: mean best value over 50 runs (30 wolves, 200 iterations), per function.
F4 is printed to four decimals, hence its resolution."""

P003_TABLE4 = PublishedTable(
    "003",
    "Table 4",
    "loading manipulator, target FK(x*); 30 wolves, 200 iterations, 50 runs",
    (
        PublishedRow("GWO", "gwo", {"mean": 0.4292, "best": 0.0115, "worst": 1.0613}),
        PublishedRow("VAGWO", "vagwo", {"mean": 1.0043, "best": 8.04e-5, "worst": 6.2053}),
        PublishedRow("PGWO", None, {"mean": 0.3986, "best": 0.0015, "worst": 2.5655}),
        PublishedRow(
            "MGWO", "mgwo", {"mean": 0.0122, "best": 0.0064, "worst": 0.0226, "var": 8.04e-5}
        ),
    ),
)
"""Paper 003, Table 4: mean / best / worst / variance of the fitness over 50 runs."""


# --------------------------------------------------------------------------- solver facts
@dataclass(frozen=True)
class SolverFacts:
    """What the benchmarks need to know about a registered solver.

    These belong in the solver's registration (``register(...)`` in
    ``swarm_ik/solvers/base.py``); until the registry carries them, they live here, in one
    place, keyed by registry name.

    Attributes:
        needs_jacobian: Uses the Jacobian (DLS, the ``swarm`` polish) rather than fitness only.
        budget_only: Takes only an evaluation budget (no population / iteration schedule).
        evals_per_iteration: Evaluations one ``iterations`` step costs (``1``: an iteration is
            one evaluation, so ``iterations = budget``; ``None``: a population schedule).
        paper: Short key of its source in ``docs/references.md`` (``None``: our own).
    """

    needs_jacobian: bool = False
    budget_only: bool = False
    evals_per_iteration: int | None = None
    paper: str | None = None


SOLVER_FACTS: dict[str, SolverFacts] = {
    "swarm": SolverFacts(needs_jacobian=True, budget_only=True),
    "dls": SolverFacts(needs_jacobian=True, evals_per_iteration=1),
    "foa": SolverFacts(paper="FOA"),
    "hlfoa": SolverFacts(paper="HLFOA"),
    "gwo": SolverFacts(paper="GWO"),
    "mgwo": SolverFacts(paper="MGWO"),
    "pso": SolverFacts(paper="PSO"),
    "cs": SolverFacts(paper="CS"),
}
"""Facts by registry name (a solver not listed: :class:`SolverFacts` defaults)."""


def solver_facts(name: str) -> SolverFacts:
    """The facts of solver ``name`` (defaults when it is not listed)."""
    return SOLVER_FACTS.get(name, SolverFacts())
