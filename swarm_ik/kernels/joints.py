"""Distances in joint space (compiled): continuous joints wrapped onto ``[−π, π)``.

The branch enumeration (:mod:`swarm_ik.many`) keeps answers that are farther apart than a
Euclidean tolerance; the path layers (:mod:`swarm_ik.path`) keep candidates that differ by a
share of the largest joint step.  Both are :func:`fresh_rows` with another norm.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from swarm_ik._types import FloatArray

TWO_PI = 2.0 * math.pi


@numba.njit(cache=True, inline="always")
def wrapped(e: float) -> float:  # pragma: no cover - compiled
    """``e`` wrapped onto ``[−π, π)`` [rad]."""
    return (e + math.pi) % TWO_PI - math.pi


@numba.njit(cache=True)
def in_box(
    q: FloatArray, lower: FloatArray, upper: FloatArray, tol: float
) -> bool:  # pragma: no cover - compiled
    """Whether ``lower[j] − tol <= q[j] <= upper[j] + tol`` for every joint ``j`` (a NaN is
    never inside): the bounds test of every answer judged, one compiled loop where numpy's
    six small operations cost several µs."""
    for j in range(q.shape[0]):
        if not (lower[j] - tol <= q[j] <= upper[j] + tol):
            return False
    return True


@numba.njit(cache=True)
def min_dist2(
    qs: FloatArray, kept: FloatArray, periodic: NDArray[np.bool_], out: FloatArray
) -> None:  # pragma: no cover - compiled
    """Squared wrapped distance of each row of ``qs`` ``(m, nq)`` to its nearest row of
    ``kept`` ``(k, nq)`` into ``out`` ``(m,)`` (``periodic``: the joints wrapped)."""
    for s in range(qs.shape[0]):
        best = np.inf
        for r in range(kept.shape[0]):
            d2 = 0.0
            for j in range(qs.shape[1]):
                e = qs[s, j] - kept[r, j]
                if periodic[j]:
                    e = wrapped(e)
                d2 += e * e
                if d2 >= best:
                    break
            if d2 < best:
                best = d2
        out[s] = best


@numba.njit(cache=True)
def fresh_rows(
    rows: FloatArray,
    kept: FloatArray,
    periodic: NDArray[np.bool_],
    scale: FloatArray,
    tol: float,
    largest: bool,
    out: NDArray[np.int64],
) -> int:  # pragma: no cover - compiled
    """The rows of ``rows`` ``(m, nq)`` at least ``tol`` from every row of ``kept``
    ``(k, nq)`` and from every row taken before them (greedy, in order): their indices into
    ``out`` ``(m,)``; returns how many.  Arguments in the order of :func:`min_dist2`.

    The distance of two rows is that of ``Δq_j / scale_j`` (``periodic`` joints' ``Δq``
    wrapped): its largest component when ``largest`` (``|Δq_j| >= tol·scale_j`` for some
    ``j`` is far enough), else its Euclidean norm (``Σ (Δq_j/scale_j)² >= tol²``)."""
    c = 0
    n = rows.shape[1]
    tol2 = tol * tol
    for s in range(rows.shape[0]):
        fresh = True
        for r in range(kept.shape[0] + c):
            far = False
            d2 = 0.0
            for j in range(n):
                other = kept[r, j] if r < kept.shape[0] else rows[out[r - kept.shape[0]], j]
                d = rows[s, j] - other
                if periodic[j]:
                    d = wrapped(d)
                if largest:
                    if abs(d) >= tol * scale[j]:
                        far = True
                        break
                else:
                    e = d / scale[j]
                    d2 += e * e
            if not largest:
                far = d2 >= tol2
            if not far:
                fresh = False
                break
        if fresh:
            out[c] = s
            c += 1
    return c
