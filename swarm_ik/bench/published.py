"""The source papers' published numbers, as data, keyed by our solver names.

Transcribed from the papers (full citations in ``docs/references.md``).

Nothing here is computed: these are the values printed in the papers, set beside our own
numbers by :mod:`swarm_ik.bench.report`.  Each :class:`PublishedRow` names the algorithm as the
paper prints it and, when we implement it, the registry name of our solver.

* [HLFOA], on the ABB YuMi IRB 14000 left arm: Table 2 (the given pose, 10 runs, population
  100, 1000 iterations) and Table 4 (10 arbitrary reachable poses); both print best / mean /
  worst / standard deviation for every algorithm.
  Fitness: eq. 3, ``λ·(|Δpx|+|Δpy|+|Δpz|) + Σ|ΔR_ij|``, millimetres with ``λ = 1e-2`` (the
  same values as metres with ``λ = 10``, our ``"paper-l1"``).
* [MGWO], on a mobile loading manipulator: Table 3 (benchmark functions F1–F4, 30 wolves,
  200 iterations, 50 runs) and Table 4 (IK of the target FK(x*), 50 runs); both print mean /
  best / worst / **variance**.  Fitness: eq. 15, ZYZ Euler angles, ``μ = 1`` (our
  ``"euler-zyz"``).

A statistic missing from a row's ``stats`` is one the paper does not print (the report shows
"—" for it); printed values that look like typesetting slips are kept as printed and flagged
where they are defined.
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


def _hlfoa_rows(printed: str) -> tuple[PublishedRow, ...]:
    """[HLFOA]'s rows from a table as printed: per line the algorithm, our solver's name
    (``-``: not implemented here) and best / mean / worst / std."""
    rows = []
    for line in printed.strip().splitlines():
        name, solver, *values = line.split()
        stats = dict(zip(("best", "mean", "worst", "std"), map(float, values), strict=True))
        rows.append(PublishedRow(name, None if solver == "-" else solver, stats))
    return tuple(rows)


P000_TABLE2 = PublishedTable(
    "HLFOA",
    "Table 2",
    "YuMi left arm, the given pose; population 100, 1000 iterations, 10 runs",
    _hlfoa_rows(
        """
        FOA          foa    5.21425      5.27143      5.35291      4.57435e-2
        LGMS-FOA     -      0.207373     0.540788     1.20566      0.265285
        AE-LGMS-FOA  -      3.42399e-2   0.349514     0.783828     0.215070
        IFOA         -      5.42641      5.51490      5.58521      5.84845e-2
        SFOA         -      6.14915      6.93508      7.77175      0.582956
        HLFOA        hlfoa  2.22045e-16  4.03677e-16  5.07372e-16  8.02196e-17
        """
    ),
)
"""[HLFOA], Table 2: best / mean / worst / std of the fitness over 10 runs, as the paper prints
them (six significant digits)."""

P000_TABLE4 = PublishedTable(
    "HLFOA",
    "Table 4",
    "YuMi left arm, 10 arbitrary reachable poses",
    _hlfoa_rows(
        """
        FOA          foa    3.12702      7.10705      9.80547      2.20799
        LGMS-FOA     -      7.21645e-16  6.83956e-1   2.01518      6.23121e-1
        AE-LGMS-FOA  -      2.64782e-12  2.95665e-1   8.66390e-1   3.03890e-1
        IFOA         -      4.05356      6.81130      1.07144e1    1.74148
        SFOA         -      3.10603      8.82899      1.40072e1    3.03113
        HLFOA        hlfoa  1.73472e-16  3.87891e-16  6.79526e-16  1.59873e-16
        """
    ),
)
"""[HLFOA], Table 4: best / mean / worst / std of the fitness over the 10 poses, every value as
printed (six significant digits)."""

# --------------------------------------------------------------------------- [MGWO]
P003_X_STAR = (np.pi / 4, np.pi / 6, np.pi / 4, 0.8, 1.0, 1.0, np.pi / 6, -np.pi / 4)
"""[MGWO]'s target joint vector ``x*`` (rad, rad, rad, m, m, m, rad, rad); it violates the
paper's own limits (θ3 = 45° > 35.45°, d4..d6 > 0.5 m)."""

HARTMANN3_MIN = -3.86278214782076
"""Global minimum of Hartmann-3 (F4) to full precision (Dixon & Szegő's test set)."""


def _printed(mean: float, best: float, worst: float, var: float) -> dict[str, float]:
    """One row of [MGWO] Table 3 or 4 in the paper's column order (平均值 mean, 最优值 best,
    最差值 worst, 方差 variance)."""
    return {"mean": mean, "best": best, "worst": worst, "var": var}


def _table3(
    caption: str, gwo: dict[str, float], mgwo: dict[str, float], resolution: float = 0.0
) -> PublishedTable:
    """One function's part of [MGWO] Table 3 (GWO's row, then MGWO's)."""
    rows = (PublishedRow("GWO", "gwo", gwo), PublishedRow("MGWO", "mgwo", mgwo))
    return PublishedTable("MGWO", "Table 3", caption, rows, resolution)


# [MGWO] Table 3 ("测试函数求解指标统计", test function solving index statistics): every value
# exactly as printed (five significant digits; mean, best, worst, variance).  F4's worst is
# printed as 0 for both algorithms, which the printed means rule out (see
# F4_WORST_AS_PRINTED); kept as printed.
P003_TABLE3: dict[str, PublishedTable] = {
    "F1": _table3(
        "F1 sphere (30-D)",
        _printed(9.3846e-9, 6.8859e-10, 4.3676e-8, 8.7286e-17),
        _printed(5.8941e-14, 1.0988e-14, 1.7557e-13, 1.3045e-27),
    ),
    "F2": _table3(
        "F2 Schwefel 2.22 (30-D)",
        _printed(6.7552e-6, 2.3777e-6, 1.8616e-5, 1.0811e-11),
        _printed(5.1626e-9, 2.0102e-9, 7.9555e-9, 1.8047e-18),
    ),
    "F3": _table3(
        "F3 Rastrigin (30-D)",
        _printed(14.7479, 7.7676e-6, 33.4622, 60.4462),
        _printed(1.3046, 1.6900e-10, 6.2076, 2.7221),
    ),
    "F4": _table3(
        "F4 Hartmann-3 (3-D)",
        _printed(-3.8609, -3.8628, 0.0, 7.1972e-6),
        _printed(-3.8628, -3.8628, 0.0, 3.5927e-11),
        resolution=5e-5,
    ),
}
"""[MGWO], Table 3: mean / best / worst / variance of the best value over 50 runs (30 wolves,
200 iterations), per function, as printed.  F4's mean and best are printed to four decimals,
hence its resolution."""

F4_WORST_AS_PRINTED = 0.0
"""[MGWO] Table 3 prints 0 as F4's worst value for GWO and MGWO.  No run can go below
:data:`HARTMANN3_MIN`, so a run at 0 among 50 would put the mean at or above
``49/50 · HARTMANN3_MIN ≈ -3.7855``, above both printed means (-3.8609, -3.8628): the 0 is not
the worst of the runs those means average.  The report shows it as printed, with this note."""

P003_TABLE4 = PublishedTable(
    "MGWO",
    "Table 4",
    "loading manipulator, target FK(x*); 30 wolves, 200 iterations, 50 runs",
    (
        PublishedRow("GWO", "gwo", _printed(0.4292, 0.0115, 1.0613, 1.0613)),
        PublishedRow("VAGWO", None, _printed(1.0043, 8.0362e-5, 6.2053, 6.2053)),
        PublishedRow("PGWO", None, _printed(0.3986, 0.0015, 2.5655, 2.5655)),
        PublishedRow("MGWO", "mgwo", _printed(0.0122, 0.0064, 0.0226, 8.0362e-5)),
    ),
)
"""[MGWO], Table 4 ("各算法求解指标统计"): mean / best / worst / variance of the fitness over 50
runs, every value as printed.  The variance column repeats the worst value for GWO, VAGWO and
PGWO, and VAGWO's best has the digits of MGWO's variance (8.0362e-5): apparently typesetting
slips, kept as printed (:data:`P003_TABLE4_REPEATED_VAR` names the rows; the report says so)."""

P003_TABLE4_REPEATED_VAR = tuple(
    r.algorithm for r in P003_TABLE4.rows if r.stats["var"] == r.stats["worst"]
)
"""Rows of [MGWO] Table 4 whose printed variance equals their printed worst value."""
