"""Batched benchmark functions of the GWO/MGWO papers, with their domains and known minima.

The four functions of [MGWO], Table 2, with the dimensions of the GWO paper [GWO], which
[MGWO] follows:

========  ===================  =====  =================  ==========================
key       function             dim    domain (each x_j)   minimum
========  ===================  =====  =================  ==========================
``F1``    sphere               30     [-100, 100]        0 at 0
``F2``    Schwefel 2.22        30     [-10, 10]          0 at 0
``F3``    Rastrigin            30     [-5.12, 5.12]      0 at 0
``F4``    Hartmann-3           3      [0, 1]             -3.86278 at (0.114614,
                                                         0.555649, 0.852547)
========  ===================  =====  =================  ==========================

[MGWO] prints the Hartmann-3 domain as ``[1, 3]``; the function is defined on ``[0, 1]³``
(its minimum lies there), which is what is used here.  Every function is batched:
``(pop, n) -> (pop,)``.

>>> import numpy as np
>>> f = FUNCTIONS["F4"]
>>> float(f(np.array([f.x_min]))[0]) < -3.8627
True
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from swarm_ik._types import FloatArray
from swarm_ik.errors import InvalidArgumentError, unknown


def _rows(x: FloatArray) -> FloatArray:
    return np.atleast_2d(np.asarray(x, dtype=float))


def sphere(x: FloatArray) -> FloatArray:
    """F1, sphere: ``Σ x_j²``; ``(pop, n) -> (pop,)``."""
    x = _rows(x)
    return np.sum(x * x, axis=1)


def schwefel_2_22(x: FloatArray) -> FloatArray:
    """F2, Schwefel 2.22: ``Σ|x_j| + Π|x_j|``; ``(pop, n) -> (pop,)``."""
    ax = np.abs(_rows(x))
    return np.sum(ax, axis=1) + np.prod(ax, axis=1)


def rastrigin(x: FloatArray) -> FloatArray:
    """F3, Rastrigin: ``Σ [x_j² − 10·cos(2π x_j) + 10]``; ``(pop, n) -> (pop,)``."""
    x = _rows(x)
    return np.sum(x * x - 10.0 * np.cos(2.0 * np.pi * x) + 10.0, axis=1)


_H3_A = np.array([[3.0, 10.0, 30.0], [0.1, 10.0, 35.0], [3.0, 10.0, 30.0], [0.1, 10.0, 35.0]])
_H3_C = np.array([1.0, 1.2, 3.0, 3.2])
_H3_P = np.array(
    [
        [0.3689, 0.1170, 0.2673],
        [0.4699, 0.4387, 0.7470],
        [0.1091, 0.8732, 0.5547],
        [0.03815, 0.5743, 0.8828],
    ]
)


def hartmann3(x: FloatArray) -> FloatArray:
    """F4, Hartmann-3: ``−Σ_i c_i·exp(−Σ_j a_ij (x_j − p_ij)²)``; ``(pop, 3) -> (pop,)``.

    Raises:
        InvalidArgumentError: the points do not have 3 coordinates.
    """
    x = _rows(x)
    if x.shape[1] != 3:
        raise InvalidArgumentError(f"hartmann3 takes points of 3 coordinates, got {x.shape[1]}")
    d = x[:, None, :] - _H3_P[None, :, :]  # (pop, 4, 3)
    return -np.exp(-np.sum(_H3_A * d * d, axis=2)) @ _H3_C


@dataclass(frozen=True)
class TestFunction:
    """A benchmark function with its box domain and known minimum.

    Attributes:
        name: Human-readable name, e.g. ``"sphere"``.
        function: Batched function ``(pop, dim) -> (pop,)``.
        lower: Lower bound of every coordinate.
        upper: Upper bound of every coordinate.
        dim: Number of coordinates.
        f_min: Known global minimum value.
        x_min: A global minimiser, ``dim`` numbers.
    """

    __test__ = False  # not a pytest test class despite the name

    name: str
    function: Callable[[FloatArray], FloatArray]
    lower: float
    upper: float
    dim: int
    f_min: float
    x_min: tuple[float, ...]

    def __call__(self, x: FloatArray) -> FloatArray:
        """Evaluate a batch ``(pop, dim) -> (pop,)``."""
        return self.function(x)

    @property
    def bounds(self) -> tuple[FloatArray, FloatArray]:
        """``(lower, upper)`` as arrays of shape ``(dim,)``."""
        return np.full(self.dim, self.lower), np.full(self.dim, self.upper)


FUNCTIONS: dict[str, TestFunction] = {
    "F1": TestFunction("sphere", sphere, -100.0, 100.0, 30, 0.0, (0.0,) * 30),
    "F2": TestFunction("Schwefel 2.22", schwefel_2_22, -10.0, 10.0, 30, 0.0, (0.0,) * 30),
    "F3": TestFunction("Rastrigin", rastrigin, -5.12, 5.12, 30, 0.0, (0.0,) * 30),
    "F4": TestFunction(
        "Hartmann-3", hartmann3, 0.0, 1.0, 3, -3.86278, (0.114614, 0.555649, 0.852547)
    ),
}
"""The benchmark functions of [MGWO], Table 2, keyed ``"F1"``..``"F4"``."""


def get_function(key: str) -> TestFunction:
    """The benchmark function registered under ``key``.

    Raises:
        UnknownNameError: no such key; the message lists ``F1``..``F4``.
    """
    try:
        return FUNCTIONS[key]
    except KeyError:
        raise unknown("test function", key, FUNCTIONS) from None
