"""The source papers' published numbers, as data, keyed by our solver names.

Transcribed from the papers (full citations in ``docs/references.md``).

Nothing here is computed: these are the values printed in the papers, set beside our own
numbers by :mod:`swarm_ik.bench.report`.  Each :class:`PublishedRow` names the algorithm as the
paper prints it and, when we implement it, the registry name of our solver.

* [HLFOA], on the ABB YuMi IRB 14000 left arm: Table 2 (the given pose, 10 runs, population
  100, 1000 iterations) and Table 4 (10 arbitrary reachable poses).
  Fitness: eq. 3, ``λ·(|Δpx|+|Δpy|+|Δpz|) + Σ|ΔR_ij|``, millimetres with ``λ = 1e-2`` (the
  same values as metres with ``λ = 10``, our ``"paper-l1"``).
* [MGWO], on a mobile loading manipulator: Table 3 (benchmark functions F1–F4, 30 wolves,
  200 iterations, 50 runs, means only) and Table 4 (IK of the target FK(x*), 50 runs; its
  last column is the **variance**).  Fitness: eq. 15, ZYZ Euler
  angles, ``μ = 1`` (our ``"euler-zyz"``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

STATS = ("best", "mean", "worst", "std", "var")
"""Statistic names a published row may carry (``var`` = variance, as [MGWO] prints)."""


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
        paper: Short key of the paper in ``docs/references.md`` (``"HLFOA"``, ``"MGWO"``).
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


# --------------------------------------------------------------------------- [HLFOA]
P000_TARGET_MM = np.array(
    [
        [-0.53812, -0.17516, 0.82447, 21.84134],
        [0.77431, 0.28371, 0.56565, 72.69408],
        [-0.33299, 0.94278, -0.01704, 234.75475],
        [0.0, 0.0, 0.0, 1.0],
    ]
)
"""[HLFOA]'s given target pose (Table 2 experiment) as printed: rotation rounded to five
decimals (not exactly orthonormal), translation in **millimetres**."""

P000_Q_PRINTED_DEG = (-135.4, -99.5, 13.8, 97.9, -70.8, 188.3, 166.4)
"""Joint vector [deg] near which the printed pose is reached best within the limits (found
with bounded least squares from random starts; refined in
:data:`swarm_ik.bench.plans.Q_EXACT`)."""

P000_TABLE2 = PublishedTable(
    "HLFOA",
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
"""[HLFOA], Table 2: best / mean / worst / std of the fitness over 10 runs."""

P000_TABLE4 = PublishedTable(
    "HLFOA",
    "Table 4",
    "YuMi left arm, 10 arbitrary reachable poses",
    (
        PublishedRow("FOA", "foa", {"mean": 7.107}),
        PublishedRow("LGMS-FOA", None, {"mean": 0.684}),
        PublishedRow("AE-LGMS-FOA", None, {"mean": 0.296}),
        PublishedRow("HLFOA", "hlfoa", {"best": 1.73e-16, "mean": 3.88e-16, "worst": 6.80e-16}),
    ),
)
"""[HLFOA], Table 4: fitness over the 10 poses (HLFOA: best / mean / worst; others: mean)."""

# --------------------------------------------------------------------------- [MGWO]
P003_X_STAR = (np.pi / 4, np.pi / 6, np.pi / 4, 0.8, 1.0, 1.0, np.pi / 6, -np.pi / 4)
"""[MGWO]'s target joint vector ``x*`` (rad, rad, rad, m, m, m, rad, rad); it violates the
paper's own limits (θ3 = 45° > 35.45°, d4..d6 > 0.5 m)."""

HARTMANN3_MIN = -3.86278214782076
"""Global minimum of Hartmann-3 (F4) to full precision (Dixon & Szegő's test set)."""


def _table3(caption: str, gwo: float, mgwo: float, resolution: float = 0.0) -> PublishedTable:
    """One function's part of [MGWO] Table 3 (means only)."""
    rows = (PublishedRow("GWO", "gwo", {"mean": gwo}), PublishedRow("MGWO", "mgwo", {"mean": mgwo}))
    return PublishedTable("MGWO", "Table 3", caption, rows, resolution)


P003_TABLE3: dict[str, PublishedTable] = {
    "F1": _table3("F1 sphere (30-D)", 9.38e-9, 5.89e-14),
    "F2": _table3("F2 Schwefel 2.22 (30-D)", 6.76e-6, 5.16e-9),
    "F3": _table3("F3 Rastrigin (30-D)", 14.75, 1.30),
    "F4": _table3("F4 Hartmann-3 (3-D)", -3.8609, -3.8628, resolution=5e-5),
}
"""[MGWO], Table 3: mean best value over 50 runs (30 wolves, 200 iterations), per function.
F4 is printed to four decimals, hence its resolution."""

P003_TABLE4 = PublishedTable(
    "MGWO",
    "Table 4",
    "loading manipulator, target FK(x*); 30 wolves, 200 iterations, 50 runs",
    (
        PublishedRow("GWO", "gwo", {"mean": 0.4292, "best": 0.0115, "worst": 1.0613}),
        PublishedRow("VAGWO", None, {"mean": 1.0043, "best": 8.04e-5, "worst": 6.2053}),
        PublishedRow("PGWO", None, {"mean": 0.3986, "best": 0.0015, "worst": 2.5655}),
        PublishedRow(
            "MGWO", "mgwo", {"mean": 0.0122, "best": 0.0064, "worst": 0.0226, "var": 8.04e-5}
        ),
    ),
)
"""[MGWO], Table 4: mean / best / worst / variance of the fitness over 50 runs."""
